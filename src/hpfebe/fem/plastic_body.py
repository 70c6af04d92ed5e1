"""An elastoplastic FE body (J2 flow theory, :mod:`hpfebe.constitutive.j2`) for Chapter 4's
work piece (Sections 4.2.2-4.2.3, 4.2.6): P1 triangles or Q1 quadrilaterals (scikit-fem),
history (eps_p, alpha, beta) at the quadrature points, internal force and algorithmic
tangent assembled by numba kernels over the elements (one pass: strain, radial return,
stress and element force; one pass: tangent element matrices written straight into the
fixed CSR pattern of the stiffness K), without (nel, nq, 9, 9) temporaries.

The element matrices need no 9 x 9 tangent: with B_i the (symmetric) strain of local
basis function i at a point, tr_i = tr B_i, G_ij = dev B_i : dev B_j and m_i = n : B_i,

    B_i : C_alg : B_j = kappa tr_i tr_j + 2 mu theta_1 G_ij - 2 mu theta_bar m_i m_j

(the tangent of :mod:`hpfebe.constitutive.j2`; theta_1 = 1, theta_bar = 0 at an elastic
point, the elastic element matrix).

    f_int(u)_i = sum_K sum_q w_q B_i(x_q) : sigma(eps(u)(x_q); committed history)
    T(u)_ij    = sum_K sum_q w_q B_i(x_q) : C_alg(x_q) : B_j(x_q)                   (4.36)-(4.37)

``formulation``:

* ``"bbar"`` (default, locking free for Q1): the mean-dilatation B-bar strain (Hughes 1980,
  Simo-Hughes Section 4.4) eps_bar = eps - 1/3 (div u) 1 + 1/3 <div u>_K 1, <.>_K the
  element mean.  Plastic flow is isochoric, and fully integrated Q1 locks under it (too
  stiff); B-bar does not.  In plane strain eps_bar_33 = 1/3 (<div u>_K - div u) is in
  general not zero; it is carried with the full 3 x 3 tensors.  On P1 triangles (constant
  strain) B-bar is the standard strain (P1 still locks in the plastic limit; use Q1).
* ``"full"``: the standard strain, fully integrated (2 x 2 Gauss on Q1, 1 point on P1);
  for the comparison curves.

The body protocol of the contact problems (:mod:`hpfebe.bodies.body`):
``internal_force(u) -> (f_int, tangent)`` is a pure function of u and the *committed*
history (trial return map), ``commit(u)`` makes the state at u the committed history (call
it only after a load step converged); a failed, cut load step therefore restarts from the
committed state automatically.  :class:`~hpfebe.bodies.PlasticFEBody` wraps the body as a contact
:class:`~hpfebe.bodies.body.FEBody` (kind "FE", segments, traces, dofs ...).

:class:`DisplacementSteps` is the :class:`hpfebe.solvers.LoadStep` of a body alone under
prescribed displacements and loads (no contact), for :func:`hpfebe.solvers.load_path`.
"""

from __future__ import annotations

from dataclasses import replace

import numba
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import Basis, ElementQuad1, ElementTriP1, ElementVector, MeshQuad, MeshTri

from ..checks import array, boolean, choice, finite, instance
from ..solvers import Iterate, SingularStep
from .elasticity import ElasticBody
from .meshes import FEDomain
from ..constitutive.j2 import (J2Material, J2State, ReturnMap, dev, radial_return_point,
                               tangent_factors, tensor_norm, TANGENTS)

FORMULATIONS = ("bbar", "full")
#: the tangents of the body: the J2 ones (:data:`~hpfebe.constitutive.j2.TANGENTS`) and
#: "secant" (:meth:`ElastoPlasticFE.tangent_matrix`)
BODY_TANGENTS = TANGENTS + ("secant",)


# The two per-iterate contractions of the body, as loops in the summation order of
# np.einsum("eqia,ei->eqa") and np.einsum("eqia,eqa,eq->ei") (the same numbers bit for
# bit, measured; the stamping results depend on the round-off of every Newton step),
# 3-4x faster than einsum.
@numba.njit(cache=True)
def _strain_kernel(B, ue):
    """eps[e, q, a] = sum_i B[e, q, i, a] ue[e, i]."""
    ne, nq, nl, na = B.shape
    out = np.empty((ne, nq, na))
    for e in range(ne):
        for q in range(nq):
            for a in range(na):
                acc = 0.0
                for i in range(nl):
                    acc += B[e, q, i, a] * ue[e, i]
                out[e, q, a] = acc
    return out


