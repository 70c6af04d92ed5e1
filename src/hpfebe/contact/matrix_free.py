"""Penalty contact with the compressed Lame operators, never applying S_hat (issue 27).

The penalty problem of :mod:`hpfebe.contact.penalty` (Section 3.2, (3.45)-(3.46) with
the Steklov-Poincare operator of Section 1.4, S_hat = W + B^T V^{-1} B, B = K + M/2),

    S_hat U + (1/eps) int_{Gamma_C} (U_n - g_h)_+ v_n ds = f,   U = U_D on Gamma_D,

is solved in its mixed form: psi = V^{-1} B U is a second unknown, so that

    W U + B^T psi + f_c(U) = f,     B U - V psi = 0,

and every semismooth Newton step solves the symmetric indefinite system

    [[W + C_eps, B^T], [B, -V]] [dU; dpsi] = -[r_1; r_2]          (free dofs of U)

by GMRES on the H-matrix operators (:mod:`hpfebe.bem.hmatrix`), preconditioned by a
sparse LU of the same block matrix built from the H-matrices' near-field blocks only
plus the penalty Jacobian C_eps (sparse, on the active set).  Applying S_hat instead
needs an inner CG solve with V per product (110-210 block-Jacobi iterations each; N =
4096 took 452 s); here each GMRES step is one product with each of W, B, B^T and V.

The positive part is integrated exactly for p = 1 (vectorised): g is replaced by its
nodal interpolant g_h, the penetration U_n - g_h is linear on each straight contact
element, its root splits the element, and 2-point Gauss rules on the positive piece
integrate (U_n - g_h)_+ v_n, its derivative and (U_n - g_h)_+^2 exactly (the same
discrete problem as ``solve_penalty``'s ``quadrature="exact"``).

Globalisation: once V psi = B U holds (after the first step), the mixed step is the
Newton step of the energy J(U) = 1/2 U^T S_hat U + 1/(2 eps) int (U_n - g_h)_+^2 - f^T U
and psi stays consistent along it, so S_hat (U + t dU) = (W U + B^T psi) + t (W dU +
B^T dpsi): an Armijo backtracking line search on J costs no extra operator product.

Converged only when the backward errors of the returned state (U, psi), recomputed by
fresh products with the compressed operators,

    ||r_1||_2 / (||f|| + ||W U + B^T psi|| + ||f_c(U)||)   (free dofs)   and
    ||B U - V psi||_2 / (||B U|| + ||V psi||),

are both <= tol.  The rigid modes are fixed by the Dirichlet side (U = U_D there).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit

from ..checks import array, choice, integer, real
from ..solvers import SolverInfo
from .mixed_precond import PrimalMultilevel

__all__ = ["MixedPenaltyResult", "PenaltyP1", "near_field", "solve_penalty_mixed"]

ARMIJO = 1e-4
MIN_STEP = 2.0 ** -30
PRECONDITIONERS = ("auto", "multilevel", "near_field")
# "auto": the near-field LU up to this many boundary elements, the multilevel one above.
# Measured (Hertz scene, p = 1, CPU s of the whole solve, near_field / multilevel):
# N = 128: 0.40 / 0.68, 256: 1.47 / 1.59, 512: 9.89 / 4.67, 1024: 51.5 / 11.0 (the
# near-field LU's GMRES iterations grow with N, the multilevel's stay nearly constant).
AUTO_NEAR_FIELD_MAX = 256
GAUSS2 = np.array([0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0)])


# ---------------------------------------------------------------------- contact terms
class PenaltyP1:
    """Exact penalty terms on the p = 1 contact elements ``elems`` of a mesh (module
    doc): nodal penetrations U_n - g_h at the element ends, force, Jacobian, energy."""

    def __init__(self, mesh, space, elems, gap):
        self.elems = np.asarray(elems, np.int64)
        if np.any(mesh.degrees[self.elems] != 1):
            raise ValueError("solve_penalty_mixed: the contact elements must have degree "
                             "p = 1 (the exact positive part is implemented for p = 1)")
        self.n = np.ascontiguousarray(mesh.normals[self.elems])
        self.L = np.ascontiguousarray(mesh.lengths[self.elems])
        self.a, self.b = mesh.a[self.elems], mesh.b[self.elems]
        self.dof = np.ascontiguousarray(space.elem_dofs[self.elems, :2])   # V_hp dofs
        g = np.column_stack([_gap(gap, self.a), _gap(gap, self.b)])
        self.g = g

    def penetration(self, U) -> np.ndarray:
        """(ne, 2): U_n - g_h at the start and end node of each contact element."""
        ux, uy = U[2 * self.dof], U[2 * self.dof + 1]
        return ux * self.n[:, :1] + uy * self.n[:, 1:] - self.g

    def pieces(self, U):
        """The positive piece [s0, s1] of each element (s in [0, 1]; s0 = s1 if none)."""
        w = self.penetration(U)
        wa, wb = w[:, 0], w[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.where(wa != wb, wa / (wa - wb), 0.0)
        s0 = np.where(wa > 0, 0.0, np.where(wb > 0, root, 0.0))
        s1 = np.where(wb > 0, 1.0, np.where(wa > 0, root, 0.0))
        s1 = np.maximum(s1, s0)
        return w, s0, s1

    def _points(self, U):
        w, s0, s1 = self.pieces(U)
        s = s0[:, None] + (s1 - s0)[:, None] * GAUSS2[None, :]          # (ne, 2)
        wq = 0.5 * (s1 - s0)[:, None] * self.L[:, None] * np.ones((1, 2))
        phi = (1.0 - s) * w[:, :1] + s * w[:, 1:]
        return s, wq, np.maximum(phi, 0.0), s1 > s0

    def terms(self, U, eps: float, ndofs: int):
        """(energy int phi_+^2 / (2 eps), force (1/eps) int phi_+ v_n, active mask)."""
        s, wq, phi, act = self._points(U)
        energy = float(np.sum(wq * phi ** 2)) / (2.0 * eps)
        N = np.stack([1.0 - s, s], axis=2)                               # (ne, q, node)
        c = np.einsum("eq,eqk->ek", wq * phi, N) / eps                   # (ne, node)
        f = np.zeros(ndofs)
        for comp in range(2):
            np.add.at(f, 2 * self.dof + comp, c * self.n[:, comp:comp + 1])
        return energy, f, act

    def jacobian(self, U, eps: float, ndofs: int) -> sp.csr_matrix:
        """(1/eps) int_{phi > 0} (v_n)(w_n): the Jacobian of the force (exact)."""
        s, wq, phi, act = self._points(U)
        e = np.flatnonzero(act)
        N = np.stack([1.0 - s[e], s[e]], axis=2)
        m = np.einsum("eq,eqk,eql->ekl", wq[e], N, N) / eps               # (ne, 2, 2)
        dofs = (2 * self.dof[e][:, :, None] + np.arange(2)[None, None, :]).reshape(-1, 4)
        nn = self.n[e]
        # entry (node k comp c, node l comp d) = m_kl n_c n_d
        vals = (m[:, :, None, :, None] * nn[:, None, :, None, None]
                * nn[:, None, None, None, :]).reshape(len(e), 4, 4)
        rows = np.repeat(dofs, 4, axis=1).ravel()
        cols = np.tile(dofs, (1, 4)).ravel()
        return sp.csr_matrix((vals.ravel(), (rows, cols)), shape=(ndofs, ndofs))

    def half_width(self, U, mesh=None):
        """(x_min, x_max) of the contact set {U_n > g_h} (exact roots), or None."""
        _, s0, s1 = self.pieces(U)
        act = s1 > s0
        if not act.any():
            return None
        xa = self.a[act, 0] + s0[act] * (self.b[act, 0] - self.a[act, 0])
        xb = self.a[act, 0] + s1[act] * (self.b[act, 0] - self.a[act, 0])
        return float(min(xa.min(), xb.min())), float(max(xa.max(), xb.max()))

    def vertical_force(self, U, eps: float) -> float:
        """F = int p (-n_y) ds: the upward force of the obstacle on the body."""
        s, wq, phi, _ = self._points(U)
        return float(np.sum(wq * phi * -self.n[:, 1:2])) / eps


def _gap(gap, pts):
    if callable(gap):
        g = np.asarray(gap(pts), dtype=float).reshape(-1)
        if g.shape != (len(pts),):
            raise ValueError(f"gap(x) must return one value per point, got shape {g.shape}"
                             f" for {len(pts)} points")
    else:
        g = np.full(len(pts), real("gap", gap))
    if not np.all(np.isfinite(g)):
        raise ValueError("gap must be finite on Gamma_C")
    return g


# ---------------------------------------------------------------------- near field
@njit(cache=True)
def _near_coo(rng, off, data, mirror, rows, cols, vals):
    """COO triplets of the near blocks (and their transposes where ``mirror``)."""
    k = 0
    for b in range(rng.shape[0]):
        r0, r1, c0, c1 = rng[b, 0], rng[b, 1], rng[b, 2], rng[b, 3]
        base = off[b]
        nc = c1 - c0
        for a in range(r1 - r0):
            for c in range(nc):
                v = data[base + a * nc + c]
                rows[k], cols[k], vals[k] = r0 + a, c0 + c, v
                k += 1
                if mirror[b]:
                    rows[k], cols[k], vals[k] = c0 + c, r0 + a, v
                    k += 1
    return k


def near_field(H) -> sp.csr_matrix:
    """The near-field blocks of an H-matrix as a sparse matrix (broken numbering; the
    blocks below the diagonal of a symmetric H by transposition)."""
    rng = np.ascontiguousarray(H.near_rng, np.int64)
    sizes = (rng[:, 1] - rng[:, 0]) * (rng[:, 3] - rng[:, 2])
    mirror = (H.symmetric & (rng[:, 0] != rng[:, 2])).astype(np.bool_)
    n = int(np.sum(sizes * np.where(mirror, 2, 1)))
    rows, cols = np.empty(n, np.int64), np.empty(n, np.int64)
    vals = np.empty(n)
    _near_coo(rng, np.ascontiguousarray(H.near_off, np.int64), H.near_data, mirror,
              rows, cols, vals)
    return sp.csr_matrix((vals, (rows, cols)), shape=H.shape)


def coarse_space(mesh, V_space, W_space, chunk: int):
    """(Z_u, Z_psi) sparse: the coarse space of the deflated preconditioner (module doc).
    The elements, in their order along the one closed curve, are grouped in chunks of
    ``chunk``; Z_u holds the coarse hat functions (piecewise linear in the element count
    between chunk starts, both components interleaved), Z_psi the chunk indicators."""
    el = mesh.elements
    ne = len(el)
    if not np.array_equal(el[:, 1], np.roll(el[:, 0], -1)):
        raise ValueError("coarse: the mesh must be one closed curve with its elements in "
                         "order (elements[e, 1] == elements[e + 1, 0])")
    k = max(1, ne // chunk)
    c = np.minimum(np.arange(ne) * k // ne, k - 1)            # chunk of every element
    start = np.searchsorted(c, np.arange(k))
    size = np.diff(np.append(start, ne))
    s = (np.arange(ne) - start[c]) / size[c]
    node = V_space.elem_dofs[:, 0]
    rows, cols, vals = [], [], []
    for comp in range(2):
        rows += [2 * node + comp, 2 * node + comp]
        cols += [2 * c + comp, 2 * ((c + 1) % k) + comp]
        vals += [1.0 - s, s]
    Zu = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(2 * V_space.ndof, 2 * k))
    wd = W_space.elem_dofs[:, 0]
    Zp = sp.csr_matrix((np.ones(2 * ne), (np.concatenate([2 * wd, 2 * wd + 1]),
                                          np.concatenate([2 * c, 2 * c + 1]))),
                       shape=(2 * W_space.ndof, 2 * k))
    return Zu, Zp


def _perm_matrix(perm, n):
    """P with (P x)[perm[r]] = x[r]: broken -> global numbering."""
    return sp.csr_matrix((np.ones(len(perm)), (perm, np.arange(len(perm)))), shape=(n, n))


# ---------------------------------------------------------------------- solver
@dataclass
class MixedPenaltyResult:
    """The solution (U interleaved V_hp^2, psi = V^{-1} B U interleaved W_hp^2), the
    Newton diagnostics (``info``: residual = max backward error per iterate), the final
    backward errors (``backward_errors`` = (equation, Calderon)), the GMRES iterations
    per Newton step, CPU seconds (``times``: near-field matrix, LU, GMRES, total) and the
    contact terms (:class:`PenaltyP1`)."""

    U: np.ndarray
    psi: np.ndarray
    converged: bool
    reason: str
    eps: float
    iterations: int
    info: SolverInfo
    backward_errors: tuple = (float("nan"), float("nan"))
    gmres_iterations: list = field(default_factory=list)
    times: dict = field(default_factory=dict)
    contact: PenaltyP1 | None = None
    n_active: int = 0
    preconditioner: str = ""


class _MixedSystem:
    """The operators of :func:`solve_penalty_mixed`: checked inputs, the free dofs, the
    near-field block matrix (built once), the coarse space of the deflation with its
    products A0 Z (once), the mixed operator and each Newton step's preconditioner."""

    def __init__(self, bem, gap, dirichlet_displacement, load, contact_label,
                 dirichlet_label, coarse, preconditioner="auto"):
        hm = getattr(bem, "hm", None)
        if hm is None:
            raise ValueError("bem: solve_penalty_mixed needs a LameBEM with "
                             "compression='hmatrix' (got the dense path)")
        if getattr(bem, "d", 0) != 2:
            raise ValueError("bem must be a LameBEM (vector traces)")
        if bem.constrained:
            raise ValueError("bem: zero_force must be False (the mixed form uses P = V^-1)")
        mesh = bem.mesh
        self.ud = array("dirichlet_displacement", dirichlet_displacement, shape=(2,))
        ce = np.flatnonzero(mesh.where(contact_label))
        if ce.size == 0:
            raise ValueError(f"contact_label {contact_label!r}: no element carries this "
                             "label")
        if not np.any(mesh.where(dirichlet_label)):
            raise ValueError(f"dirichlet_label {dirichlet_label!r}: no element carries "
                             "this label (the rigid modes need a Dirichlet side)")
        n = self.n = 2 * bem.V_space.ndof
        d = self.d = np.asarray(bem.V_space.dofs_on(dirichlet_label), np.int64)
        self.fixed = np.concatenate([2 * d, 2 * d + 1])
        self.free = np.setdiff1d(np.arange(n), self.fixed)
        self.f = np.zeros(n) if load is None else array("load", load, shape=(n,))
        self.pen = PenaltyP1(mesh, bem.V_space, ce, gap)
        self.W, self.B, self.V = hm.W, hm.B, hm.V
        m = self.m = self.V.shape[0]
        self.nf = len(self.free)
        self.count = 0
        # near-field block matrix (global numbering), built once
        t0 = time.process_time()
        Pw = _perm_matrix(hm.perm_W, m)
        self.Vn = (Pw @ near_field(hm.hmatrix("V")) @ Pw.T).tocsr()
        Bn = (Pw @ near_field(hm.hmatrix("K")) @ hm.S + 0.5 * bem.M).tocsr()
        Wn = (hm.S.T @ near_field(hm.hmatrix("W")) @ hm.S).tocsr()
        self.Wff, self.Bf = Wn[self.free][:, self.free], Bn[:, self.free]
        self.t_near = time.process_time() - t0
        if preconditioner == "auto":
            small = len(mesh.elements) <= AUTO_NEAR_FIELD_MAX
            preconditioner = "near_field" if small else "multilevel"
        self.kind = preconditioner
        if preconditioner == "multilevel":
            self._multilevel(bem, hm)
            return
        # coarse space of the deflated preconditioner: A0 Z once (H-matrix products)
        t0 = time.process_time()
        self.Z = None
        if coarse is not None:
            Zu, Zp = coarse_space(mesh, bem.V_space, bem.W_space, coarse)
            Zuf = Zu[self.free]
            self.Zuf = Zuf[:, np.flatnonzero(np.diff(Zuf.tocsc().indptr))]  # not in Gamma_D
            self.Z = sp.block_diag([self.Zuf, Zp], format="csr")
            self.AZ0 = self.mixed0(self.Z.toarray())
        self.t_coarse = time.process_time() - t0

    def _multilevel(self, bem, hm):
        """The block-diagonal multilevel preconditioner (:mod:`.mixed_precond`)."""
        t0 = time.process_time()
        mesh = bem.mesh
        pos = np.empty(bem.V_space.ndof, np.int64)
        pos[bem.V_space.elem_dofs[:, 0]] = np.arange(len(mesh.elements))
        self.PA = PrimalMultilevel(
            lambda X: self.W @ X, self.Wff, self.free, self.n,
            lambda chunk: coarse_space(mesh, bem.V_space, bem.W_space, chunk)[0],
            pos[self.free // 2], len(mesh.elements))
        self.PV = hm.preconditioner_V()
        self.perm_W = hm.perm_W
        self.t_coarse = time.process_time() - t0

    def start(self) -> np.ndarray:
        """U = 0 but the prescribed translation on Gamma_D."""
        U = np.zeros(self.n)
        U[self.fixed[: len(self.d)]], U[self.fixed[len(self.d):]] = self.ud
        return U

    def mixed0(self, x):
        """The mixed matrix without C_eps on a vector or the columns of a matrix."""
        x = np.asarray(x, float)
        du = np.zeros((self.n,) + x.shape[1:])
        du[self.free] = x[:self.nf]
        dp = x[self.nf:]
        y1 = self.W @ du + self.B.T @ dp
        return np.concatenate([y1[self.free], self.B @ du - self.V @ dp])

    def mixed(self, x, Cff):
        """The mixed matrix with the penalty Jacobian C_eps (free dofs) on x."""
        self.count += 1
        y = self.mixed0(x)
        y[:self.nf] += Cff @ x[:self.nf]
        return y

    def residuals(self, U, psi, eps):
        """``((be1, be2), S_hat U, r1, r2, J_c)``: the residuals of both equations (r1 on
        the free dofs), their backward errors (module doc) and the penalty energy, from
        fresh products with the compressed operators."""
        WU, Btp, BU, Vp = self.W @ U, self.B.T @ psi, self.B @ U, self.V @ psi
        energy_c, fc, _ = self.pen.terms(U, eps, self.n)
        Su = WU + Btp
        r1 = (Su + fc - self.f)[self.free]
        r2 = BU - Vp
        be1 = np.linalg.norm(r1) / max(float(np.linalg.norm(self.f[self.free]))
                                       + np.linalg.norm(Su[self.free])
                                       + np.linalg.norm(fc[self.free]), 1e-300)
        be2 = np.linalg.norm(r2) / max(np.linalg.norm(BU) + np.linalg.norm(Vp), 1e-300)
        return (float(be1), float(be2)), Su, r1, r2, energy_c

    def step(self, r1, r2, Cff, precond, gtol, restart, maxiter):
        """``(du, dp, failure)``: the Newton step by preconditioned GMRES (its products
        counted in ``self.count``); ``failure`` a reason, or "" when GMRES converged."""
        nf, m = self.nf, self.m
        rhs = -np.concatenate([r1, r2])
        A = spla.LinearOperator((nf + m, nf + m), matvec=lambda x: self.mixed(x, Cff),
                                dtype=float)
        M = spla.LinearOperator((nf + m, nf + m), matvec=precond, dtype=float)
        self.count = 0
        x, flag = spla.gmres(A, rhs, M=M, rtol=gtol, atol=0.0, restart=restart,
                             maxiter=maxiter, x0=precond(rhs))
        failure = ""
        if flag != 0 or not np.all(np.isfinite(x)):
            rel = np.linalg.norm(rhs - A @ x) / np.linalg.norm(rhs)
            failure = (f"flag {flag}, {self.count} iterations: ||r|| / ||b|| = {rel:.1e} > "
                       f"gmres_tol = {gtol:.1e}")
        du = np.zeros(self.n)
        du[self.free] = x[:nf]
        return du, x[nf:], failure

    def preconditioner(self, Cff):
        """The near-field LU of [[W + C_eps, B^T], [B, -V]], deflated by the coarse space
        (ADEF1: Z w + M0^{-1} (r - A Z w), w = (Z^T A Z)^{-1} Z^T r); or the block-
        triangular multilevel [[P_A, 0], [B, -P_V]] of :mod:`.mixed_precond`."""
        if self.kind == "multilevel":
            solve_A, nf, perm = self.PA.update(Cff), self.nf, self.perm_W
            B, free, n = self.B, self.free, self.n

            def block_triangular(r):           # P = [[P_A, 0], [B, -P_V]]
                y = np.empty_like(r)
                y[:nf] = solve_A(r[:nf])
                du = np.zeros(n)
                du[free] = y[:nf]
                y[nf:][perm] = self.PV.solve((B @ du - r[nf:])[perm])
                return y
            return block_triangular
        P = sp.bmat([[self.Wff + Cff, self.Bf.T], [self.Bf, -self.Vn]], format="csc")
        lu = spla.splu(P, permc_spec="COLAMD")
        if self.Z is None:
            return lu.solve
        Z, AZ = self.Z, self.AZ0.copy()
        AZ[:self.nf, :self.Zuf.shape[1]] += (Cff @ self.Zuf).toarray()
        Ac = sla.lu_factor(Z.T @ AZ)

        def precond(r):
            w = sla.lu_solve(Ac, Z.T @ r)
            return Z @ w + lu.solve(r - AZ @ w)
        return precond


def _armijo(sysm: _MixedSystem, U, du, dp, Su, energy_c, r1, eps):
    """``(t, None)``: the Armijo step on the energy J along (du, dp) (module doc: no extra
    operator product beyond S_hat du), or ``(None, why)``."""
    f, n = sysm.f, sysm.n
    Sdu = sysm.W @ du + sysm.B.T @ dp
    J0 = 0.5 * U @ Su + energy_c - f @ U
    slope = float(du[sysm.free] @ r1)
    if slope >= 0.0:
        return None, (f"not a descent direction (slope {slope:.2e}): GMRES step too "
                      "inaccurate")
    t = 1.0
    while True:
        Ut = U + t * du
        Jt = (0.5 * Ut @ (Su + t * Sdu) + sysm.pen.terms(Ut, eps, n)[0] - f @ Ut)
        if Jt <= J0 + ARMIJO * t * slope or abs(Jt - J0) <= 1e-15 * abs(J0):
            return t, None
        t *= 0.5
        if t < MIN_STEP:
            return None, "line search failed"


def solve_penalty_mixed(bem, eps: float, gap, dirichlet_displacement=(0.0, 0.0),
                        load=None, contact_label: str = "C", dirichlet_label: str = "D",
                        tol: float = 1e-8, max_iter: int = 50,
                        gmres_tol: float | None = None, restart: int = 200,
                        gmres_maxiter: int = 5, coarse: int | None = 16,
                        preconditioner: str = "auto"
                        ) -> MixedPenaltyResult:
    """Penalty contact (3.45)-(3.46) of a compressed :class:`LameBEM` body (module doc).

    Parameters
    ----------
    bem : LameBEM with ``compression="hmatrix"`` and ``zero_force=False`` (P = V^{-1})
    eps : penalty parameter > 0
    gap : float or callable g(x) on Gamma_C (admissible U_n <= g)
    dirichlet_displacement : the rigid translation (2,) prescribed on Gamma_D
    load : interleaved L(v) on V_hp^2 (default 0)
    tol : the backward errors to reach, in (0, 1)
    max_iter : Newton limit
    gmres_tol : relative residual of each Newton step's GMRES (default tol / 100)
    restart, gmres_maxiter : GMRES restart length and cycles
    coarse : elements per coarse element of the deflation space of the "near_field"
        preconditioner (None: the near-field LU alone)
    preconditioner : "multilevel" (block-triangular, :mod:`.mixed_precond`), "near_field"
        (sparse LU of the near-field block matrix) or "auto": near_field up to
        ``AUTO_NEAR_FIELD_MAX`` = 256 boundary elements, multilevel above (measured
        crossover, see the constant); the choice is returned as ``preconditioner``
    """
    t_all = time.process_time()
    eps = real("eps (penalty parameter)", eps, positive=True)
    tol = real("tol", tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True)
    max_iter = integer("max_iter", max_iter, lo=1)
    gtol = max(1e-14, tol * 1e-2) if gmres_tol is None else real(
        "gmres_tol", gmres_tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True)
    restart = integer("restart", restart, lo=1)
    gmres_maxiter = integer("gmres_maxiter", gmres_maxiter, lo=1)
    coarse = integer("coarse", coarse, lo=1, allow_none=True)
    preconditioner = choice("preconditioner", preconditioner, PRECONDITIONERS)
    sysm = _MixedSystem(bem, gap, dirichlet_displacement, load, contact_label,
                        dirichlet_label, coarse, preconditioner)
    n, free, f, pen = sysm.n, sysm.free, sysm.f, sysm.pen
    U, psi = sysm.start(), np.zeros(sysm.m)
    info = SolverInfo(converged=False, reason="")
    gm_its, t_lu, t_gm = [], 0.0, 0.0
    bes = (np.inf, np.inf)
    for it in range(max_iter + 1):
        # ---- residuals and backward errors of (U, psi): fresh operator products
        bes, Su, r1, r2, energy_c = sysm.residuals(U, psi, eps)
        be1, be2 = bes
        info.residuals.append(max(bes))
        info.merits.append(0.5 * U @ Su + energy_c - f @ U)
        if max(bes) <= tol:
            info.converged = True
            info.reason = (f"converged: backward errors {be1:.1e} (equation), {be2:.1e} "
                           f"(V psi = B U) <= tol = {tol:.1e}")
            break
        if it == max_iter:
            info.reason = (f"max_iter: {max_iter} Newton steps, backward errors {be1:.1e}, "
                           f"{be2:.1e} > tol = {tol:.1e}")
            break
        # ---- Newton step: near-field LU preconditioner + GMRES on the H-matrices
        C = pen.jacobian(U, eps, n)
        Cff = C[free][:, free]
        t0 = time.process_time()
        precond = sysm.preconditioner(Cff)
        t_lu += time.process_time() - t0
        t0 = time.process_time()
        du, dp, failure = sysm.step(r1, r2, Cff, precond, gtol, restart, gmres_maxiter)
        t_gm += time.process_time() - t0
        gm_its.append(sysm.count)
        if failure:
            info.reason = f"gmres did not converge at Newton step {it + 1} ({failure})"
            break
        # ---- step length: full step first; then Armijo on the energy (module doc)
        t = 1.0
        if it > 0:
            t, why = _armijo(sysm, U, du, dp, Su, energy_c, r1, eps)
            if t is None:
                info.reason = f"{why} at Newton step {it + 1}"
                break
        info.step_lengths.append(t)
        U = U + t * du
        psi = psi + t * dp
        info.iterations = it + 1
    info.backward_error = max(bes)
    times = dict(near_s=sysm.t_near, coarse_s=sysm.t_coarse, lu_s=t_lu, gmres_s=t_gm,
                 total_s=time.process_time() - t_all)
    return MixedPenaltyResult(U=U, psi=psi, converged=info.converged, reason=info.reason,
                              eps=eps, iterations=info.iterations, info=info,
                              backward_errors=bes, gmres_iterations=gm_its, times=times,
                              contact=pen, n_active=int(pen.pieces(U)[2].__gt__(
                                  pen.pieces(U)[1]).sum()),
                              preconditioner=sysm.kind)
