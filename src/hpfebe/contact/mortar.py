"""hp-mortar BEM for two-body contact with friction (Sections 4.3.3-4.3.5): the inner
frictionless contact QP solved by Polyak's projected conjugate gradients, the Uzawa
algorithm for given (Tresca) friction (Algorithm 4.4), the Dirichlet-to-Neumann
algorithm (Algorithm 4.3) with damping omega_D, omega_N (optionally Aitken-relaxed), the
global Uzawa algorithm for Coulomb friction (Algorithm 4.5), the indicator eta of
Section 4.3.5 and the hp-refinement rule of Algorithm 4.6 (:func:`hp_refine`, a
``refine`` callback for :func:`hpfebe.adaptivity.adapt`).

Discrete setting.  Body i is a :class:`hpfebe.bem.lame.LameBEM` body with unknowns U^i in
V^i_hp^2 (GLL Lagrange basis, interleaved components) and stiffness S_hat^i; its
Dirichlet dofs are eliminated and S_hat condensed onto the contact dofs once per mesh
(:class:`CondensedBody`: one Cholesky factorisation of the rest).  The data transfer is
the mortar projection of :mod:`hpfebe.coupling.mortar` (displacements Q = pi U^2, (4.87))
and its adjoint (tractions).

Constraints (Algorithm 4.3, step 4) are imposed at the Gauss-Lobatto points of
Gamma^1_C, which are the nodes of the GLL basis: in the frame (n_j, t_j) of each contact
node (n_j the outward normal of body 1 given by the scene, t_j = (-n_y, n_x)) the
unknowns are x = (U_n, U_t) and the constraint is U_n - Q_n <= g (gap g measured along
n_j to Gamma^2_C).  The friction functional j(W_t - Q_t) = int F |W_t - Q_t| ds is
integrated by the Gauss-Lobatto rule of each element (weights w_j, lumped), so that
the Tresca conditions hold pointwise at these points: |lambda_j| <= 1 and
lambda_j (U_t - Q_t)_j = |(U_t - Q_t)_j|.

Every outer loop is :func:`hpfebe.solvers.nonlinear.fixed_point` (stopping rule
||x_k - x_{k-1}|| <= TOL ||x_k||, divergence and iteration cap detected there); the inner
solves report a :class:`~hpfebe.solvers.nonlinear.SolverInfo` collected in ``info.steps``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
from numba import njit

from ..bem.lame import LameBEM
from ..coupling.mortar import MortarProjection
from ..geometry import BoundaryMesh
from ..solvers import SingularStep, SolverInfo, fixed_point
from ..quadrature import gauss_lobatto


# --------------------------------------------------------------------------- Polyak
#: status codes of :func:`_polyak_kernel`
_PCG_REASONS = ("max_iter", "converged", "diverged: non-finite gradient",
                "matrix not positive definite on the free set")


@njit(cache=True)
def _norm2(v):
    """||v||_2 exactly as numpy's ``np.linalg.norm`` (sqrt of the BLAS dot)."""
    return np.sqrt(np.dot(v, v))


@njit(cache=True)
def _kkt_met(r, A, x, tol, nb, bound_Ax):
    """r <= tol * max(||b||, ||A x||, 1e-300) (the KKT threshold of projected_cg),
    deciding without the product A x where the bounds ||b|| <= ... and ||A x|| <=
    ``bound_Ax`` (= ||A||_F ||x|| (1 + 1e-8), a rigorous bound of the computed norm)
    already decide it; otherwise with A x as in the numpy formulation."""
    lo = tol * max(nb, 1e-300)
    if r <= lo:
        return True
    if r > tol * max(nb, bound_Ax, 1e-300):
        return False
    return r <= tol * max(nb, _norm2(np.dot(A, x)), 1e-300)


@njit(cache=True)
def _frobenius_bound(A):
    """||A||_F (1 + 1e-8): the factor of the rigorous bound ||A x|| <= ||A||_F ||x||
    (:func:`_kkt_met`)."""
    return np.sqrt(np.sum(A * A)) * (1.0 + 1e-8)


@njit(cache=True)
def _polyak_kernel(A, b, u, x, tol, max_iter, res):
    """The iteration of :func:`projected_cg` (compiled; the same floating-point
    operations in the same order as the numpy formulation it replaces: BLAS gemv / dot,
    norms as sqrt(dot); the product A x of the stopping threshold only where the bound
    ||A x|| <= ||A||_F ||x|| leaves the decision open, :func:`_kkt_met`).  ``x`` (start,
    already <= u) is overwritten; the KKT residuals go into ``res``.  Returns
    (status, steps, n_residuals): status 0 max_iter, 1 converged, 2 non-finite gradient,
    3 not positive definite on the free set."""
    return _polyak_core(A, b, u, x, tol, max_iter, res, _frobenius_bound(A))


@njit(cache=True)
def _uzawa_step(A, b, Fw, rhoF, Qt, upper, lam, x, tol, max_iter, res, nA, lam_new):
    """One iteration of Algorithm 4.4 compiled (:meth:`MortarContact.uzawa`; the same
    floating-point operations as its numpy formulation): the contact QP with the
    friction load, rhs = b - (0, F w lambda), by :func:`_polyak_core` from the start
    ``x`` (clipped to ``upper`` first, overwritten by the solution), then
    lambda_new = P_Lambda(lambda + rho F (U_t - Q_t)) = clip to [-1, 1] into
    ``lam_new``.  ``Fw``, ``rhoF``: per node; ``nA``: :func:`_frobenius_bound` of A.
    Returns :func:`_polyak_core`'s (status, steps, n_residuals) and the size of the
    active set (x_i >= upper_i)."""
    nc = lam.size
    rhs = b.copy()
    for i in range(nc):
        rhs[nc + i] = rhs[nc + i] - Fw[i] * lam[i]
    for i in range(x.size):                   # np.minimum(x, upper) (NaN propagates)
        if not (x[i] <= upper[i] or x[i] != x[i]):
            x[i] = upper[i]
    status, steps, nres = _polyak_core(A, rhs, upper, x, tol, max_iter, res, nA)
    for i in range(nc):                       # np.minimum(np.maximum(v, -1), 1)
        v = lam[i] + rhoF[i] * (x[nc + i] - Qt[i])
        if not (v >= -1.0 or v != v):
            v = -1.0
        if not (v <= 1.0 or v != v):
            v = 1.0
        lam_new[i] = v
    active = 0
    for i in range(x.size):
        if x[i] >= upper[i]:
            active += 1
    return status, steps, nres, active