@numba.njit(cache=True)
def _force_kernel(B, s, dx):
    """f[e, i] = sum_q sum_a B[e, q, i, a] s[e, q, a] dx[e, q]."""
    ne, nq, nl, na = B.shape
    out = np.empty((ne, nl))
    for e in range(ne):
        for i in range(nl):
            tot = 0.0
            for q in range(nq):
                acc = 0.0
                for a in range(na):
                    acc += B[e, q, i, a] * s[e, q, a] * dx[e, q]
                tot += acc
            out[e, i] = tot
    return out


@numba.njit(cache=True)
def _state_kernel(Bc, comps, ue, dx, ep, alpha, beta, mu, kappa, H, theta, sigma_Y):
    """Strain eps = B ue, the radial return from the committed (ep, alpha, beta) (all
    (nel * nq, ...)), the stress and the element forces fe[e, i] = sum_q sum_a
    B[e, q, i, a] sigma[e, q, a] dx[e, q] in one pass over the elements.  ``Bc`` holds
    the components ``comps`` of B (the others vanish: :attr:`ElastoPlasticFE._comps`),
    so the sums skip exact zeros only: the numbers of the full 9-component sums."""
    ne, nq, nl, nc = Bc.shape
    n = ne * nq
    sigma, ep_new, beta_new = np.empty((n, 9)), np.empty((n, 9)), np.empty((n, 9))
    normal = np.empty((n, 9))
    alpha_new, dgamma, f_trial, safe = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    fe = np.zeros((ne, nl))
    eps = np.zeros(9)
    for e in range(ne):
        for q in range(nq):
            p = e * nq + q
            for c in range(nc):
                acc = 0.0
                for i in range(nl):
                    acc += Bc[e, q, i, c] * ue[e, i]
                eps[comps[c]] = acc
            alpha_new[p], dgamma[p], f_trial[p], safe[p] = radial_return_point(
                eps, ep[p], alpha[p], beta[p], mu, kappa, H, theta, sigma_Y,
                sigma[p], ep_new[p], beta_new[p], normal[p])
            w = dx[e, q]
            for i in range(nl):
                acc = 0.0
                for c in range(nc):
                    acc += Bc[e, q, i, c] * sigma[p, comps[c]] * w
                fe[e, i] += acc
    return sigma, ep_new, alpha_new, beta_new, normal, dgamma, f_trial, safe, fe


@numba.njit(cache=True)
def _elastic_kernel(TR, G, dx, kappa, mu):
    """Elastic element matrices sum_q dx (kappa tr_i tr_j + 2 mu G_ij) (nel, nl, nl)."""
    ne, nq, nl = TR.shape
    Ke = np.zeros((ne, nl, nl))
    for e in range(ne):
        for q in range(nq):
            for i in range(nl):
                for j in range(nl):
                    Ke[e, i, j] += dx[e, q] * (kappa * TR[e, q, i] * TR[e, q, j]
                                               + 2.0 * mu * G[e, q, i, j])
    return Ke


