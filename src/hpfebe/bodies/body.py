"""Bodies of the contact problems (Chapter 4, Section 4.2: block systems (4.27) FE/BE and
(4.33) BE/BE): one protocol for a finite element body (:class:`FEBody`, P1/Q1
:class:`hpfebe.fem.elasticity.ElasticBody`), a boundary element body (:class:`BEBody`,
:class:`hpfebe.bem.lame.LameBEM`) and a rigid obstacle (:class:`RigidObstacle`, no dofs),
so that the contact code (gap, projection, laws, Newton) is written once for every pair.

The protocol:

    kind, ndofs, K            "FE" / "BE" / "rigid", number of unknowns, stiffness (sparse;
                              a BE body's dense S_hat is stored as a fully populated sparse
                              block, so that the FE blocks of the global matrix stay sparse)
    internal_force(u)         (f_int(u), tangent): K u and K for a linear body; a plastic
                              body returns its return-map force and algorithmic tangent,
                              with its history updated per call ...
    commit(u)                 ... and committed when a load step converges
    internal_force_lazy(u)    optional: (f_int(u), a callable returning the tangent), for
                              a body whose tangent costs more than its force (plastic):
                              TwoBodyContact assembles it only for a Newton step
    segments(labels)          straight pieces of the contact boundary: end points a, b, end
                              vertex ids, outward unit normals, the body's facet/element ids
    trace(ids, s)             dofs -> displacement at a + s (b - a) of segments ``ids``:
                              columns (n, 2, k) and values (n, k)
    degree                    polynomial degree of the traces
    dofs_on / dofs_at / traction_load / dof_coordinates   boundary conditions and loads

FE body: traces on a facet are the two vertex hat functions (1 - s, s).  BE body: the
unknowns are the boundary displacement in V_hp^2 (GLL Lagrange basis of degree p_I,
interleaved components 2 * scalar dof + c, :mod:`hpfebe.spaces`), its stiffness the
discrete Steklov-Poincare operator S_hat (Section 1.4).  Rigid obstacle: a gap function
g(x) (admissible U_n <= g for the other body's outward normal n) and a prescribed
tangential motion w(x); it has no dofs.  Dirichlet dofs stay in the vector and are
eliminated by the solver (``fixed_dofs``).
"""

from __future__ import annotations

import dataclasses

from typing import Optional, Sequence

import numpy as np
import scipy.sparse as sp

from ..bem.lame import LameBEM
from ..checks import (InputTypeError, array, callable_returning, choice, instance,
                      real)
from ..fem.elasticity import ElasticBody
from ..fem.plastic_body import ElastoPlasticFE
from ..quadrature import gauss_legendre, gauss_lobatto
from ..spaces import lagrange_values


def _labels(labels) -> list:
    return [labels] if isinstance(labels, str) else list(labels)


class _LinearBody:
    """internal_force / commit of a linear body: K u and K, no history."""

    linear = True

    def internal_force(self, u):
        return self.K @ u, self.K

    def commit(self, u) -> None:
        pass


class FEBody(_LinearBody):
    """A P1/Q1 :class:`ElasticBody` (facets of its labelled boundary)."""

    kind = "FE"
    degree = 1

    def __init__(self, body: ElasticBody):
        self.body = body
        self.ndofs = body.ndofs
        self.K = body.K

    def segments(self, labels):
        b = self.body
        f = np.unique(np.concatenate([b.boundary_facets(lb) for lb in _labels(labels)]))
        va, vb = b.mesh.facets[0, f], b.mesh.facets[1, f]
        return dict(a=b.mesh.p[:, va].T, b=b.mesh.p[:, vb].T, va=va, vb=vb,
                    normals=b.outward_normals(f).T, ids=f)

    def trace(self, ids, s):
        m = self.body.mesh
        va, vb = m.facets[0, ids], m.facets[1, ids]
        nd = self.body.nodal_dofs
        cols = np.stack([np.stack([nd[c, va], nd[c, vb]], axis=1) for c in (0, 1)], axis=1)
        vals = np.column_stack([1.0 - s, s])
        return cols, vals

    def dofs_on(self, labels, component=None):
        return self.body.dofs_on(labels, component)

    def dofs_at(self, point, component=None):
        return self.body.dofs_at(point, component)

    def traction_load(self, label, traction):
        return self.body.traction_load(label, traction)

    def dof_coordinates(self):
        return self.body.dof_coordinates()