@njit(cache=True)
def _polyak_core(A, b, u, x, tol, max_iter, res, nA):
    """:func:`_polyak_kernel` with the bound factor ``nA`` = :func:`_frobenius_bound` of
    A given (computed once for a sequence of QPs with the same A)."""
    n = b.size
    g = np.dot(A, x) - b
    nb = _norm2(b)
    steps = 0
    nres = 0
    free = np.empty(n, dtype=np.bool_)
    pg = np.empty(n)
    gf = np.empty(n)
    p = np.empty(n)
    while steps < max_iter:
        # KKT: projected gradient (max(g, 0) on the active set, g elsewhere)
        for i in range(n):
            gi = g[i]
            if x[i] >= u[i]:
                pg[i] = gi if (gi > 0.0 or gi != gi) else 0.0
            else:
                pg[i] = gi
        r = _norm2(pg)
        if nres < res.size:
            res[nres] = r
        nres += 1
        if not np.isfinite(r):
            return 2, steps, nres
        if _kkt_met(r, A, x, tol, nb, nA * _norm2(x)):
            return 1, steps, nres
        for i in range(n):
            free[i] = not (x[i] >= u[i] and g[i] <= 0.0)   # held: multiplier -g_i >= 0
            p[i] = -g[i] if free[i] else 0.0
        rr = np.dot(p, p)
        while steps < max_iter:
            steps += 1
            Ap = np.dot(A, p)
            pAp = np.dot(p, Ap)
            if pAp <= 0:
                return 3, steps, nres
            alpha = rr / pAp
            afeas = np.inf
            for i in range(n):
                if free[i] and p[i] > 0:
                    a = (u[i] - x[i]) / p[i]
                    if a < afeas:
                        afeas = a
            if afeas < alpha:                    # hit a bound: cut, restart CG
                for i in range(n):
                    x[i] = x[i] + afeas * p[i]
                for i in range(n):
                    if free[i] and p[i] > 0:
                        if x[i] >= u[i] - 1e-14 * max(abs(u[i]), 1.0):
                            x[i] = u[i]
                g = np.dot(A, x) - b
                break
            for i in range(n):
                x[i] = x[i] + alpha * p[i]
                g[i] = g[i] + alpha * Ap[i]
                gf[i] = g[i] if free[i] else 0.0
            if _kkt_met(_norm2(gf), A, x, tol, nb, nA * _norm2(x)):
                g = np.dot(A, x) - b
                break
            rr_new = np.dot(gf, gf)
            beta = rr_new / rr
            for i in range(n):
                p[i] = -gf[i] + beta * p[i]
            rr = rr_new
    return 0, steps, nres


def projected_cg(A, b, upper, x0=None, tol: float = 1e-10, max_iter: int | None = None):
    """Polyak's projected conjugate gradients [53] for the bound-constrained QP

        min 1/2 x^T A x - b^T x   subject to   x <= upper   (A SPD, upper may be +inf).

    CG on the face of the active set; a CG step leaving the feasible set is cut at the
    first bound hit, that variable joins the active set and CG restarts; when CG has
    converged on a face, the active variables whose multiplier has the wrong sign
    (gradient g_i = (A x - b)_i > 0, pulling into the interior) are all released.
    Converged when the projected gradient (g on the free set, max(g, 0) on the active
    set) is <= tol * max(||b||, ||A x||) (the KKT conditions).  Returns (x, SolverInfo);
    ``info.counts`` has the CG steps and the final active set size.  The iteration is
    compiled (:func:`_polyak_kernel`)."""
    A = np.ascontiguousarray(A, dtype=float)
    b = np.ascontiguousarray(b, dtype=float)
    u = np.ascontiguousarray(upper, dtype=float)
    n = b.size
    if b.ndim != 1 or A.shape != (n, n) or u.shape != (n,):
        raise ValueError(f"b must be a vector ({n},), A ({n}, {n}) and upper ({n},), got "
                         f"{b.shape}, {A.shape}, {u.shape}")
    if x0 is not None and np.shape(x0) != (n,):
        raise ValueError(f"x0 must have shape ({n},), got {np.shape(x0)}")
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be positive, got {tol!r}")
    if np.any(np.isnan(u)):
        raise ValueError("upper contains NaN")
    max_iter = 20 * n + 100 if max_iter is None else int(max_iter)
    return _projected_cg_checked(A, b, u, x0, float(tol), max_iter)


def _projected_cg_checked(A, b, u, x0, tol: float, max_iter: int):
    """:func:`projected_cg` on validated input (A, b, u contiguous float arrays)."""
    x = np.minimum(np.zeros(b.size) if x0 is None else np.asarray(x0, dtype=float), u)
    res = np.empty(max_iter + 1)
    status, steps, nres = _polyak_kernel(A, b, u, x, tol, max_iter, res)
    return x, _pcg_info(status, steps, nres, res, int(np.count_nonzero(x >= u)))


def _per_node(v, n: int) -> np.ndarray:
    """``v`` (a scalar or an (n,) vector) as a contiguous float vector (n,)."""
    if isinstance(v, np.ndarray) and v.shape == (n,) and v.dtype == np.float64 and \
            v.flags.c_contiguous:
        return v
    return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=float), (n,)))


def _pcg_info(status, steps, nres, res, active: int) -> SolverInfo:
    """The SolverInfo of one projected-CG solve (:func:`_polyak_kernel`'s outputs and
    the final active set size)."""
    return SolverInfo(status == 1, _PCG_REASONS[status], int(steps),
                      res[:min(nres, res.size)].tolist(),
                      counts=dict(cg_steps=int(steps), active=int(active)))


# --------------------------------------------------------------------------- bodies
class CondensedBody:
    """S_hat of one body with its Dirichlet dofs eliminated and condensed onto its
    contact dofs (Schur complement, one Cholesky of the rest):

        A = S_cc - S_cr S_rr^-1 S_rc,   b = f_c - S_cr S_rr^-1 f_r,   f = -S_{.D} U_D.

    ``contact`` are interleaved dofs; those that are Dirichlet dofs are dropped
    (``cpos`` = positions of the kept ones in ``contact``)."""

    def __init__(self, S, fixed, values, contact):
        S = np.asarray(S, dtype=float)
        n = S.shape[0]
        fixed = np.asarray(fixed, dtype=np.int64)
        values = np.broadcast_to(np.asarray(values, dtype=float), fixed.shape)
        contact = np.asarray(contact, dtype=np.int64)
        is_fixed = np.zeros(n, dtype=bool)
        is_fixed[fixed] = True
        self.cpos = np.flatnonzero(~is_fixed[contact])
        c = contact[self.cpos]
        rest = np.ones(n, dtype=bool)
        rest[fixed] = False
        rest[c] = False
        r = np.flatnonzero(rest)
        self.n, self.fixed, self.values, self.c, self.r = n, fixed, values.copy(), c, r
        self.S = S
        f = -S[:, fixed] @ self.values
        cho = sla.cho_factor(S[np.ix_(r, r)])
        self.X = sla.cho_solve(cho, S[np.ix_(r, c)])
        self.y = sla.cho_solve(cho, f[r])
        A = S[np.ix_(c, c)] - S[np.ix_(c, r)] @ self.X
        self.A = 0.5 * (A + A.T)
        self.b = f[c] - S[np.ix_(c, r)] @ self.y
        self._choA = None

    def expand(self, u_c) -> np.ndarray:
        """The full U from its contact values (Dirichlet values, rest eliminated)."""
        u = np.zeros(self.n)
        u[self.fixed] = self.values
        u[self.c] = u_c
        u[self.r] = self.y - self.X @ u_c
        return u

    def solve(self, load_c) -> np.ndarray:
        """Contact values of the Neumann problem A u_c = b + load_c (the Cholesky factor
        of A once; LAPACK potrs directly - what scipy's cho_solve calls, without its
        per-call checks)."""
        if self._choA is None:
            self._choA = sla.cho_factor(self.A)
            self._potrs = sla.get_lapack_funcs("potrs", (self._choA[0],))
        rhs = np.asarray(self.b + load_c, dtype=float)
        if rhs.shape != self.b.shape or not np.isfinite(rhs).all():
            raise ValueError(f"load_c must be a finite vector of shape {self.b.shape}")
        if rhs.size == 0:
            return rhs.copy()
        x, info = self._potrs(self._choA[0], rhs, lower=self._choA[1])
        if info != 0:
            raise ValueError(f"illegal value in argument {-info} of potrs")
        return x

    def reaction(self, u_c) -> np.ndarray:
        """(S U - L) on the contact dofs (the residual functional, Algorithm 4.3 step 5)."""
        return self.A @ u_c - self.b