@numba.njit(cache=True)
def _tangent_kernel(Bc, comps, TR, G, dx, Ke_el, pos, nnz, normal, dgamma, safe, plastic,
                    kappa, mu, H, algorithmic, secant):
    """The CSR data (nnz,) of the tangent on the pattern of K (``pos[e, i, j]``: the
    position of element entry (i, j) in it): the element matrix (module doc) of every
    element with a plastic point, the elastic one ``Ke_el`` elsewhere (``Bc``, ``comps``:
    the nonzero components of B, as in :func:`_state_kernel`).  ``secant``: without the
    n x n term (theta_bar = 0), the secant stiffness of :meth:`ElastoPlasticFE.tangent_matrix`."""
    ne, nq, nl, nc = Bc.shape
    data = np.zeros(nnz)
    Ke = np.empty((nl, nl))
    m = np.empty(nl)
    for e in range(ne):
        any_plastic = False
        for q in range(nq):
            any_plastic = any_plastic or plastic[e * nq + q]
        if not any_plastic:
            for i in range(nl):
                for j in range(nl):
                    data[pos[e, i, j]] += Ke_el[e, i, j]
            continue
        Ke[:, :] = 0.0
        for q in range(nq):
            p = e * nq + q
            t1, tb = tangent_factors(dgamma[p], safe[p], plastic[p], mu, H, algorithmic)
            if secant:
                tb = 0.0
            for i in range(nl):
                acc = 0.0
                for c in range(nc):
                    acc += normal[p, comps[c]] * Bc[e, q, i, c]
                m[i] = acc
            for i in range(nl):
                for j in range(nl):
                    Ke[i, j] += dx[e, q] * (kappa * TR[e, q, i] * TR[e, q, j]
                                            + 2.0 * mu * t1 * G[e, q, i, j]
                                            - 2.0 * mu * tb * m[i] * m[j])
        for i in range(nl):
            for j in range(nl):
                data[pos[e, i, j]] += Ke[i, j]
    return data