class BEBody(_LinearBody):
    """A :class:`LameBEM` body: unknowns = boundary displacement in V_hp^2,
    stiffness S_hat, contact boundary = the elements carrying the contact labels."""

    kind = "BE"

    def __init__(self, bem: LameBEM, S=None):
        self.body = lame_body(bem)          # a LaplaceBEM has scalar traces: refused
        self.mesh = bem.mesh
        self.space = bem.V_space
        self.ndofs = 2 * self.space.ndof
        self.degree = int(self.mesh.degrees.max())
        self._S = None if S is None else array("S", S, shape=(self.ndofs, self.ndofs))
        self._K = None

    @property
    def S(self) -> np.ndarray:
        """The dense S_hat (assembled on first use, as traces do not need it)."""
        if self._S is None:
            self._S = self.body.S_hat
        return self._S

    @property
    def K(self) -> sp.csr_matrix:
        if self._K is None:
            self._K = sp.csr_matrix(self.S)
        return self._K

    def internal_force(self, u):
        """S_hat u and the dense S_hat (dense blocks stay dense)."""
        return self.S @ u, self.S

    def _elements(self, labels) -> np.ndarray:
        labels = _labels(labels)
        known = set(np.unique(self.mesh.labels).tolist())
        for lb in labels:
            if lb not in known:
                raise ValueError(f"boundary label must be one of {sorted(known)}, got {lb!r}")
        return np.flatnonzero(self.mesh.where(*labels))

    def segments(self, labels):
        e = self._elements(labels)
        m = self.mesh
        return dict(a=m.a[e], b=m.b[e], va=m.elements[e, 0], vb=m.elements[e, 1],
                    normals=m.normals[e], ids=e)

    def trace(self, ids, s):
        ids = np.asarray(ids)
        s = np.asarray(s, dtype=float)
        k = self.degree + 1
        n = ids.size
        cols = np.zeros((n, 2, k), dtype=np.int64)
        vals = np.zeros((n, k))
        deg = self.mesh.degrees[ids]
        for p in np.unique(deg):
            sel = np.flatnonzero(deg == p)
            p = int(p)
            vals[sel, :p + 1] = lagrange_values(p, 2.0 * s[sel] - 1.0)
            d = self.space.elem_dofs[ids[sel], :p + 1]
            for c in (0, 1):
                cols[sel, c, :p + 1] = 2 * d + c
        return cols, vals

    def dofs_on(self, labels, component: Optional[int] = None):
        d = self.space.dofs_on(*_labels(self._check(labels)))
        return self._interleave(d, component)

    def _check(self, labels):
        self._elements(labels)
        return labels

    @staticmethod
    def _interleave(d, component):
        d = np.asarray(d, dtype=np.int64)
        if component is None:
            return np.sort(np.concatenate([2 * d, 2 * d + 1]))
        return 2 * d + choice("component", component, (0, 1))

    def dofs_at(self, point: Sequence[float], component: Optional[int] = None):
        p = array("point", point, shape=(2,)).reshape(1, 2)
        m = self.mesh
        dist = np.linalg.norm(m.a - p, axis=1)
        e = int(np.argmin(dist))
        if dist[e] > 1e-10 * m.diameter:
            raise ValueError(f"point must be a boundary mesh node, got {tuple(p.ravel())!r}")
        return self._interleave(np.array([self.space.elem_dofs[e, 0]]), component)

    def dof_coordinates(self):
        xy = np.empty((self.ndofs, 2))
        m = self.mesh
        for p in np.unique(m.degrees):
            p = int(p)
            els = np.flatnonzero(m.degrees == p)
            xg, _ = gauss_lobatto(p + 1)
            pts = m.points(els[:, None], xg[None, :])          # (ne, p+1, 2)
            d = self.space.elem_dofs[els, :p + 1]
            for c in (0, 1):
                xy[2 * d + c] = pts
        return xy

    def traction_load(self, label: str, traction):
        """int_{Gamma_label} t . v ds for v in V_hp^2 (Gauss-Legendre, p + 3 points);
        ``traction`` a constant (tx, ty) or a callable (x, y) -> (tx, ty)."""
        e_all = self._elements(label)
        if not callable(traction):
            tc = array("traction (a pair (tx, ty) or a callable)", traction, shape=(2,))
        m = self.mesh
        f = np.zeros(self.ndofs)
        for p in np.unique(m.degrees[e_all]):
            p = int(p)
            els = e_all[m.degrees[e_all] == p]
            tq, wq = gauss_legendre(p + 3)
            tq, wq = np.asarray(tq, float), np.asarray(wq, float)
            x = m.points(els[:, None], tq[None, :])             # (ne, nq, 2)
            if callable(traction):
                tx, ty = traction(x[..., 0], x[..., 1])
                tv = array("traction(x, y)", np.stack([np.broadcast_to(tx, x.shape[:2]),
                                                        np.broadcast_to(ty, x.shape[:2])],
                                                       axis=-1))
            else:
                tv = np.broadcast_to(tc, x.shape)
            phi = lagrange_values(p, tq)                         # (nq, p+1)
            w = wq[None, :] * (0.5 * m.lengths[els])[:, None]    # (ne, nq)
            loc = np.einsum("eq,qj,eqc->ejc", w, phi, tv)        # (ne, p+1, 2)
            d = self.space.elem_dofs[els, :p + 1]
            for c in (0, 1):
                np.add.at(f, 2 * d + c, loc[..., c])
        return f