def ray_gap(points, normals, mesh: BoundaryMesh, label: str) -> np.ndarray:
    """Distance g_j >= ... from ``points[j]`` along ``normals[j]`` to the elements of
    ``mesh`` labelled ``label`` (first hit, possibly negative = overlap); +inf where the
    ray misses them (no constraint there)."""
    els = np.flatnonzero(mesh.labels == label)
    a, d = mesh.a[els], mesh.b[els] - mesh.a[els]
    x, nn = np.asarray(points, float), np.asarray(normals, float)
    # x + tau n = a + sigma d  ->  [n, -d] (tau, sigma) = a - x
    det = nn[:, None, 0] * (-d[None, :, 1]) - nn[:, None, 1] * (-d[None, :, 0])
    rx, ry = a[None, :, 0] - x[:, None, 0], a[None, :, 1] - x[:, None, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = (rx * (-d[None, :, 1]) - ry * (-d[None, :, 0])) / det
        sig = (nn[:, None, 0] * ry - nn[:, None, 1] * rx) / det
    ok = (np.abs(det) > 1e-14) & (sig >= -1e-12) & (sig <= 1 + 1e-12)
    tau = np.where(ok, tau, np.inf)
    k = np.argmin(np.abs(tau), axis=1)
    return tau[np.arange(len(x)), k]


# --------------------------------------------------------------------------- problem
@dataclass
class MortarSolution:
    """Result of a mortar contact solve: full boundary displacements U1, U2, the
    friction multiplier lambda and the transferred fields Q (X^1) and P (X^2 dual),
    the frame quantities at the contact nodes of body 1 and the SolverInfo."""

    U1: np.ndarray
    U2: np.ndarray
    lam: np.ndarray
    Q: np.ndarray
    P: np.ndarray
    x: np.ndarray
    info: SolverInfo
    extra: dict = field(default_factory=dict)


def _check_omega(name, w):
    if not (np.isfinite(w) and 0.0 < w <= 1.0):
        raise ValueError(f"{name} must lie in (0, 1], got {w!r}")


def _check_pos(name, v):
    if not (np.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be positive, got {v!r}")


class MortarContact:
    """Two BE bodies in frictional contact through a mortar coupling (Section 4.3.3).

    Parameters
    ----------
    bem1, bem2 : LameBEM of body 1 (contact / mortar side) and body 2 (Neumann side)
    dirichlet1, dirichlet2 : (label, (Ux, Uy)) prescribed displacement on that label
    F : given friction bound (Tresca), >= 0
    normal : callable (m, 2) points -> (m, 2) outward unit normals of body 1 on
        Gamma^1_C (default: the mean of the adjacent element normals)
    label : contact label of both meshes; axis : pairing parameter of the mortar
    gap : callable (m, 2) points of Gamma^1_C -> (m,) initial gap (default: the
        distance along n to Gamma^2_C, :func:`ray_gap`)
    test_space : "full" (test with all of X^1_hp, Phi^1 = D^-1 B Phi^2 as printed in
        (4.87)) or "mortar" (the mortar space M^1_hp of (4.49) with end-point matching,
        (4.50)); see :class:`hpfebe.coupling.mortar.MortarProjection`
    """

    def __init__(self, bem1: LameBEM, bem2: LameBEM, dirichlet1, dirichlet2, F: float,
                 normal=None, label: str = "C", axis=(1.0, 0.0), test_space: str = "full",
                 gap=None):
        if not np.isfinite(F) or F < 0:
            raise ValueError(f"F must be >= 0, got {F!r}")
        self.bem1, self.bem2, self.F = bem1, bem2, float(F)
        self.mortar = MortarProjection(bem1.mesh, bem2.mesh, label, label, axis,
                                       bem1.V_space, bem2.V_space, test_space)
        m = self.mortar
        self.c1 = np.column_stack([2 * m.dofs1, 2 * m.dofs1 + 1]).ravel()
        self.c2 = np.column_stack([2 * m.dofs2, 2 * m.dofs2 + 1]).ravel()
        self.body1 = self._condense(bem1, dirichlet1, self.c1, "dirichlet1")
        self.body2 = self._condense(bem2, dirichlet2, self.c2, "dirichlet2")
        if self.body1.cpos.size != self.c1.size:
            raise ValueError("dirichlet1: the contact nodes of body 1 must not be Dirichlet "
                             "nodes")
        nc = m.dofs1.size
        self.nc = nc
        self.points = self._node_points(bem1, m.dofs1)
        nrm = self._default_normals(bem1.V_space, m.dofs1, label) if normal is None else \
            np.asarray(normal(self.points), dtype=float)
        if nrm.shape != (nc, 2):
            raise ValueError(f"normal must return ({nc}, 2) normals, got {nrm.shape}")
        self._normal_fn = normal
        self._gap_fn = gap
        self._set_frame(nrm)
        self.gap = self.gap_at(self.points, self.n)
        self.w = self._lobatto_weights(bem1.mesh, bem1.V_space, m.dofs1, label)

    def _set_frame(self, normals):
        """The frame (n, t) at the nc contact nodes, the rotation x = R u_c = (U_n, U_t)
        and body 1's condensed quadratic program in it: A = R A_1 R^T (symmetrised
        against round-off), b = R b_1."""
        nc = self.nc
        self.n = normals / np.linalg.norm(normals, axis=1)[:, None]
        self.t = np.column_stack([-self.n[:, 1], self.n[:, 0]])
        R = np.zeros((2 * nc, 2 * nc))
        j = np.arange(nc)
        R[j, 2 * j], R[j, 2 * j + 1] = self.n[:, 0], self.n[:, 1]
        R[nc + j, 2 * j], R[nc + j, 2 * j + 1] = self.t[:, 0], self.t[:, 1]
        self.R = R
        self.A = R @ self.body1.A @ R.T
        self.A = 0.5 * (self.A + self.A.T)
        self.b = R @ self.body1.b

    # ---------------------------------------------------------------- set-up helpers
    @staticmethod
    def _condense(bem, dirichlet, contact, name):
        try:
            label, value = dirichlet
            value = np.asarray(value, dtype=float).reshape(2)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be (label, (Ux, Uy)), got {dirichlet!r}") from None
        if not np.any(bem.mesh.labels == label):
            raise ValueError(f"{name}: no element labelled {label!r}")
        d = bem.V_space.dofs_on(label)
        fixed = np.column_stack([2 * d, 2 * d + 1]).ravel()
        vals = np.tile(value, d.size)
        return CondensedBody(bem.S_hat, fixed, vals, contact)

    @staticmethod
    def _node_points(bem, dofs):
        mesh, sp_ = bem.mesh, bem.V_space
        xy = np.zeros((sp_.ndof, 2))
        for p in np.unique(mesh.degrees):
            els = np.flatnonzero(mesh.degrees == p)
            xg, _ = gauss_lobatto(int(p) + 1)
            xy[sp_.elem_dofs[els, :int(p) + 1]] = mesh.points(els[:, None], xg[None, :])
        return xy[dofs]

    @staticmethod
    def _default_normals(space, dofs, label):
        """Sum of the outward normals of the contact elements sharing each node."""
        mesh = space.mesh
        acc = np.zeros((space.ndof, 2))
        els = np.flatnonzero(mesh.labels == label)
        d = space.elem_dofs[els]
        for k in range(d.shape[1]):                   # local basis index (<= p + 1)
            ok = d[:, k] >= 0
            np.add.at(acc, d[ok, k], mesh.normals[els[ok]])
        return acc[dofs]

    @staticmethod
    def _lobatto_weights(mesh, space, dofs, label):
        """w_j = int phi_j ds by the Gauss-Lobatto rule of each contact element."""
        w = np.zeros(space.ndof)
        els = np.flatnonzero(mesh.labels == label)
        for p in np.unique(mesh.degrees[els]):
            e = els[mesh.degrees[els] == p]
            _, wg = gauss_lobatto(int(p) + 1)
            d = space.elem_dofs[e, :int(p) + 1]
            np.add.at(w, d.ravel(), (0.5 * mesh.lengths[e][:, None] * wg[None, :]).ravel())
        return w[dofs]

    def gap_at(self, x, normals) -> np.ndarray:
        """Initial gap at points x of Gamma^1_C: the scene's gap function, or the distance
        along ``normals`` to Gamma^2_C (+inf where the ray misses it)."""
        if self._gap_fn is None:
            return ray_gap(x, normals, self.bem2.mesh, "C")
        g = np.asarray(self._gap_fn(np.asarray(x, dtype=float)), dtype=float)
        if g.shape != (len(x),) or np.any(np.isnan(g)):
            raise ValueError(f"gap must return {len(x)} finite values, got shape {g.shape}")
        return g

    def _normal(self, x) -> np.ndarray:
        """Unit normal of body 1 at points x of Gamma^1_C (the scene's, or the element's)."""
        if self._normal_fn is not None:
            n = np.asarray(self._normal_fn(x), dtype=float)
        else:
            e, _ = self.bem1.mesh.locate(x)
            n = self.bem1.mesh.normals[e]
        return n / np.linalg.norm(n, axis=1)[:, None]

    # ---------------------------------------------------------------- Uzawa step
    @property
    def rho_crit(self) -> float:
        """Largest convergent Uzawa step of Theorem 3.1.8 for the linear (all nodes in
        contact, sticking) model: lambda <- lambda + rho F^2 W^(1/2) C_tt W^(1/2) ...
        contracts iff rho < 2 / (F^2 lambda_max(W^(1/2) C_tt W^(1/2))), C = A^-1 the
        condensed compliance at the contact nodes (tangential block), W = diag(w)."""
        if self.F == 0.0:
            return np.inf
        if not hasattr(self, "_rho_crit"):
            C = np.linalg.inv(self.A)[self.nc:, self.nc:]
            sw = np.sqrt(self.w)
            T = sw[:, None] * C * sw[None, :]
            self._rho_crit = 2.0 / (self.F ** 2 * np.linalg.eigvalsh(0.5 * (T + T.T))[-1])
        return float(self._rho_crit)

    def _rho_bound(self, rho: float, relative: bool, bound) -> float:
        """The Uzawa step for a nodal friction bound s (Coulomb in DtN): rho itself, or
        rho / (s-weighted largest eigenvalue) as :attr:`rho_crit` with F -> diag(s)."""
        if not relative:
            return float(rho)
        if not hasattr(self, "_Ctt"):
            self._Ctt = np.linalg.inv(self.A)[self.nc:, self.nc:]
        sw = np.sqrt(self.w) * np.asarray(bound, dtype=float)
        T = sw[:, None] * self._Ctt * sw[None, :]
        lmax = np.linalg.eigvalsh(0.5 * (T + T.T))[-1]
        return float(rho) / lmax if lmax > 0 else float(rho)

    def rho_step(self, rho: float, relative: bool) -> float:
        """The Uzawa step used: ``rho`` itself, or rho * rho_crit / 2 when ``relative``
        (rho = 1 is then the step with the fastest contraction of the stiffest mode)."""
        _check_pos("rho", rho)
        if not relative or self.F == 0.0:
            return float(rho)
        return float(rho) * 0.5 * self.rho_crit

    # ---------------------------------------------------------------- inner solvers
    def frame(self, v) -> tuple[np.ndarray, np.ndarray]:
        """Normal and tangential components at the contact nodes of an interleaved
        vector on the contact dofs of body 1."""
        v = np.asarray(v).reshape(self.nc, 2)
        n, t = self.n, self.t        # (two terms: the same sums as np.sum(v * n, axis=1))
        return v[:, 0] * n[:, 0] + v[:, 1] * n[:, 1], v[:, 0] * t[:, 0] + v[:, 1] * t[:, 1]

    def contact_qp(self, Q, lam, x0=None, tol: float = 1e-11, bound=None):
        """Algorithm 4.4 step 2: frictionless contact of body 1 against the obstacle Q
        with the friction load F w lambda (``bound``: a nodal friction bound replacing F,
        e.g. mu_f p_n), by projected CG.  Returns (x, info)."""
        Fw, upper = self._qp_data(Q, bound)
        return self._qp(Fw, upper, np.asarray(lam, dtype=float), x0, tol)

    def _qp_data(self, Q, bound):
        """The pieces of the contact QP fixed for one obstacle Q and one friction bound:
        the friction weights F w (or s w) and the upper bounds (g + Q_n on U_n, none on
        U_t)."""
        Qn, _ = self.frame(Q)
        F = self.F if bound is None else np.asarray(bound, dtype=float)
        upper = np.concatenate([self.gap + Qn, np.full(self.nc, np.inf)])
        return F * self.w, upper

    def _qp(self, Fw, upper, lam, x0, tol):
        """The contact QP with the friction load (F w) lambda (A, b of body 1 in the
        node frames, read at every call: subclasses may replace them; compiled
        projected CG without re-validating the shapes)."""
        A, b, nA, _ = self._qp_matrices()
        rhs = b.copy()
        rhs[self.nc:] -= Fw * lam
        x = np.minimum(np.zeros(b.size) if x0 is None else np.asarray(x0, dtype=float),
                       upper)
        max_iter = 20 * b.size + 100
        res = np.empty(max_iter + 1)
        status, steps, nres = _polyak_core(A, rhs, upper, x, float(tol), max_iter, res, nA)
        return x, _pcg_info(status, steps, nres, res, int(np.count_nonzero(x >= upper)))

    def _qp_matrices(self):
        """(A, b, :func:`_frobenius_bound` of A, a residual buffer) of the contact QP as
        contiguous float arrays, built once per (A, b) pair (``self.A``, ``self.b`` are
        read at every call: subclasses may replace them)."""
        c = self.__dict__.get("_qp_cache")
        if c is None or c[0] is not self.A or c[1] is not self.b:
            A = np.ascontiguousarray(self.A, dtype=float)
            b = np.ascontiguousarray(self.b, dtype=float)
            n = b.size
            if b.ndim != 1 or A.shape != (n, n):
                raise ValueError(f"A must be ({n}, {n}), got {A.shape}")
            c = self.__dict__["_qp_cache"] = (self.A, self.b, A, b, _frobenius_bound(A),
                                              np.empty(20 * n + 101))
        return c[2:]

    def uzawa(self, Q, rho: float = 1.0, tol: float = 1e-6, max_iter: int = 2000,
              lam0=None, x0=None, cg_tol: float = 1e-11, bound=None):
        """Algorithm 4.4 (Uzawa for given friction) against the obstacle Q:
        lambda_{m+1} = P_Lambda(lambda_m + rho F (U_t - Q_t)), stop when
        ||lambda_m - lambda_{m-1}|| <= TOL_U ||lambda_m||.  Returns (x, lambda, info);
        x = (U_n, U_t) at the contact nodes for the returned lambda.  ``bound``: nodal
        friction bound s_j replacing F (lambda_j += rho s_j (U_t - Q_t)_j).  The QP
        data fixed by Q and the bound are built once per call; each iteration is one
        compiled call (:func:`_uzawa_step`: the QP and the projection step).
        ``info.counts``: the QP solves and their CG steps in all; ``info.steps`` holds a
        QP's SolverInfo only where it failed (that ends the iteration) - one SolverInfo
        per iteration kept for hundreds of thousands of iterations cost a quarter of the
        run time in Python's garbage collector (measured on Table 4.1's capped cells)."""
        _check_pos("rho", rho)
        F = self.F if bound is None else np.asarray(bound, dtype=float)
        _, Qt = self.frame(Q)
        lam0 = np.zeros(self.nc) if lam0 is None else np.asarray(lam0, dtype=float)
        Fw, upper = self._qp_data(Q, bound)
        nc = self.nc
        state = {"x": x0}
        A, b, nA, res = self._qp_matrices()
        n, max_cg = b.size, res.size - 1
        if lam0.shape != (nc,):
            raise ValueError(f"lam0 must have shape ({nc},), got {lam0.shape}")
        if x0 is not None and np.shape(x0) != (n,):
            raise ValueError(f"x0 must have shape ({n},), got {np.shape(x0)}")
        args = (A, b, _per_node(Fw, nc), _per_node(rho * F, nc), _per_node(Qt, nc),
                _per_node(upper, n))
        tol_cg = float(cg_tol)
        cg = [0, 0]                                      # QP solves, CG steps

        def update(lam):
            x = np.zeros(n) if state["x"] is None else np.array(state["x"], dtype=float)
            lam_new = np.empty(nc)
            status, steps, nres, active = _uzawa_step(
                *args, np.ascontiguousarray(lam, dtype=float), x, tol_cg, max_cg, res, nA,
                lam_new)
            state["x"] = x
            cg[0] += 1
            cg[1] += steps
            if status != 1:                  # a failed QP ends the iteration with its info
                return lam_new, _pcg_info(status, steps, nres, res, active)
            return lam_new

        lam, info = fixed_point(update, lam0, tol, max_iter, norm=2)
        info.counts = dict(qp_solves=cg[0], cg_steps=cg[1])
        x, qinfo = self._qp(Fw, upper, lam, state["x"], cg_tol)
        if not qinfo.converged and info.converged:
            info.converged, info.reason = False, f"final QP: {qinfo.reason}"
        return x, lam, info

    # ---------------------------------------------------------------- DtN
    def dtn(self, omega_D: float, omega_N: float, rho: float = 1.0, tol: float = 1e-6,
            tol_U: float = 1e-6, max_iter: int = 200, max_uzawa: int = 2000,
            divergence: float = 1e6, rho_relative: bool = True,
            aitken: bool = False, friction: str = "tresca",
            transfer: str = "functional") -> MortarSolution:
        """Algorithm 4.3 (Dirichlet-to-Neumann) with damping omega_D, omega_N in (0, 1]:

        2. S2 U2 = L2 - P_k (Neumann problem of body 2; P_k = the transferred contact
           force on body 1, so body 2 carries -P_k),
        3. Q_k = (1 - omega_D) Q_{k-1} + omega_D D^-1 B U2,
        4. contact problem of body 1 against Q_k (Uzawa, Algorithm 4.4),
        5. R1 = S1 U1 - L1 on the contact dofs (the contact force on body 1),
        6. P_{k+1} = (1 - omega_N) P_k + omega_N B^T D^-T R1,
        7. stop if ||P_{k+1} - P_k|| <= TOL ||P_{k+1}|| (:func:`fixed_point`).

        The Uzawa multiplier and the QP solution are warm-started from the previous DtN
        iteration.  Non-convergence (cap, growth, NaN) is reported in ``info.reason``.
        ``rho_relative``: the Uzawa step is rho * rho_crit / 2 (:meth:`rho_step`).

        ``transfer``: "functional" - R1 and P are functionals (residual vectors), step 6
        as above (consistent: action = reaction); "function" - the literal reading of
        steps 5, 6 and (4.88) with R1 in X^1_hp and P in X^2_hp *functions*: R1 = D^-1 r1
        (the L2 Riesz representative of the residual r1), P_k+1 = (1 - omega_N) P_k +
        omega_N B^T D^-T R1 (coefficients) and the load of step 2 <P_k, W^2> = M2 P_k.
        ``friction``: "tresca" - the bound F of j (given friction, (4.55)); "coulomb" -
        the nodal bound F p_n with p_n = max(0, -R1_n / w) of the previous DtN iteration
        (0 in the first one).

        ``aitken`` (beyond the thesis): step 6 with Aitken's dynamic relaxation of the
        Neumann damping, P_k+1 = P_k + w_k r_k with r_k = B^T D^-T R1 - P_k,
        w_k = -w_k-1 (r_k-1 . (r_k - r_k-1)) / |r_k - r_k-1|^2 (Irons-Tuck / Kuettler-Wall),
        w_1 = omega_N; omega_D damping of step 3 as given."""
        _check_omega("omega_D", omega_D)
        _check_omega("omega_N", omega_N)
        if friction not in ("tresca", "coulomb"):
            raise ValueError(f"friction must be 'tresca' or 'coulomb', got {friction!r}")
        if transfer not in ("functional", "function"):
            raise ValueError(f"transfer must be 'functional' or 'function', got "
                             f"{transfer!r}")
        rho_in = rho
        rho = self.rho_step(rho, rho_relative)
        m, b2 = self.mortar, self.body2
        st = dict(Q=np.zeros(2 * self.nc), lam=np.zeros(self.nc), x=None, bound=None)
        load2 = m.pair2 if transfer == "function" else (lambda P: P)
        to_P = (lambda R1: m.adjoint(m.riesz(R1))) if transfer == "function" else m.adjoint

        def neumann(P):
            u2c = b2.solve(-load2(P)[b2.cpos])
            return u2c, b2.expand(u2c)[self.c2]

        st.update(r=None, w=float(omega_N))

        def update(P):
            _, u2 = neumann(P)
            Q = (1.0 - omega_D) * st["Q"] + omega_D * m.project(u2)
            rho_k = rho if st["bound"] is None else self._rho_bound(rho_in, rho_relative,
                                                                     st["bound"])
            x, lam, info = self.uzawa(Q, rho_k, tol_U, max_uzawa, st["lam"], st["x"],
                                      bound=st["bound"])
            st.update(Q=Q, lam=lam, x=x)
            R1 = self.body1.reaction(self.R.T @ x)
            if friction == "coulomb":
                st["bound"] = self.F * np.maximum(0.0, -self.frame(R1)[0] / self.w)
            r = to_P(R1) - P
            if aitken and st["r"] is not None:
                dr = r - st["r"]
                den = dr @ dr
                if den > 0:
                    st["w"] = float(np.clip(-st["w"] * (st["r"] @ dr) / den, 1e-3, 2.0))
            st["r"] = r
            return P + (st["w"] if aitken else omega_N) * r, info

        P, info = fixed_point(update, np.zeros(self.c2.size), tol, max_iter, norm=2,
                              divergence=divergence)
        u2c, _ = neumann(P)
        x = st["x"] if st["x"] is not None else np.zeros(2 * self.nc)
        U1 = self.body1.expand(self.R.T @ x)
        U2 = b2.expand(u2c)
        return MortarSolution(U1, U2, st["lam"], st["Q"], P, x, info)

    # ---------------------------------------------------------------- global Uzawa
    def _global_operators(self):
        """Dense pieces of Algorithm 4.5 on the contact dofs (built once): the lumped
        Gauss-Lobatto pairing Wk = diag(w) x I2 on Gamma^1_C, the traction transfer
        T2 = (B^T D^-T)(free rows of body 2) and H = A1^-1 + Pi A2^-1 Pi^T with
        Pi = D^-1 B (restricted to body 2's free contact dofs): the response of the
        relative displacement U1 - Pi U2 to the nodal traction P is -H Wk P."""
        if not hasattr(self, "_glob"):
            m, nc = self.mortar, self.nc
            Wk = np.repeat(self.w, 2)
            n2 = self.c2.size
            Pi = np.column_stack([m.project(e) for e in np.eye(n2)])[:, self.body2.cpos]
            T2 = Pi.T                                   # B^T D^-T restricted, = Pi^T
            H = np.linalg.inv(self.body1.A) + Pi @ np.linalg.solve(self.body2.A, Pi.T)
            sw = np.sqrt(Wk)
            G = sw[:, None] * H * sw[None, :]
            lam_max = np.linalg.eigvalsh(0.5 * (G + G.T))[-1]
            self._glob = dict(Wk=Wk, T2=T2, rho_crit=2.0 / lam_max, nc=nc, H=H, Pi=Pi)
        return self._glob

    def global_uzawa(self, rho: float = 1.0, tol: float = 1e-6, max_iter: int = 20000,
                     friction: str = "coulomb", mu_f: float = 0.1, rho_relative: bool = True,
                     divergence: float = 1e6) -> MortarSolution:
        """Algorithm 4.5 (Uzawa for the global problem): with the nodal contact traction
        P at the Gauss-Lobatto points of Gamma^1_C (force on body 1 = -P),

        2. S1 U1 = L1 - <P, .>_1 and S2 U2 = L2 + pi*<P, .>_1 (two Neumann problems),
        3. P <- Pi_M(P + rho (U1 - pi U2 - g n)) pointwise in the frame (n, t):
           P_n <- max(0, P_n + rho d_n), P_t <- clip(P_t + rho d_t, -b, b) with
           b = mu_f P_n (Coulomb) or b = F (Tresca, ``friction="tresca"``).

        <P, .>_1 is the Gauss-Lobatto (lumped) pairing on Gamma^1_C, the same as the
        friction functional of :meth:`contact_qp`, so that with Tresca friction this is
        the discrete problem DtN solves.  Step: rho * rho_crit / 2 if ``rho_relative``
        (rho_crit = 2 / lambda_max of the linear response, Theorem 3.1.8).  Stopping:
        :func:`fixed_point` (relative increment of P, at least 3 iterations)."""
        if friction not in ("coulomb", "tresca"):
            raise ValueError(f"friction must be 'coulomb' or 'tresca', got {friction!r}")
        if not (np.isfinite(mu_f) and mu_f >= 0):
            raise ValueError(f"mu_f must be >= 0, got {mu_f!r}")
        _check_pos("rho", rho)
        g = self._global_operators()
        step = rho * 0.5 * g["rho_crit"] if rho_relative else float(rho)
        b1, b2, nc = self.body1, self.body2, self.nc
        gap = np.where(np.isfinite(self.gap), self.gap, 0.0)
        closed = np.isfinite(self.gap)

        def bodies(p):
            u1 = b1.solve(-g["Wk"] * p)
            u2c = b2.solve(g["T2"] @ (g["Wk"] * p))
            return u1, u2c

        def update(p):
            u1, u2c = bodies(p)
            d = u1 - self.mortar.project(b2.expand(u2c)[self.c2])
            dn, dt = self.frame(d)
            pn, pt = self.frame(p)
            pn = np.where(closed, np.maximum(0.0, pn + step * (dn - gap)), 0.0)
            bound = mu_f * pn if friction == "coulomb" else np.full(nc, self.F)
            pt = np.clip(pt + step * dt, -bound, bound)
            return (pn[:, None] * self.n + pt[:, None] * self.t).ravel()

        P, info = fixed_point(update, np.zeros(2 * nc), tol, max_iter, norm=2,
                              divergence=divergence, min_iter=3)
        info.counts = dict(rho=step, rho_crit=g["rho_crit"])
        return self._state(P, info, friction, mu_f)

    def _state(self, P, info, friction, mu_f) -> MortarSolution:
        """Displacements of the nodal contact traction P (the two Neumann problems)."""
        g = self._global_operators()
        b1, b2, nc = self.body1, self.body2, self.nc
        u1 = b1.solve(-g["Wk"] * P)
        u2c = b2.solve(g["T2"] @ (g["Wk"] * P))
        Q = self.mortar.project(b2.expand(u2c)[self.c2])
        pn, pt = self.frame(P)
        bound = mu_f * pn if friction == "coulomb" else np.full(nc, self.F)
        lam = np.divide(pt, bound, out=np.zeros(nc), where=bound > 0)
        return MortarSolution(b1.expand(u1), b2.expand(u2c), lam, Q, P,
                              self.R @ u1, info, extra=dict(pn=pn, pt=pt))

    # ---------------------------------------------------------------- semismooth Newton
    def semismooth_newton(self, tol: float = 1e-10, max_iter: int = 100,
                          friction: str = "coulomb", mu_f: float = 0.1) -> MortarSolution:
        """Monolithic semismooth Newton (primal-dual active set) for the discrete problem
        of Algorithm 4.5 (beyond the thesis).  The displacements are linear in the nodal
        traction P, d(P) = U1 - pi U2 = d0 - H Wk P (:meth:`_global_operators`); in the
        node frames y = (P_n, P_t) it solves the complementarity functions

            P_n - max(0, z_n) = 0,   P_t - clip(z_t, -b, b) = 0,
            z_n = P_n + c (d_n - g),  z_t = P_t + c d_t,  b = mu_f max(0, z_n) or F,

        with c = rho_crit / 2, by :func:`hpfebe.solvers.nonlinear.newton` (line search on
        1/2 |F|^2, cycling detection on the active/stick pattern)."""
        from ..solvers import Iterate, newton

        if friction not in ("coulomb", "tresca"):
            raise ValueError(f"friction must be 'coulomb' or 'tresca', got {friction!r}")
        if not (np.isfinite(mu_f) and mu_f >= 0):
            raise ValueError(f"mu_f must be >= 0, got {mu_f!r}")
        g = self._global_operators()
        nc, R = self.nc, self.R
        c = 0.5 * g["rho_crit"]
        b1, b2 = self.body1, self.body2
        d0 = R @ (b1.solve(np.zeros(2 * nc)) - g["Pi"] @ b2.solve(np.zeros(b2.cpos.size)))
        G = R @ (g["H"] * g["Wk"][None, :]) @ R.T          # d(local) = d0 - G y
        closed = np.isfinite(self.gap)
        gap = np.where(closed, self.gap, 0.0)
        eye = np.eye(2 * nc)
        scale = max(float(np.abs(c * d0).max()), 1e-300)

        class Problem:
            def evaluate(_, y):
                d = d0 - G @ y
                zn = np.where(closed, y[:nc] + c * (d[:nc] - gap), -1.0)
                zt = y[nc:] + c * d[nc:]
                bnd = mu_f * np.maximum(0.0, zn) if friction == "coulomb" else \
                    np.full(nc, self.F)
                Fr = np.concatenate([y[:nc] - np.maximum(0.0, zn),
                                     y[nc:] - np.clip(zt, -bnd, bnd)])
                act, stick = zn > 0, np.abs(zt) < bnd
                return Iterate(y, Fr, 0.5 * float(Fr @ Fr), scale,
                               key=(act.tobytes(), stick.tobytes()),
                               data=(act, stick, np.sign(zt)))

            def step(_, it):
                act, stick, sg = it.data
                J = eye.copy()
                rows_n = np.flatnonzero(act)
                J[rows_n] = c * G[rows_n]
                rows_t = nc + np.flatnonzero(stick)
                J[rows_t] = c * G[rows_t]
                if friction == "coulomb":
                    slip = np.flatnonzero(~stick & act)
                    # d b / d y = mu_f (e_n - c G[n, :]) on slipping, active nodes
                    J[nc + slip] -= (sg[slip] * mu_f)[:, None] * (eye[slip] - c * G[slip])
                try:
                    return np.linalg.solve(J, -it.residual)
                except np.linalg.LinAlgError as e:
                    raise SingularStep(f"singular Newton matrix: {e}") from None

            def slope(_, it, dx):
                return -2.0 * it.merit

        it, info = newton(Problem(), np.zeros(2 * nc), tol, max_iter, norm=2)
        P = R.T @ it.x
        info.counts = dict(c=c)
        return self._state(P, info, friction, mu_f)

    # ---------------------------------------------------------------- post-processing
    def norm_W(self, U1, U2) -> float:
        """||U||_W = (<W U1, U1> + <W U2, U2>)^(1/2) (Section 4.3.4)."""
        return float(np.sqrt(U1 @ (self.bem1.W @ U1) + U2 @ (self.bem2.W @ U2)))

    def tresca_residual(self, sol: MortarSolution) -> dict:
        """Tresca conditions at the Gauss-Lobatto points: max |lambda| - 1, the largest
        slip where |lambda| < 1 (must vanish) and the largest violation of
        lambda s = |s| (scaled by max |s|)."""
        _, Qt = self.frame(sol.Q)
        s = sol.x[self.nc:] - Qt
        inner = np.abs(sol.lam) < 1.0 - 1e-9
        sc = max(np.abs(s).max(), 1e-300)
        return dict(lam_excess=float(np.abs(sol.lam).max() - 1.0),
                    stick_slip=float(np.abs(s[inner]).max() if inner.any() else 0.0),
                    complementarity=float(np.abs(sol.lam * s - np.abs(s)).max() / sc),
                    slip_scale=float(sc))


# --------------------------------------------------------------------------- scene
def model_meshes(n1: int = 16, n2: int = 12, p1: int = 2, p2: int = 2,
                 radius: float = 5.05, L: float = 2.0, side_depth: float = 2.0,
                 geometry: str = "arc"):
    """Boundary meshes of the model problem of Section 4.3.4 (see :func:`model_problem`)
    and the normal of Gamma^1_C: (mesh1, mesh2, normal).

    ``geometry``: "arc" - Gamma^1_C is the polygon of the circular arc (nodes on the
    circle), normal = radial direction; "flat" - body 1 is the rectangle [-1,1] x [0,2],
    Gamma^1_C = [-1,1] x {0} (Section 4.3.1: Gamma_C a straight segment, the bodies
    initially in contact) and the arc enters only through the initial gap
    :func:`model_gap` measured along the normal (0, -1) of Gamma^1_C.

    ``side_depth``: Gamma^2_D on the vertical sides of body 2 is {-1,1} x [-side_depth, 0]
    (2 = the whole sides; the thesis prints {-1,1} x [-1,0], i.e. 1, with
    Gamma^2_N = empty); below it the sides are traction free (label "N")."""
    for name, v in (("n1", n1), ("n2", n2), ("p1", p1), ("p2", p2)):
        if int(v) != v or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
    if radius <= 1.0:
        raise ValueError(f"radius must exceed 1, got {radius!r}")
    if geometry not in ("arc", "flat"):
        raise ValueError(f"geometry must be 'arc' or 'flat', got {geometry!r}")
    yc = radius                                       # centre (0, R): arc through (0, 0)
    half = np.arcsin(1.0 / radius)
    ang = np.linspace(-half, half, int(n1) + 1)
    arc = np.column_stack([radius * np.sin(ang), yc - radius * np.cos(ang)])
    h1, h2 = L / n1, L / n2
    top = float(arc[0, 1])
    nside = int(np.ceil((2.0 - top) / h1 - 1e-9))
    verts = np.vstack([arc, [[1.0, 2.0], [-1.0, 2.0]]])
    n_sides = [1] * int(n1) + [nside, int(np.ceil(2.0 / h1 - 1e-9)), nside]
    labels = ["C"] * int(n1) + ["N", "D", "N"]
    if geometry == "flat":
        ns = int(np.ceil(2.0 / h1 - 1e-9))
        verts = np.array([[-1.0, 0.0], [1.0, 0.0], [1.0, 2.0], [-1.0, 2.0]])
        n_sides, labels = [int(n1), ns, ns, ns], ["C", "N", "D", "N"]
    mesh1 = BoundaryMesh.polygon(verts, n=n_sides, labels=labels, p=int(p1))
    if not (np.isfinite(side_depth) and 0.0 < side_depth <= 2.0):
        raise ValueError(f"side_depth must lie in (0, 2], got {side_depth!r}")
    k2 = int(np.ceil(2.0 / h2 - 1e-9))
    if side_depth >= 2.0:
        mesh2 = BoundaryMesh.polygon([(-1, -2), (1, -2), (1, 0), (-1, 0)],
                                     n=[k2, k2, int(n2), k2], labels=["D", "D", "C", "D"],
                                     p=int(p2))
    else:
        kd = int(np.ceil(side_depth / h2 - 1e-9))
        kn = int(np.ceil((2.0 - side_depth) / h2 - 1e-9))
        d = float(side_depth)
        mesh2 = BoundaryMesh.polygon([(-1, -2), (1, -2), (1, -d), (1, 0), (-1, 0), (-1, -d)],
                                     n=[k2, kn, kd, int(n2), kd, kn],
                                     labels=["D", "N", "D", "C", "D", "N"], p=int(p2))

    def normal(x):
        d = np.asarray(x, dtype=float) - np.array([0.0, yc])
        return d / np.linalg.norm(d, axis=1)[:, None]

    def normal_flat(x):
        return np.tile([0.0, -1.0], (len(x), 1))

    return mesh1, mesh2, (normal if geometry == "arc" else normal_flat)


def model_gap(radius: float = 5.05):
    """The initial gap of the "flat" scene: the height of the arc through (-1, 0.1),
    (0, 0), (1, 0.1) above Gamma_C, g(x) = R - (R^2 - x^2)^(1/2)."""
    if radius <= 1.0:
        raise ValueError(f"radius must exceed 1, got {radius!r}")

    def gap(x):
        x = np.asarray(x, dtype=float)
        return radius - np.sqrt(radius ** 2 - np.minimum(x[:, 0] ** 2, radius ** 2))

    return gap


def contact_from_meshes(mesh1, mesh2, normal, E: float = 266926.0, nu: float = 0.29,
                        F: float = 0.1, u_top=(0.0, -0.09),
                        plane: str = "strain", test_space: str = "full",
                        gap=None) -> MortarContact:
    """The model problem's boundary conditions on given meshes (e.g. adaptive ones);
    ``gap``: the initial gap function (None: measured along the normal to mesh2)."""
    bem1, bem2 = LameBEM(mesh1, E, nu, plane), LameBEM(mesh2, E, nu, plane)
    return _model_contact(bem1, bem2, normal, F, u_top, test_space, gap)


def _model_contact(bem1, bem2, normal, F, u_top, test_space, gap) -> MortarContact:
    """The model problem's boundary conditions on the bodies ``bem1``, ``bem2``."""
    return MortarContact(bem1, bem2, ("D", u_top), ("D", (0.0, 0.0)), F, normal=normal,
                         test_space=test_space, gap=gap)


def model_problem(n1: int = 16, n2: int = 12, p1: int = 2, p2: int = 2,
                  E: float = 266926.0, nu: float = 0.29, F: float = 0.1,
                  u_top=(0.0, -0.09), radius: float = 5.05, plane: str = "strain",
                  L: float = 2.0, side_depth: float = 2.0,
                  test_space: str = "full", geometry: str = "arc",
                  bem_cache: dict | None = None, gap=None) -> MortarContact:
    """The model problem of Section 4.3.4 (thesis lines 19474-19530): body 1 bounded by
    Gamma^1_D = [-1,1] x {2} (U = u_top), Gamma^1_N = {-1,1} x [0.1, 2] and the arc
    Gamma^1_C of radius ``radius`` through (-1, 0.1), (0, 0), (1, 0.1); body 2 =
    [-1,1] x [-2,0] with Gamma^2_C = [-1,1] x {0} and Gamma^2_D = the rest (U = 0).
    Meshes: ``n1`` elements on Gamma^1_C (h1 = L / n1, equal angles), ``n2`` on
    Gamma^2_C (h2 = L / n2), the other sides with ceil(length / h) elements; degrees
    p1, p2 everywhere.  Normals of Gamma^1_C: the radial direction of the circle; gap
    along it.  ``geometry="flat"``: Gamma^1_C straight, the arc only as initial gap
    (:func:`model_meshes`); ``side_depth``: Dirichlet part of body 2's sides;
    ``test_space``: of the mortar projection (:class:`MortarContact`).  ``bem_cache``: a
    dict keeping the BE bodies (and their assembled operators) across calls - body 1
    depends only on (n1, p1, radius, L, geometry), body 2 on (n2, p2, L, side_depth), so
    a sweep over degree pairs assembles each body once.  ``gap``: an initial gap function
    replacing the scene's (e.g. zero: Algorithm 4.5's step 3 as printed, without g)."""
    if not np.isfinite(F) or F < 0:
        raise ValueError(f"F must be >= 0, got {F!r}")
    mesh1, mesh2, normal = model_meshes(n1, n2, p1, p2, radius, L, side_depth, geometry)
    if gap is None and geometry == "flat":
        gap = model_gap(radius)
    if bem_cache is None:
        return contact_from_meshes(mesh1, mesh2, normal, E, nu, F, u_top, plane,
                                   test_space, gap)
    mat = (float(E), float(nu), plane)
    keys = ((1, int(n1), int(p1), float(radius), float(L), geometry) + mat,
            (2, int(n2), int(p2), float(L), float(side_depth)) + mat)
    bems = [bem_cache.get(k) or bem_cache.setdefault(k, LameBEM(m, E, nu, plane))
            for k, m in zip(keys, (mesh1, mesh2))]
    return _model_contact(*bems, normal, F, u_top, test_space, gap)