class ElastoPlasticFE:
    """J2 elastoplastic P1/Q1 body.  ``mesh`` (labelled skfem MeshTri/MeshQuad or
    FEDomain), ``material`` (:class:`J2Material`), ``formulation`` ("bbar" or "full"),
    ``tangent`` ("algorithmic", "continuum" or "secant", the tangent returned by
    internal_force; :meth:`tangent_matrix`)."""

    def __init__(self, mesh, material: J2Material, formulation: str = "bbar",
                 tangent: str = "algorithmic"):
        if isinstance(mesh, FEDomain):
            mesh = mesh.mesh
        instance("material", material, J2Material)
        choice("formulation", formulation, FORMULATIONS)
        choice("tangent", tangent, BODY_TANGENTS)
        if isinstance(mesh, MeshQuad):
            elem, order = ElementQuad1(), 2
        elif isinstance(mesh, MeshTri):
            elem, order = ElementTriP1(), 1
        else:
            raise ValueError(f"mesh must be a skfem MeshTri or MeshQuad, got {type(mesh).__name__}")
        self.material, self.formulation, self.tangent = material, formulation, tangent
        self.elastic = ElasticBody(mesh, material.E, material.nu, "strain")
        self.mesh = mesh
        self.basis = Basis(mesh, ElementVector(elem), intorder=order)
        self.dx = self.basis.dx                                   # (nel, nq)
        self.nel, self.nq = self.dx.shape
        self.B = np.ascontiguousarray(self._strain_operator())    # (nel, nq, nloc, 9)
        # the components of the strain that B can make nonzero (plane strain: xx, xy,
        # yx, yy and, with B-bar, zz): the kernels sum over these only (the other
        # terms are exact zeros), on a compact copy of B (5/9 of the memory traffic)
        self._comps = np.flatnonzero(np.any(self.B != 0.0, axis=(0, 1, 2))).astype(np.int64)
        self._Bc = np.ascontiguousarray(self.B[..., self._comps])
        self._dx_c = np.ascontiguousarray(self.dx, dtype=float)
        dofs = self.basis.element_dofs                            # (nloc, nel)
        self.element_dofs = dofs
        nloc = dofs.shape[0]
        self._rows = np.repeat(dofs.T, nloc, axis=1).ravel()
        self._cols = np.tile(dofs.T, (1, nloc)).ravel()
        self.committed = J2State.zeros(self.nel * self.nq)
        self.sigma = np.zeros((self.nel * self.nq, 3, 3))          # committed stress
        # the geometry of the element matrices (module doc): tr B_i, dev B_i : dev B_j
        B3 = self.B.reshape(self.B.shape[:3] + (3, 3))
        self._TR = np.ascontiguousarray(np.trace(B3, axis1=-2, axis2=-1))
        devB = dev(B3).reshape(self.B.shape)
        self._G = np.ascontiguousarray(np.einsum("eqia,eqja->eqij", devB, devB))
        # element matrices of the elastic tangent: the tangent of an element whose
        # points are all elastic (the numbers of :func:`_tangent_kernel` there)
        self._Ke_el = _elastic_kernel(self._TR, self._G, self._dx_c, material.kappa,
                                      material.mu)
        self.K = self._coo(self._Ke_el)
        # position of element entry (e, i, j) in K.data: the tangent's fixed pattern
        lookup = sp.csr_matrix((np.arange(1, self.K.nnz + 1, dtype=float),
                                self.K.indices, self.K.indptr), shape=self.K.shape)
        self._pos = (np.asarray(lookup[self._rows, self._cols]).ravel().astype(np.int64)
                     - 1).reshape(self.nel, nloc, nloc)
        self._cache = None

    # ------------------------------------------------------------------ kinematics
    @property
    def ndofs(self) -> int:
        return self.basis.N

    @property
    def n_points(self) -> int:
        return self.nel * self.nq

    def dofs_on(self, labels, component: int | None = None) -> np.ndarray:
        """Dofs of the vertices on the boundary part(s) ``labels`` (a label or a list of
        the mesh's ``boundaries``); ``component`` 0 / 1 for one component, None for both.
        The numbering of :class:`~hpfebe.fem.elasticity.ElasticBody` on the same mesh
        (the same vector P1/Q1 basis)."""
        return self.elastic.dofs_on(labels, component)

    def dof_coordinates(self) -> np.ndarray:
        """(ndofs, 2) coordinates of the vertex of every dof."""
        return self.elastic.dof_coordinates()

    def _strain_operator(self) -> np.ndarray:
        """(nel, nq, nloc, 3, 3) -> reshaped (nel, nq, nloc, 9): the (B-bar) strain of each
        local basis function at each quadrature point, plane strain embedded in 3 x 3."""
        grads = np.stack([phi[0].grad for phi in self.basis.basis])   # (nloc, 2, 2, nel, nq)
        g = np.moveaxis(grads, (3, 4), (0, 1))                      # (nel, nq, nloc, 2, 2)
        B = np.zeros(g.shape[:3] + (3, 3))
        B[..., :2, :2] = 0.5 * (g + np.swapaxes(g, -1, -2))
        if self.formulation == "bbar":
            div = g[..., 0, 0] + g[..., 1, 1]                        # (nel, nq, nloc)
            mean = np.einsum("eqi,eq->ei", div, self.dx) / self.dx.sum(axis=1)[:, None]
            B += ((mean[:, None, :] - div) / 3.0)[..., None, None] * np.eye(3)
        return B.reshape(B.shape[:3] + (9,))

    def strain(self, u: np.ndarray) -> np.ndarray:
        """(nel * nq, 3, 3) (B-bar) strain of the dof vector u at the quadrature points."""
        u = array("u", u, shape=(self.ndofs,), finite=False)   # NaN: the solver's to judge
        ue = np.ascontiguousarray(u[self.element_dofs].T)           # (nel, nloc)
        eps = _strain_kernel(self.B, ue)
        return eps.reshape(-1, 3, 3)

    def _assemble(self, C: np.ndarray) -> sp.csr_matrix:
        """sum_K sum_q w_q B^T C B with C (nel, nq, 9, 9)."""
        return self._coo(self._element_matrices(C))

    def _element_matrices(self, C: np.ndarray, elements=None) -> np.ndarray:
        """Element matrices sum_q w_q B^T C B (n, nloc, nloc) of the ``elements`` (None =
        all) with C (n, nq, 9, 9) on their points; elementwise, so a subset gives the
        numbers of the full set."""
        B, dx = (self.B, self.dx) if elements is None else (self.B[elements],
                                                             self.dx[elements])
        CB = C @ np.swapaxes(B, -1, -2)                             # (n, nq, 9, nloc)
        BCB = B @ CB                                                # (n, nq, nloc, nloc)
        return np.einsum("eqij,eq->eij", BCB, dx)

    def _coo(self, Ke: np.ndarray) -> sp.csr_matrix:
        A = sp.coo_matrix((Ke.ravel(), (self._rows, self._cols)), shape=(self.ndofs,) * 2)
        return A.tocsr()

    def tangent_matrix(self, rm, tangent: str | None = None) -> sp.csr_matrix:
        """The tangent (4.36)-(4.37) of the return map ``rm`` (:meth:`state_at`):
        element matrices (module doc) of the elements with a plastic point, the elastic
        ones elsewhere, written by :func:`_tangent_kernel` into the pattern of K (the
        full assembly of :func:`~hpfebe.constitutive.j2.consistent_tangent` to round-off;
        the elastic stiffness K itself if no point is plastic).  The pattern is fixed:
        the Newton solver of the contact problems analyses it once
        (:mod:`hpfebe.contact.newton_matrix`).  ``tangent`` "secant": the algorithmic
        tangent without its n x n term, kappa 1 x 1 + 2 mu theta_1 P_dev with theta_1 =
        1 - 2 mu dgamma / ||eta_trial|| (the stress over the trial stress): the secant
        stiffness sigma = C_sec eps of a point loaded from a virgin state, stiffer than
        the algorithmic tangent along n.  Newton's first step from an elastic predictor
        (every point far past yield, the algorithmic tangent along n about H / (3 mu)
        soft) takes it (:class:`hpfebe.contact.settings.ContactSettings`
        ``secant_start``)."""
        tg = choice("tangent", self.tangent if tangent is None else tangent, BODY_TANGENTS)
        if not rm.plastic.any():
            return self.K
        m = self.material
        data = _tangent_kernel(self._Bc, self._comps, self._TR, self._G, self._dx_c,
                               self._Ke_el, self._pos, self.K.nnz,
                               np.ascontiguousarray(rm.normal.reshape(-1, 9)), rm.dgamma,
                               rm.eta_norm, rm.plastic, m.kappa, m.mu, m.H,
                               tg != "continuum", tg == "secant")
        # the pattern of K (its index arrays shared): a fixed pattern for the solver
        return sp.csr_matrix((data, self.K.indices, self.K.indptr), shape=self.K.shape)

    def _force(self, sigma: np.ndarray) -> np.ndarray:
        s = np.ascontiguousarray(sigma.reshape(self.nel, self.nq, 9))
        fe = _force_kernel(self.B, s, self._dx_c)
        return np.bincount(self.element_dofs.T.ravel(), fe.ravel(), minlength=self.ndofs)

    # ------------------------------------------------------------------ protocol
    def state_at(self, u: np.ndarray):
        """The return map at u from the committed history without its tangent:
        (f_int, :class:`~hpfebe.constitutive.j2.ReturnMap`), cached for the last u; the
        tangent follows from :meth:`tangent_matrix` when it is needed (a Newton step,
        not a rejected line-search trial)."""
        key = np.asarray(u, dtype=float)
        if self._cache is not None and np.array_equal(self._cache[0], key):
            return self._cache[1], self._cache[2]
        rm, fe = self._return_map(array("u", key, shape=(self.ndofs,), finite=False))
        f = np.bincount(self.element_dofs.T.ravel(), fe.ravel(), minlength=self.ndofs)
        self._cache = (key.copy(), f, rm, {})
        return f, rm

    def _return_map(self, u: np.ndarray):
        """(:class:`~hpfebe.constitutive.j2.ReturnMap` at u from the committed history,
        element forces (nel, nloc)) by :func:`_state_kernel`."""
        m, c, n = self.material, self.committed, self.n_points
        ue = np.ascontiguousarray(u[self.element_dofs].T)
        sigma, ep, alpha, beta, normal, dgamma, f_trial, safe, fe = _state_kernel(
            self._Bc, self._comps, ue, self._dx_c,
            np.ascontiguousarray(c.eps_p.reshape(n, 9)),
            np.ascontiguousarray(c.alpha), np.ascontiguousarray(c.beta.reshape(n, 9)),
            m.mu, m.kappa, m.H, m.theta, m.sigma_Y)
        t = (n, 3, 3)
        rm = ReturnMap(sigma.reshape(t), J2State(ep.reshape(t), alpha, beta.reshape(t)),
                       None, dgamma, f_trial > 0.0, f_trial, normal.reshape(t), safe)
        return rm, fe

    def response(self, u: np.ndarray, tangent: str | None = None):
        """The return map at u from the committed history: (f_int, tangent matrix,
        :class:`~hpfebe.constitutive.j2.ReturnMap`); the ReturnMap's pointwise tangent
        is not formed (:func:`~hpfebe.constitutive.j2.consistent_tangent` gives it)."""
        tg = self.tangent if tangent is None else tangent
        f, rm = self.state_at(u)
        T = self._cache[3].get(tg)
        if T is None:
            T = self._cache[3][tg] = self.tangent_matrix(rm, tg)
        return f, T, rm

    def internal_force(self, u: np.ndarray):
        """(f_int(u), algorithmic tangent) from the committed history (pure in u)."""
        f, T, _ = self.response(u)
        return f, T

    def internal_force_lazy(self, u: np.ndarray):
        """(f_int(u), a callable returning the tangent at u): the tangent is assembled
        only when called (:meth:`internal_force` gives both at once)."""
        f, rm = self.state_at(u)
        return f, lambda: self.tangent_matrix(rm)

    def commit(self, u: np.ndarray) -> None:
        """The state at u becomes the committed history (after a converged load step);
        ValueError if u or the state at u is not finite (NaN is never history)."""
        finite("u (the displacement committed as history)", u)
        _, rm = self.state_at(u)
        finite("the state at u (eps_p, alpha, beta, sigma)", rm.state.eps_p,
               rm.state.alpha, rm.state.beta, rm.sigma)
        self.committed = rm.state.copy()
        self.sigma = rm.sigma.copy()
        self._cache = None

    # ------------------------------------------------------------------ post-processing
    def committed_force(self) -> np.ndarray:
        """f_int of the committed stress (the reactions on Dirichlet dofs)."""
        return self._force(self.sigma)

    def fields(self) -> dict:
        """Committed fields per quadrature point, (nel, nq): ||eps_p||, ||dev sigma||,
        alpha (the hardening variable), the stress and plastic strain components
        ``sigma_xx`` ... ``eps_p_xy`` (xx, yy, zz, xy), and the element means (nel,)
        under the keys ``*_mean``."""
        out = {"eps_p_norm": tensor_norm(self.committed.eps_p),
               "dev_sigma_norm": tensor_norm(dev(self.sigma)),
               "alpha": self.committed.alpha}
        for name, t in (("sigma", self.sigma), ("eps_p", self.committed.eps_p)):
            for c, (i, j) in zip(("xx", "yy", "zz", "xy"), ((0, 0), (1, 1), (2, 2), (0, 1))):
                out[f"{name}_{c}"] = t[..., i, j]
        w = self.dx / self.dx.sum(axis=1, keepdims=True)
        for k in list(out):
            v = out[k].reshape(self.nel, self.nq)
            out[k] = v
            out[k + "_mean"] = (v * w).sum(axis=1)
        return out

    def elements_at(self, point) -> np.ndarray:
        """Indices of the elements whose closure contains ``point`` (one inside an
        element, two on an edge, up to four at a vertex; ValueError if outside)."""
        p = np.asarray(point, dtype=float).reshape(2)
        # cached per point: skfem's quad element_finder rebuilds a triangle mesh with a
        # Python-level boundary lookup on every call (measured 11.5 s of a 98 s
        # stamping run at h = 0.05, two calls per load increment)
        cache = self.__dict__.setdefault("_elements_at", {})
        key = (float(p[0]), float(p[1]))
        if key in cache:
            return cache[key].copy()
        d = 1e-9 * float(np.ptp(self.mesh.p, axis=1).max())
        off = np.array([[d, d], [d, -d], [-d, d], [-d, -d]])
        x, y = p[0] + off[:, 0], p[1] + off[:, 1]
        finder = self.__dict__.get("_finder")
        if finder is None:          # built once per body (the same finder every call),
            # on the mesh without its labels: skfem carries the boundaries over to the
            # triangle mesh by a quadratic search (0.4 s per finder at h = 0.05)
            bare = replace(self.mesh, _boundaries=None, _subdomains=None)
            finder = self._finder = bare.element_finder()
        try:
            e = np.asarray(finder(x, y))
        except ValueError:
            e = np.array([-1])
        e = np.unique(e[e >= 0])
        if e.size == 0:
            raise ValueError(f"point must lie in the body, got {tuple(p)!r}")
        cache[key] = e
        return e.copy()

    def value_at(self, key: str, point) -> float:
        """The committed field ``key`` (see :meth:`fields`) at ``point``: its element
        mean, averaged over the elements that touch the point."""
        f = self.fields()
        if key not in f or key.endswith("_mean"):
            raise ValueError(f"key must be one of {sorted(k for k in f if '_mean' not in k)}, "
                             f"got {key!r}")
        return float(f[key + "_mean"][self.elements_at(point)].mean())