class RigidObstacle:
    """A rigid obstacle: gap g(x) on the other body's contact boundary (admissible
    U_n <= g, g < 0 an initial overlap) and its tangential motion w(x) along the contact
    tangent; each a float or a callable of the points (n, 2).  No dofs."""

    kind = "rigid"
    linear = True
    ndofs = 0
    degree = 0

    def __init__(self, gap, motion=None):
        self.gap, self.motion = gap, motion
        self.K = sp.csr_matrix((0, 0))

    def internal_force(self, u):
        return np.zeros(0), np.zeros((0, 0))

    def commit(self, u) -> None:
        pass

    def dof_coordinates(self):
        return np.zeros((0, 2))


class PlasticFEBody(FEBody):
    """An :class:`ElastoPlasticFE` as a contact body (kind "FE", the FEBody geometry of its
    mesh); ``K`` is the elastic stiffness of the formulation, internal_force / commit the
    plastic ones.

    ``offset``: a displacement u_0 already carried by the body (e.g. the residual
    displacement after an earlier touch).  The body's unknown is then v = u - u_0: its
    geometry (segments, normals, coordinates, hence the contact gap) is the deformed
    configuration x + u_0, and internal_force(v) = f_int(u_0 + v) of the small-strain
    body with its committed history."""

    linear = False

    def __init__(self, fe: ElastoPlasticFE, offset=None):
        instance("fe", fe, ElastoPlasticFE)
        if offset is None:
            self.offset = np.zeros(fe.ndofs)
            geometry = fe.elastic
        else:
            self.offset = array("offset", offset, shape=(fe.ndofs,), copy=True)
            moved = dataclasses.replace(fe.mesh, doflocs=fe.mesh.p
                                        + fe.elastic.nodal_displacement(self.offset))
            m = fe.material
            geometry = ElasticBody(moved, m.E, m.nu, "strain")
        super().__init__(geometry)
        self.plastic = fe
        self.K = fe.K

    def internal_force(self, u):
        return self.plastic.internal_force(self.offset + u)

    def internal_force_lazy(self, u):
        """(f_int, a callable returning the tangent): the tangent only when asked for
        (:meth:`ElastoPlasticFE.internal_force_lazy`)."""
        return self.plastic.internal_force_lazy(self.offset + u)

    def commit(self, u) -> None:
        self.plastic.commit(self.offset + u)


def pointwise(name: str, value, pts: np.ndarray, allow_negative: bool = True) -> np.ndarray:
    """A float or callable x -> values (None = 0), evaluated at the points (n, 2): a
    callable must return one finite value per point (a scalar is refused: a constant is
    given as a float, and ``lambda x: norm(x) - 1`` is no gap of n points)."""
    if value is None:
        return np.zeros(len(pts))
    if callable(value):
        v = callable_returning(name, value, pts, (len(pts),))(pts)
    else:
        v = np.full(len(pts), real(f"{name} (a float or a callable of the points)", value))
    if not allow_negative and np.any(v < 0):
        raise ValueError(f"{name} must be >= 0 on Gamma_C, got min {v.min()!r}")
    return v


def lame_body(bem, name: str = "bem"):
    """``bem`` checked to be a :class:`LameBEM` (a Laplace operator has scalar traces)."""
    return instance(name, bem, LameBEM, "a LameBEM (2D elasticity)")


def against_obstacle(bem, S, contact_label: str, dirichlet_label: str, load):
    """The one-body problems of Sections 3.2-3.3: (BEBody, its Dirichlet dofs or None,
    the load vector or None), checked."""
    lame_body(bem)
    if not np.any(bem.mesh.where(contact_label)):
        raise ValueError(f"contact_label {contact_label!r}: no element carries this label")
    body = BEBody(bem, S)
    fixed = body.dofs_on(dirichlet_label) if np.any(bem.mesh.where(dirichlet_label)) \
        else None
    f = None
    if load is not None:
        f = array("load", load, shape=(body.ndofs,))
    return body, fixed, f


def as_body(body, name: str = "body"):
    """The contact body of an :class:`ElasticBody` (FE), an :class:`ElastoPlasticFE`
    (plastic FE), a :class:`LameBEM` (BE), or a body object already (FEBody, BEBody,
    PlasticFEBody, RigidObstacle or any object with ``kind`` and ``internal_force``)."""
    if hasattr(body, "kind") and hasattr(body, "internal_force"):
        return body
    if isinstance(body, ElastoPlasticFE):
        return PlasticFEBody(body)
    if isinstance(body, ElasticBody):
        return FEBody(body)
    if isinstance(body, LameBEM):
        return BEBody(body)
    raise InputTypeError(f"{name} must be an ElasticBody, an ElastoPlasticFE, a LameBEM or "
                         f"a contact body, got an object of type {type(body).__name__}")
