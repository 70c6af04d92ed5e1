"""Two elastic bodies in penalty contact with Coulomb friction on non-matching meshes
(Chapter 4, Section 4.2: master-slave gap (4.18), constitutive laws (4.19)-(4.20), the
return map of Section 4.2.5, Newton with load increments, Algorithm 4.1, block systems
(4.27) FE/BE and (4.33) BE/BE).

Bodies.  Each body is either a P1/Q1 finite element body
(:class:`hpfebe.fem.elasticity.ElasticBody`) or a Galerkin boundary element body
(:class:`hpfebe.bem.lame.LameBEM` on a labelled :class:`hpfebe.geometry.BoundaryMesh`).
The contact code below is written once; what depends on the discretisation (stiffness,
contact segments, traces at the contact points, boundary conditions and loads) comes
from the body (:mod:`hpfebe.bodies.body`).  A BE body's unknowns are its
boundary displacement in V_hp^2 (interleaved components), its stiffness the dense
discrete Steklov-Poincare operator S_hat, its traces the GLL Lagrange basis of degree p.

Unknowns and block structure.  One dof vector U = (U^s, U^m): the slave body's dofs first,
then the master's (offset = the slave's ndofs), as in (4.27)/(4.33).  The Newton matrix is

    [ K^s + C_ss    -C_sm     ]
    [ -C_ms         K^m + C_mm]   (signs absorbed in the coupling matrices below),

K^b the FE stiffness (sparse) or S_hat (dense, stored as a fully populated block of the
one sparse matrix, so that FE blocks stay sparse), C the linearised contact terms
(sparse); each Newton system is solved by a sparse LU (scipy.sparse.linalg.splu).

Contact points. The thesis evaluates the gap at slave points x^s and leaves the
integration of the contact terms open. Ours (segment-based Gauss-point-to-segment):
every slave facet of Gamma_C^s is split where master vertices of Gamma_C^m project onto
it, and each piece gets ``nq`` Gauss-Legendre points, so that both traces (linear on the
piece) and the contact integrands are integrated exactly for a flat interface: this is
what makes the contact patch test pass to rounding on non-matching meshes. With
``split=False`` the Gauss points of the whole slave facets are used (plain GPTS); the
master forces are then integrated inexactly across master kinks and the patch test fails
at the percent level (5-7 % pressure error on the 4-vs-5 element test). The split is
exact for straight interfaces; on a polygonal master it still puts a break at every
master vertex. Every contact point x^s is projected onto the master polyline Gamma_C^m
(closest point, vectorised: all points against all master segments, parameter clipped to
the segment). Corners: the nearest segment wins; when two segments are equally near (a
point in the exterior cone of a convex corner, or exactly above a shared vertex) the one
on which the unclipped projection parameter lies inside [0, 1] (or the least outside) is
taken, and its normal is used - Wriggers' "nearest segment" rule. A point in the
exterior cone of a corner projects onto the corner vertex (with the normal of the chosen
segment). Points whose projection falls beyond the ends of the master polyline (clipped
onto an end vertex, a vertex of one master facet only) are flagged ``outside`` and carry
no contact.

Small deformation (what Section 4.2.5 linearises: g_n(U_n) = ([U_n] - g)_+ with the normal
fixed): the projection, the master normal n_m (outward of the master body) and tangent
t_m = (n_m,y, -n_m,x) (n_m turned clockwise by 90 degrees: +x on the top side of a lower
body) are computed once, in the reference configuration, and kept fixed.  With
x_m = the projection and N_m the master shape functions at it,

    g_n = (x_s + u_s - x_m - u_m) . n_m     (signed normal gap; penetration  g_n < 0),
    g_t = (u_s - u_m) . t_m                 (relative tangential displacement).

Laws: the normal penalty and the Coulomb / Tresca return map of
:mod:`hpfebe.constitutive.laws` with penetration d_n = -g_n and slip g_t, the traction on the
slave p_n n_m - t_t t_m, on the master its negative.  Weak form, with the internal contact
force f_c(U) . V = sum_q w_q [ -p_n dg_n(V) + t_t dg_t(V) ] (w_q the quadrature weights):

    R(U) = K U + f_c(U) - F_ext = 0   on the free dofs,

and the consistent tangent K + G_n^T W_n G_n + G_t^T (W_t G_t - W_tn G_n) (G_n, G_t the
sparse maps U -> dg_n, dg_t at the points, W the diagonal law derivatives of
:class:`hpfebe.constitutive.laws.LawState` times the weights): non-symmetric in slip.

Single pass and two passes.  The construction above is one master-slave pass, the
thesis's Section 4.2 formulation (the gap (4.18) at slave points, the master's normal):
the default.  ``two_pass=True`` (two deformable bodies) adds the symmetric treatment of
Laursen (Computational Contact and Impact Mechanics, Ch. 5) and Wriggers (Computational
Contact Mechanics, two-pass node-to-segment): a second pass with the roles swapped,
points on the master's contact segments (split at the projections of the slave
vertices), projected onto the slave polyline, gap and slip along the slave's outward
normal n_s and t_s = (n_s,y, -n_s,x),

    g_n = (x_m + u_m - x_s - u_s) . n_s,     g_t = (u_m - u_s) . t_s,

with the same eps_n, eps_t and law.  On a flat interface n_s = -n_m, t_s = -t_m, so at
coinciding points both passes see the same g_n and the same physical slip g_t (the sign
flips of the tangent and of the difference cancel).  Both passes integrate
(approximately: exactly on a flat interface with the splits) the same interface, so the
contact stiffness is about 2/eps_n and the penetration about half the single pass's at
the same contact force; each pass carries about half the force (the physical traction is
the sum of the passes').  On a flat interface the pass-1 points coincide with the pass-0
points wherever both sides overlap (both passes integrate on the common refinement of
the two interface meshes), with the same weights, gaps and slips, and the other points
are ``outside``: the two-pass problem is then the single pass with eps_n/2, eps_t/2 up
to rounding (measured on the Table 4.3 scene: max |dU| / max |U| = 2.7e-16); the two
differ on curved or kinked interfaces.  Per-point arrays are concatenated, pass 0
first; ``passes`` (here and in :class:`ContactResult`) marks each point's pass, e.g. the
penetration on the slave side alone is integrated with ``weights * (passes == 0)``.

A rigid obstacle as master (:class:`hpfebe.bodies.body.RigidObstacle`): the points are
Gauss points of the slave's contact elements, n_m = -n (n the slave's outward normal),
t_m its tangent, g_n = g(x) - U_n, g_t = U_t - w(x): the one-body problems of Sections
3.2-3.3 (:func:`hpfebe.contact.friction.solve_friction`).

Algorithm 4.1 (:meth:`TwoBodyContact.solve` on :func:`hpfebe.solvers.load_path`): for
every load factor the load, the Dirichlet values and the obstacle motion are applied, the
start iterate is the last converged state, semismooth Newton iterates (optionally with an
Armijo line search on ||R||_2 or on the energy of a potential law; the semismooth
iteration alone may cycle between two contact states, e.g. the Figure 4.13 scene on
h = 1/2), and the slip is committed after convergence; failures are reported with a
reason, or the step is cut and retried (``max_cuts``).  Dense systems (no FE body) are
solved by LAPACK, sparse ones by a sparse LU with a check of its residual.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..solvers import Iterate, SolverInfo, load_path
from ..bodies.body import as_body, pointwise
from ..checks import array, boolean, choice, instance, integer, real
from ..constitutive.laws import penalty_friction, tresca_energy
from .loading import LoadSteps
from .points import rigid_points, trace_maps, two_body_points
from .positive_part import ExactPositivePart
from .result import ContactResult
from .settings import ContactSettings

QUADRATURES = ("gauss", "exact")


def data_force(steps: LoadSteps, lam: float = 1.0) -> float:
    """The reference force of the data of the load ``steps`` at the load factor ``lam``:
    ||R(U_D)|| in the norm of the stopping test, the residual on the free dofs of the
    state U_D that is zero but for the prescribed values (the load, the forces of the
    prescribed displacement and of an initial penetration on the undeformed bodies: the
    start of a one-step solve).  It scales with the forces when moduli, loads and
    prescribed displacements are scaled together."""
    steps.problem(lam)
    r = steps.evaluate(steps.start(np.zeros(steps.pr.ndofs), lam)).residual
    if r.size == 0:
        return 0.0
    return float(np.abs(r).max() if steps.settings.norm == "max" else np.linalg.norm(r))


def _csr_block_diag(A: sp.csr_matrix, B: sp.csr_matrix) -> sp.csr_matrix:
    """blockdiag(A, B) in CSR: the rows of A, then those of B with shifted columns (the
    entries of ``sp.block_diag``, without its COO round trip; entries in the order of
    the blocks)."""
    n, m = A.shape
    idx = np.result_type(A.indices, B.indices, np.int32)
    if m + B.shape[1] > np.iinfo(idx).max or A.nnz + B.nnz > np.iinfo(idx).max:
        idx = np.int64
    indptr = np.concatenate([A.indptr.astype(idx), A.nnz + B.indptr[1:].astype(idx)])
    indices = np.concatenate([A.indices.astype(idx), B.indices.astype(idx) + m])
    data = np.concatenate([A.data, B.data]).astype(np.result_type(A.data, B.data))
    return sp.csr_matrix((data, indices, indptr), shape=(n + B.shape[0], m + B.shape[1]))


class _BlockDiagonal:
    """:func:`_csr_block_diag` of two body tangents, its index arrays reused while both
    tangents keep their patterns (a plastic body's tangent at every state has the pattern
    of its stiffness), so that a Newton step of a plastic body concatenates the values
    only."""

    def __init__(self):
        self.last = None     # (A.indices, A.indptr, B.indices, B.indptr, block diagonal)

    def __call__(self, A: sp.csr_matrix, B: sp.csr_matrix) -> sp.csr_matrix:
        last = self.last
        if last is not None and A.data.dtype == B.data.dtype == np.float64 and all(
                _same_array(a, b) for a, b in zip(last[:4], (A.indices, A.indptr,
                                                            B.indices, B.indptr))):
            out = last[4]
            return sp.csr_matrix((np.concatenate([A.data, B.data]), out.indices,
                                  out.indptr), shape=out.shape)
        out = _csr_block_diag(A, B)
        self.last = (A.indices.copy(), A.indptr.copy(), B.indices.copy(), B.indptr.copy(),
                     out)
        return out


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    """a and b hold the same numbers (equal shapes and entries; scipy's constructors
    return new array objects, often views, for the index arrays they are given)."""
    return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b)


class _State(dict):
    """The contact state of :meth:`TwoBodyContact.internal_force`: a dict whose entries
    in ``lazy`` (key -> callable) are computed on first access."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.lazy = {}

    def __missing__(self, key):
        if key not in self.lazy:
            raise KeyError(key)
        value = self[key] = self.lazy.pop(key)()
        return value