class DisplacementSteps:
    """Load steps of one body alone (:class:`hpfebe.solvers.LoadStep`): at load factor
    lam the dofs ``fixed`` are prescribed to lam * ``values`` and the external load is
    lam * ``f_ext``; residual R = f_int(u) - lam f_ext on the free dofs, merit 1/2 |R|^2,
    force scale max |f_int| (reactions included); each step starts from the secant
    extrapolation of the last two converged states (``extrapolate``).  ``body``: an
    object with ndofs, internal_force, commit.  ``history`` collects (lam, SolverInfo)
    of every attempt."""

    def __init__(self, body, fixed, values, f_ext=None, extrapolate: bool = True):
        self.body = body
        self.extrapolate = boolean("extrapolate", extrapolate)
        self._last = None
        n = body.ndofs
        self.fixed = array("fixed (dofs)", fixed, dtype=np.int64, ndim=1)
        values = array("values", values)
        if values.ndim > 1 or values.size not in (1, self.fixed.size):
            raise ValueError(f"values must be a number or one per fixed dof "
                             f"({self.fixed.size}), got shape {values.shape}")
        self.values = np.broadcast_to(values, self.fixed.shape).copy()
        if self.fixed.size and (self.fixed.min() < 0 or self.fixed.max() >= n):
            raise ValueError(f"fixed dofs must lie in [0, {n}), got {self.fixed.min()}.."
                             f"{self.fixed.max()}")
        self.f_ext = np.zeros(n) if f_ext is None else array("f_ext", f_ext, shape=(n,))
        self.free = np.setdiff1d(np.arange(n), self.fixed)
        self.lam = 0.0
        self.history = []

    # LoadStep
    def problem(self, lam: float):
        self.lam = float(lam)
        return self

    def start(self, x: np.ndarray, lam: float) -> np.ndarray:
        """The committed x, extrapolated linearly from the last converged increment if
        ``extrapolate`` (secant predictor), with the prescribed values at lam."""
        x = np.array(x, dtype=float)
        if self.extrapolate and self._last is not None:
            (x0, l0), (x1, l1) = self._last
            if l1 > l0 and np.array_equal(x1, x):
                x = x + (lam - l1) / (l1 - l0) * (x1 - x0)
        x[self.fixed] = lam * self.values
        return x

    def commit(self, it: Iterate) -> None:
        self.body.commit(it.x)
        prev = (np.zeros_like(it.x), 0.0) if self._last is None else self._last[1]
        self._last = (prev, (it.x.copy(), self.lam))

    def record(self, it: Iterate, info) -> None:
        self.history.append((self.lam, info))

    # NewtonProblem
    def evaluate(self, x: np.ndarray) -> Iterate:
        # the tangent only when a Newton step asks for it (not at rejected line-search
        # trials and the converged iterate): ``data`` may be a callable returning it
        lazy = getattr(self.body, "internal_force_lazy", None)
        f, T = lazy(x) if lazy is not None else self.body.internal_force(x)
        r = f[self.free] - self.lam * self.f_ext[self.free]
        scale = max(float(np.abs(f).max(initial=0.0)),
                    float(np.abs(self.lam * self.f_ext).max(initial=0.0)), 1e-300)
        return Iterate(x, r, 0.5 * float(r @ r), scale, None, T)

    def slope(self, it: Iterate, dx: np.ndarray) -> float:
        return -2.0 * it.merit

    @staticmethod
    def tangent(it: Iterate):
        """The tangent of an iterate of :meth:`evaluate` (assembled now if deferred)."""
        return it.data() if callable(it.data) else it.data

    def step(self, it: Iterate) -> np.ndarray:
        A = self.tangent(it)[self.free][:, self.free].tocsc()
        try:
            d = spla.spsolve(A, -it.residual)
        except RuntimeError as e:                                   # singular factor
            raise SingularStep(f"tangent singular: {e}") from None
        if not np.all(np.isfinite(d)):
            raise SingularStep("tangent singular: non-finite Newton step")
        dx = np.zeros_like(it.x)
        dx[self.free] = d
        return dx