def _objects(body) -> set:
    """The ids of a body and of the objects its contact wrapper holds (the FE body, the
    BEM, the plastic body): the same body given twice shares one of them."""
    return {id(b) for b in (body, getattr(body, "body", None), getattr(body, "bem", None),
                            getattr(body, "plastic", None)) if b is not None}


def _force_lazy(body, u):
    """(f_int, tangent or a callable returning it) of a contact body: the callable when
    the body can defer its tangent (``internal_force_lazy``, a plastic body)."""
    lazy = getattr(body, "internal_force_lazy", None)
    return lazy(u) if lazy is not None else body.internal_force(u)


class TwoBodyContact:
    """Two bodies (FE, BE, or a BE/FE body against a rigid obstacle) in frictional
    penalty contact.

    Parameters
    ----------
    slave, master
        ElasticBody (FE), LameBEM (BE), or a body of :mod:`hpfebe.bodies.body`
        (:class:`~hpfebe.bodies.RigidObstacle` for the master: one body against a rigid
        obstacle, Sections 3.2-3.3)
    slave_boundary, master_boundary
        labels (str or list) of Gamma_C^s, Gamma_C^m
        (FE: facet labels; BE: element labels; ignored for a rigid master)
    eps_n, eps_t
        penalty parameters (> 0, keywords; eps_n is required, eps_t defaults
        to 1); 1/eps are the contact stiffnesses
    mu_f
        Coulomb coefficient (>= 0; 0 = frictionless), or F : Tresca bound (float or
        callable of the points, >= 0; acts on all of Gamma_C)
    nq
        Gauss points per integration piece (two bodies: at least p_max + 1 with a BE
        body; rigid master: per element, default p_I + 1 for a BE slave, 2 for FE)
    split
        split the slave segments at the projections of the master vertices
    quadrature
        "gauss" (fixed points above) or "exact": a BE body against a rigid
        obstacle without friction, (U_n - g_h)_+ integrated exactly on the pieces where
        it is positive (:mod:`hpfebe.contact.positive_part`, Section 3.2)
    two_pass
        False (default) = one master-slave pass, the thesis's Section 4.2
        formulation; True = the symmetric two-pass treatment (module doc: a second pass
        with the bodies' roles swapped, contact stiffness about 2/eps_n on a flat
        interface); two deformable bodies and quadrature "gauss" only
    """

    def __init__(self, slave, master, slave_boundary, master_boundary=None, *,
                 eps_n: float, eps_t: float = 1.0, mu_f: float = 0.0, F=None,
                 nq: Optional[int] = 2, split: bool = True, quadrature: str = "gauss",
                 two_pass: bool = False):
        self.bodies = {"slave": as_body(slave, "slave"), "master": as_body(master, "master")}
        self.slave, self.master = slave, master
        if self.bodies["slave"].kind == "rigid":
            raise ValueError("slave must be a deformable body (the obstacle is the master)")
        if _objects(slave) & _objects(master):
            raise ValueError("slave, master must be two bodies, got the same body twice "
                             "(self-contact is not modelled: its two copies would "
                             "overlap in the reference configuration)")
        self.eps_n = real("eps_n", eps_n, positive=True)
        self.eps_t = real("eps_t", eps_t, positive=True)
        self.mu_f = real("mu_f", mu_f, nonnegative=True)
        if F is not None and self.mu_f > 0:
            raise ValueError("give mu_f (Coulomb) or F (Tresca), not both")
        self.nq = integer("nq", nq, lo=1, allow_none=True)
        self.split = boolean("split", split)
        sb, mb = self.bodies["slave"], self.bodies["master"]
        self.two_pass = self._two_pass(two_pass, mb, quadrature)
        self.offset = sb.ndofs
        self.ndofs = sb.ndofs + mb.ndofs
        # (4.27) / (4.33): FE blocks sparse, a BE block (dense S_hat) inside; a system
        # without FE body (BE against rigid or BE) stays dense
        self.dense = "FE" not in (sb.kind, mb.kind)
        # the contact points and their per-point arrays (:mod:`.points`)
        pts = rigid_points(sb, mb, slave_boundary, self.nq, self.ndofs) \
            if mb.kind == "rigid" else \
            two_body_points(sb, mb, slave_boundary, master_boundary, self.offset,
                            self.ndofs, self.nq, self.split, self.two_pass)
        for key, value in pts.items():
            setattr(self, key, value)
        self.F = None if F is None else pointwise("F", F, self.points, allow_negative=False)
        self.law_name = "tresca" if F is not None else "coulomb"
        self.exact = self._exact_quadrature(quadrature, slave_boundary)
        # the last block diagonal of the body tangents and its index arrays (_blocks)
        self._blocks_last, self._block_pattern = None, _BlockDiagonal()

    @staticmethod
    def _two_pass(two_pass, master, quadrature) -> bool:
        """Validated ``two_pass``: a bool, only for a deformable master and the fixed
        Gauss points (the exact positive part is a one-body quadrature)."""
        two_pass = boolean("two_pass", two_pass)
        if two_pass and master.kind == "rigid":
            raise ValueError("two_pass needs a deformable master (a rigid obstacle has no "
                             "contact points of its own)")
        if two_pass and quadrature == "exact":
            raise ValueError("two_pass is not available with quadrature='exact'")
        return bool(two_pass)

    def _exact_quadrature(self, quadrature: str, slave_boundary):
        choice("quadrature", quadrature, QUADRATURES)
        if quadrature == "gauss":
            return None
        sb, mb = self.bodies["slave"], self.bodies["master"]
        if not (sb.kind == "BE" and mb.kind == "rigid" and self.F is None
                and self.mu_f == 0):
            raise ValueError("quadrature='exact' is for a BE body against a rigid obstacle "
                             "without friction")
        return ExactPositivePart(sb.mesh, sb.space, np.unique(self.point_facets), mb.gap)

    @property
    def K(self):
        """The stiffness of the bodies (4.27)/(4.33) at rest (dense without FE body)."""
        sb, mb = self.bodies["slave"], self.bodies["master"]
        if self.dense:
            return sla.block_diag(*[b.S for b in (sb, mb) if b.kind == "BE"])
        return sp.block_diag([sb.K, mb.K], format="csr")

    # ------------------------------------------------------------------ dof helpers
    def global_dofs(self, body: str, dofs: np.ndarray) -> np.ndarray:
        """Global indices of a body's local dofs (``body`` = "slave" or "master")."""
        if body == "slave":
            return np.asarray(dofs, dtype=np.int64)
        if body == "master":
            return np.asarray(dofs, dtype=np.int64) + self.offset
        raise ValueError(f"body must be 'slave' or 'master', got {body!r}")

    def dofs_on(self, body: str, labels, component: Optional[int] = None) -> np.ndarray:
        return self.global_dofs(body, self._contact_body(body).dofs_on(labels, component))

    def stamp_dofs(self) -> tuple[np.ndarray, np.ndarray]:
        """The dofs a stamp scene prescribes (Sections 4.2.7, 4.2.8, 4.4: the slave
        stamp held at its "top", the master work piece moved at its "bottom" in y and held
        in x): (fixed, is_y), with ``is_y`` marking the master's bottom y components (the
        prescribed values are lift * is_y)."""
        top = self.dofs_on("slave", "top")
        bx, by = self.dofs_on("master", "bottom", 0), self.dofs_on("master", "bottom", 1)
        is_y = np.concatenate([np.zeros(top.size + bx.size, bool), np.ones(by.size, bool)])
        return np.concatenate([top, bx, by]), is_y

    def dofs_at(self, body: str, point, component: Optional[int] = None) -> np.ndarray:
        return self.global_dofs(body, self._contact_body(body).dofs_at(point, component))

    def traction_load(self, body: str, label: str, traction) -> np.ndarray:
        """Global load vector of a traction on the boundary part ``label`` of ``body``."""
        ad = self._contact_body(body)
        f = np.zeros(self.ndofs)
        f[self.global_dofs(body, np.arange(ad.ndofs))] = ad.traction_load(label, traction)
        return f

    def dof_coordinates(self) -> np.ndarray:
        return np.vstack([self.bodies["slave"].dof_coordinates(),
                          self.bodies["master"].dof_coordinates()])

    def displacement_at(self, body: str, U: np.ndarray, labels, s) -> np.ndarray:
        """(n, 2) displacement of ``body`` (global dof vector U) at the points
        a + s (b - a) of its segments on ``labels`` (n = number of segments x len(s))."""
        ad = self._contact_body(body)
        sg = ad.segments(labels)
        s = np.atleast_1d(np.asarray(s, dtype=float))
        ids = np.repeat(sg["ids"], s.size)
        par = np.tile(s, sg["ids"].size)
        tc, tv = ad.trace(ids, par)
        u = np.asarray(U)[self.global_dofs(body, np.arange(ad.ndofs))]
        return np.einsum("nj,ncj->nc", tv, u[tc])

    def _contact_body(self, body: str):
        if body in ("slave", "master"):
            return self.bodies[body]
        raise ValueError(f"body must be 'slave' or 'master', got {body!r}")

    def _body(self, body: str):
        return self._contact_body(body).body

    # ------------------------------------------------------------------ contact law
    def _quadrature(self, U: np.ndarray) -> dict:
        """The contact points at U: fixed (Gauss points of the slave segments), or with
        ``quadrature="exact"`` the Gauss points of the pieces where U_n - g_h > 0."""
        if self.exact is None:
            return dict(Gn=self.Gn, Gt=self.Gt, weights=self.weights, g0=self.g0,
                        points=self.points, outside=self.outside, elements=self.point_facets)
        q = self.exact.points(U)
        S, ids = self.bodies["slave"], q["ids"]
        nm = -S.mesh.normals[ids]
        Gn, Gt, _ = trace_maps(nm, [(S, ids, q["s"], 0, 1.0)], self.ndofs) if ids.size \
            else (sp.csr_matrix((0, self.ndofs)),) * 2 + (None,)
        return dict(Gn=Gn, Gt=Gt, weights=q["weights"], g0=q["g0"],
                    points=S.mesh.points(ids, 2.0 * q["s"] - 1.0) if ids.size
                    else np.zeros((0, 2)), outside=np.zeros(ids.size, bool), elements=ids,
                    n_active=q["n_active"])

    def contact_state(self, U: np.ndarray, slip, motion=None) -> dict:
        """Contact points, gap g_n, relative tangential displacement g_t and the law at U."""
        cs = self._quadrature(U)
        g_n = cs["g0"] + cs["Gn"] @ U
        if self.exact is None:
            g_t = cs["Gt"] @ U - (self.motion if motion is None else motion)
        else:
            g_t, slip = np.zeros_like(g_n), 0.0          # frictionless
        law = penalty_friction(-g_n, g_t, slip, self.eps_n, self.eps_t,
                               mu_f=self.mu_f if self.F is None else None, F=self.F,
                               active=~cs["outside"])
        cs.update(g_n=g_n, g_t=g_t, p_n=law.p_n, t_t=law.t_t, state=law.state, law=law)
        return cs

    def contact_force(self, cs: dict) -> np.ndarray:
        """f_c(U) = sum_q w_q [-p_n dg_n + t_t dg_t] (the traction on the slave is
        p_n n_m - t_t t_m, on the master its negative)."""
        w = cs["weights"]
        return cs["Gn"].T @ (w * -cs["p_n"]) + cs["Gt"].T @ (w * cs["t_t"])

    def internal_force(self, U: np.ndarray, slip: np.ndarray, motion=None):
        """f_int(U) + f_c(U) and the state at U: the bodies' internal forces and tangents
        (``body.internal_force``: K U and K for a linear body, the return-map force and
        algorithmic tangent of a plastic one, from its committed history) and the
        contact state; ``cs["K_body"]`` of a body with ``internal_force_lazy`` (plastic)
        is assembled on its first access (a Newton step, the predictor), not at every
        line-search trial."""
        cs = _State(self.contact_state(U, slip, motion))
        (fs, Ks), (fm, Km) = (_force_lazy(self.bodies["slave"], U[: self.offset]),
                              _force_lazy(self.bodies["master"], U[self.offset:]))
        cs["f_body"] = np.concatenate([fs, fm])
        if callable(Ks) or callable(Km):
            # a plastic body's tangent only when a Newton step or the predictor asks for
            # it (not at rejected line-search trials): assembled on first access
            cs.lazy["K_body"] = lambda: self._blocks(Ks() if callable(Ks) else Ks,
                                                     Km() if callable(Km) else Km)
        else:
            cs["K_body"] = self._blocks(Ks, Km)
        cs["f_c"] = self.contact_force(cs)
        return cs["f_body"] + cs["f_c"], cs

    def _blocks(self, Ks, Km):
        """The block diagonal of the body tangents (4.27)/(4.33): dense without FE body.
        Built once while the bodies return the same tangent objects (linear bodies: their
        stiffness, at every Newton iterate), rebuilt when a tangent changes (plastic)."""
        last = self._blocks_last
        if last is not None and last[0] is Ks and last[1] is Km:
            return last[2]
        if Km.shape[0] == 0:
            out = Ks if self.dense else sp.csr_matrix(Ks)
        elif self.dense:
            out = sla.block_diag(Ks, Km)
        else:
            out = self._block_pattern(sp.csr_matrix(Ks), sp.csr_matrix(Km))
        self._blocks_last = (Ks, Km, out)
        return out

    def commit(self, U: np.ndarray) -> None:
        """Commit the bodies' history (plastic state) at a converged U."""
        self.bodies["slave"].commit(U[: self.offset])
        self.bodies["master"].commit(U[self.offset:])

    def contact_tangent(self, cs: dict) -> sp.csr_matrix:
        """Linearised contact terms (Section 4.2.5): Gn^T W_n Gn + Gt^T (W_t Gt - W_tn Gn),
        W = diag(w dp_n), diag(w dt_t), diag(w dt_n)."""
        w, law, Gn, Gt = cs["weights"], cs["law"], cs["Gn"], cs["Gt"]
        C = Gn.T @ sp.diags(w * law.dp_n) @ Gn
        if np.any(law.dt_t) or np.any(law.dt_n):
            C = C + Gt.T @ (sp.diags(w * law.dt_t) @ Gt - sp.diags(w * law.dt_n) @ Gn)
        return C

    def tangent(self, cs: dict):
        """Consistent Newton matrix K + C for the state ``cs`` (dense without FE body)."""
        C = self.contact_tangent(cs)
        K = cs["K_body"]
        return K + C.toarray() if self.dense else (K + C).tocsr()

    def energy(self, U: np.ndarray, cs: dict, f: np.ndarray) -> float:
        """1/2 U.K U - f.U + contact potential: the merit of the potential laws
        (frictionless, Tresca) of linear bodies, whose gradient is the residual."""
        F = 0.0 if self.F is None else self.F
        pot = tresca_energy(cs["law"], self.eps_n, self.eps_t, F)
        return float(0.5 * U @ cs["f_body"] - f @ U + cs["weights"] @ pot)

    # ------------------------------------------------------------------ Algorithm 4.1
    def solve(self, f_ext=None, fixed_dofs=None, fixed_values=None,
              load_factors: Sequence[float] = (1.0,),
              settings: ContactSettings = ContactSettings(),
              initial: ContactResult | None = None) -> ContactResult:
        """Incremental loading with semismooth Newton (Algorithm 4.1,
        :func:`hpfebe.solvers.load_path`) with the Newton, line-search, cut and
        linear-solver settings ``settings`` (:class:`ContactSettings`).

        ``f_ext`` global load at load factor 1 (scaled by lambda) or a callable
        lambda -> vector; ``fixed_dofs`` with ``fixed_values`` (at lambda = 1, scaled;
        a callable; None = 0); the obstacle motion is ramped like the load;
        ``load_factors`` increasing; a failed step is halved and retried from the last
        converged state at most ``settings.max_cuts`` times.  ``initial``: a converged
        result of this problem to continue from (U, slip, load and obstacle motion
        ramped from its final values)."""
        instance("settings", settings, ContactSettings)
        steps = LoadSteps(self, f_ext, fixed_dofs, fixed_values, settings, initial)
        lf = array("load_factors", load_factors, ndim=1, min_size=1)
        if settings.atol > 0:                 # an absolute floor: scaled with the data?
            lam = float(lf[np.argmax(np.abs(lf))])
            settings.check_floor(data_force(steps, lam), lam)
        it, info = load_path(steps, lf, steps.x0, max_cuts=settings.max_cuts, lam0=0.0,
                             **steps.newton_options())
        return self.result(it, info, steps)

    def result(self, it: Iterate, info: SolverInfo, steps: LoadSteps) -> ContactResult:
        """The :class:`ContactResult` of the iterate ``it`` of the load ``steps``."""
        U, cs = it.x, it.data
        return ContactResult(
            U=U.copy(), u_slave=U[: self.offset].copy(), u_master=U[self.offset:].copy(),
            converged=info.converged, reason=info.reason, info=info, points=cs["points"],
            weights=cs["weights"], g_n=cs["g_n"], g_t=cs["g_t"], p_n=cs["p_n"],
            t_t=cs["t_t"], bound=np.asarray(cs["law"].bound, dtype=float),
            state=cs["state"], slip=steps.slip, elements=cs["elements"],
            load_vector=steps.f, obstacle_motion=steps.w, friction=self.law_name,
            passes=self.passes if self.exact is None
            else np.zeros(cs["points"].shape[0], dtype=np.intp))
