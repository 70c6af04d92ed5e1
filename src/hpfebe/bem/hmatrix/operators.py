"""Compressed V, K, K', W, B, S_hat and Psi of one :class:`LaplaceBEM` / :class:`LameBEM`.

Three H-matrices on one cluster tree of the mesh's elements (:mod:`.cluster`):

    V  (single layer, W_hp x W_hp),
    K  (double layer, W_hp x broken GLL),         K = K_b S,
    W  (hypersingular by parts, broken GLL^2),    W = S^T W_b S,

with S the sparse assembly matrix broken GLL -> V_hp (a 1 per local function at its
global dof) and W_b's local blocks D_i^T Vt_ij D_j (:mod:`.entries`): W is compressed
itself, to its own tolerance, not through T^T V T (whose relative error would be that
of V amplified by the derivatives).  W_hp needs no S: its broken numbering is a
permutation.  Then (Section 1.4, :mod:`hpfebe.bem.operators`)

    B = K + M/2,   Psi = P B U,   S_hat = W + B^T P B,
    P = V^{-1} - V^{-1} C (C^T V^{-1} C)^{-1} C^T V^{-1}   (constrained),

with every V^{-1} a preconditioned CG solve to ``solver_tol`` (the multilevel additive
Schwarz preconditioner of :mod:`.precond`, or the block-diagonal near-field Cholesky
:class:`~.solvers.BlockJacobi`: ``HMatrixSettings.preconditioner``): V^{-1} is never
formed.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...checks import choice, integer, real
from ..assembly import _element_geometry
from .cluster import cluster_tree
from .entries import rule_tuple
from .matrix import HMatrix, Layout
from .precond import Multilevel
from .solvers import BlockJacobi, cg, dense_cholesky_solver, gmres, require


QTOL_FRACTION = 1e-2   # far-field quadrature accuracy (relative, per entry) / tol
QTOL_MIN = 1e-16       # ... but never below the dense assembly's integration.TOL
# The broken-space H-matrices' own tolerance / tol: K = K_b S and W = S^T W_b S sum the
# local functions of the two elements at a vertex (||S||^2 = 2), and in W the sum cancels
# most of the local blocks (they share the kernel's smooth part): measured, W's relative
# matvec error was up to 1.6 x that of W_b (Lame, p = 1), so W_b is built to tol / 4
TOL_FACTOR = {"V": 1.0, "K": 0.5, "W": 0.25}
INNER_TOL_FRACTION = 1e-3   # default inner CG residual / tol (HMatrixSettings.inner_tol)
INNER_TOL_MIN = 1e-14
PRECONDITIONERS = ("multilevel", "jacobi")


@dataclass(frozen=True)
class HMatrixSettings:
    """Compression settings: ``tol`` the relative (Frobenius) accuracy of every operator,
    in (0, 1); ``eta`` the admissibility parameter; ``leaf_size`` elements per leaf
    cluster (None: about 32 dofs per leaf); ``max_rank`` cap of the ACA rank;
    ``solver_tol`` the relative residual of the inner CG solves (None: tol / 1000);
    ``preconditioner`` of the CG solves with V: "multilevel" (default; leaf blocks, Haar
    functions per cluster and an exact coarse space, :mod:`.precond`: iterations nearly
    constant in N) or "jacobi" (the leaf blocks only, :class:`~.solvers.BlockJacobi`)."""

    tol: float = 1e-8
    eta: float = 1.0
    leaf_size: int | None = None
    max_rank: int = 300
    solver_tol: float | None = None
    maxiter: int = 5000
    preconditioner: str = "multilevel"

    def __post_init__(self):
        real("tol", self.tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True)
        real("eta", self.eta, positive=True)
        integer("leaf_size", self.leaf_size, lo=1, allow_none=True)
        integer("max_rank", self.max_rank, lo=1)
        real("solver_tol", self.solver_tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True,
             allow_none=True)
        integer("maxiter", self.maxiter, lo=1)
        choice("preconditioner", self.preconditioner, PRECONDITIONERS)

    @property
    def inner_tol(self) -> float:
        """The relative residual of the inner solves: ``solver_tol``, default tol / 1000
        (floor 1e-14).  The error of Psi is about cond(V) times the residual: at p = 4,
        N = 1024, tol = 1e-8, a residual of tol / 10 left a relative L2 error of 2.6e-7
        in Psi against 7.7e-9 at 1e-13 (dense: 8.9e-13, u quadratic, exact in W_hp)."""
        if self.solver_tol is not None:
            return self.solver_tol
        return max(INNER_TOL_MIN, INNER_TOL_FRACTION * self.tol)


class _Op(spla.LinearOperator):
    """A LinearOperator from matvec / rmatvec callables acting on column blocks too."""

    def __init__(self, shape, mv, rmv):
        super().__init__(dtype=np.dtype(float), shape=shape)
        self._mv, self._rmv = mv, rmv

    def _matvec(self, x):
        return self._mv(np.asarray(x).reshape(-1))

    def _rmatvec(self, x):
        return self._rmv(np.asarray(x).reshape(-1))

    def _matmat(self, X):
        return self._mv(np.asarray(X))

    def _rmatmat(self, X):
        return self._rmv(np.asarray(X))

    def _adjoint(self):
        return _Op((self.shape[1], self.shape[0]), self._rmv, self._mv)


class CompressedOperators:
    """The compressed operators of one BEM object (built on first use, cached); see the
    module doc.  ``bem``: a LaplaceBEM or LameBEM (its spaces, kernel parameters ``kp``,
    ``M``, ``constraints`` and ``hmatrix_kernels()``: the (kernel id, log coefficient)
    of V, K and of the single-layer-type kernel of W)."""

    def __init__(self, bem, settings: HMatrixSettings):
        self.bem, self.settings = bem, settings
        mesh, d = bem.mesh, bem.d
        self.d = d
        self.pmax = int(mesh.degrees.max())
        leaf = settings.leaf_size or max(2, 32 // (d * (self.pmax + 1)) + 1)
        self.tree = cluster_tree(mesh.nodes, mesh.elements, leaf)
        order = self.tree.order
        normals, L, mid = _element_geometry(mesh.nodes, mesh.elements)
        degs = np.ascontiguousarray(mesh.degrees, dtype=np.int64)
        self.geom = (mesh.nodes, mesh.elements, normals, L, mid, degs, order)
        pt = degs[order]
        self.lay_W = Layout.of(pt, 0, False, d)        # W_hp (broken = W_hp)
        self.lay_G = Layout.of(pt, 1, False, d)        # broken GLL
        self.perm_W = self._global(bem.W_space, self.lay_W)
        gl = self._global(bem.V_space, self.lay_G)
        keep = gl >= 0
        self.S = sp.csr_matrix((np.ones(int(keep.sum())), (np.flatnonzero(keep), gl[keep])),
                               shape=(self.lay_G.size, d * bem.V_space.ndof))
        self._H: dict[str, HMatrix] = {}
        self._cache: dict[str, object] = {}
        self.solves: list = []

    def _global(self, space, lay: Layout) -> np.ndarray:
        """Global index (d dof + c) of every broken dof, -1 for a removed function."""
        e = self.tree.order[lay.pos]
        k, c = np.divmod(lay.loc, self.d)
        dof = space.elem_dofs[e, k]
        return np.where(dof >= 0, self.d * dof + c, -1).astype(np.int64)

    # ------------------------------------------------------------------ H-matrices
    def hmatrix(self, name: str) -> HMatrix:
        """The H-matrix "V", "K" or "W" (broken numbering), built on first use."""
        if name not in self._H:
            (kv, lv), (kk, lk), (kw, lw) = self.bem.hmatrix_kernels()
            spec = {"V": (kv, lv, 0, 0, False, self.lay_W, self.lay_W),
                    "K": (kk, lk, 0, 1, False, self.lay_W, self.lay_G),
                    "W": (kw, lw, 0, 0, True, self.lay_G, self.lay_G)}[name]
            kernel, logc, kt, kr, deriv, test, trial = spec
            logc = np.ascontiguousarray(np.asarray(logc, float).reshape(-1))
            kern = (kernel, logc, bool(logc.any()),
                    np.ascontiguousarray(np.asarray(self.bem.kp, float).reshape(-1)),
                    self.d, kt, kr, deriv)
            s = self.settings
            t0 = time.process_time()
            tol = s.tol * TOL_FACTOR[name]
            qtol = max(QTOL_MIN, QTOL_FRACTION * tol)
            self._H[name] = HMatrix(kern, self.geom, rule_tuple(kt, kr, self.pmax),
                                    self.tree, test, trial, tol, s.eta, s.max_rank,
                                    self.pmax, far_rules=rule_tuple(kt, kr, self.pmax, qtol),
                                    symmetric=name != "K")
            self._H[name].time_total = time.process_time() - t0
        return self._H[name]

    def _perm_apply(self, H, x, trans):
        """V (or V^T) in the global W_hp numbering."""
        X = np.asarray(x, float)
        y = H.rmatvec(X[self.perm_W]) if trans else H.matvec(X[self.perm_W])
        out = np.empty_like(y)
        out[self.perm_W] = y
        return out

    @property
    def V(self) -> _Op:
        H = self.hmatrix("V")
        return _Op(H.shape, lambda x: self._perm_apply(H, x, False),
                   lambda x: self._perm_apply(H, x, True))

    def _k(self, x):
        H = self.hmatrix("K")
        y = H.matvec(self.S @ np.asarray(x, float))
        out = np.empty_like(y)
        out[self.perm_W] = y
        return out

    def _kt(self, y):
        H = self.hmatrix("K")
        return self.S.T @ H.rmatvec(np.asarray(y, float)[self.perm_W])

    @property
    def K(self) -> _Op:
        n = self.d * self.bem.V_space.ndof
        return _Op((self.hmatrix("K").shape[0], n), self._k, self._kt)

    @property
    def K_adj(self) -> _Op:
        return self.K.T

    def _w(self, x, trans=False):
        H = self.hmatrix("W")
        xb = self.S @ np.asarray(x, float)
        return self.S.T @ (H.rmatvec(xb) if trans else H.matvec(xb))

    @property
    def W(self) -> _Op:
        n = self.d * self.bem.V_space.ndof
        return _Op((n, n), self._w, lambda x: self._w(x, True))

    def _b(self, x):
        return self._k(x) + 0.5 * (self.bem.M @ np.asarray(x, float))

    def _bt(self, y):
        return self._kt(y) + 0.5 * (self.bem.M.T @ np.asarray(y, float))

    @property
    def B(self) -> _Op:
        return _Op(self.K.shape, self._b, self._bt)

    # ------------------------------------------------------------------ solves
    def solve_V(self, rhs: np.ndarray) -> np.ndarray:
        """V^{-1} rhs (global W_hp numbering; a vector or the columns of a matrix, solved
        together) by preconditioned CG (``settings.preconditioner``).

        The achieved error: CG stops when ||r|| <= inner_tol ||b|| (Euclidean, every
        column), so ||x - V_H^{-1} b|| <= cond_2(V_H) inner_tol ||V_H^{-1} b|| against
        the H-matrix V_H, and against the exact V another cond_2(V) times the
        compression error (<= tol relative).  The preconditioner changes the iterations
        only, not this bound; ``solves[-1].counts["cond_estimate"]`` is CG's Lanczos
        estimate of cond(C^{-1} V_H) (tools/bem_scaling.py, Laplace p = 1: multilevel
        10.3 at N = 1024 to 31.8 at N = 65536, about + 3.6 per doubling of N; block
        Jacobi 129 to 8004, like N)."""
        pre = self.preconditioner_V()
        H = self.hmatrix("V")
        rhs = np.asarray(rhs, float)
        xb, info = cg(H.matvec, rhs[self.perm_W], pre.solve, tol=self.settings.inner_tol,
                      maxiter=self.settings.maxiter)
        self.solves.append(info)
        require(info, "CG on the compressed V")
        out = np.empty_like(xb)
        out[self.perm_W] = xb
        return out

    def preconditioner_V(self):
        """The preconditioner of the CG solves with V (broken numbering), built on first
        use: :class:`~.precond.Multilevel` or :class:`~.solvers.BlockJacobi`."""
        kind = self.settings.preconditioner
        if kind not in self._cache:
            H = self.hmatrix("V")
            t0 = time.process_time()
            if kind == "jacobi":
                self._cache[kind] = BlockJacobi(H)
            else:
                L = self.geom[3][self.tree.order]
                self._cache[kind] = Multilevel(H, self.tree, self.lay_W, L, self.d)
            self._cache[kind].cpu_s = time.process_time() - t0
            self._check_conditioning(H)
        return self._cache[kind]

    def _check_conditioning(self, H) -> None:
        """Warn when ``tol`` is too coarse for the conditioning of V: the relative
        error of V^{-1} b from a V perturbed by tol (relative) is up to cond_2(V) tol /
        (1 - cond_2(V) tol), no digit once cond_2(V) tol >= 1.  cond_2(V) >= the lower
        bound max_t lambda_max(V_tt) / min_t lambda_min(V_tt) over the leaf blocks
        (principal sub-matrices: Cauchy interlacing); a leaf block that is not positive
        definite is an error."""
        lo, hi = np.inf, 0.0
        for b in H.diag_blocks:                 # a loop over the leaf clusters
            ev = np.linalg.eigvalsh(H.diagonal_block(int(b))[2])
            lo, hi = min(lo, ev[0]), max(hi, ev[-1])
        if lo <= 0.0:
            raise np.linalg.LinAlgError(
                f"the compressed V at tol={self.settings.tol:g} has a leaf block with "
                f"eigenvalue {lo:.3e} <= 0: V is not positive definite")
        kappa = hi / lo
        if kappa * self.settings.tol >= 1.0:
            warnings.warn(f"tol={self.settings.tol:g} is too coarse for V: cond_2(V) >= "
                          f"{kappa:.3g}, so cond_2(V) * tol >= 1 and the solves with V "
                          "(Psi, S_hat) may have no correct digit; use tol < "
                          f"{1.0 / kappa:.1e}", UserWarning, stacklevel=3)

    def _project(self, psi):
        """psi - V^{-1} C (C^T V^{-1} C)^{-1} C^T psi (the constraint of P), if any."""
        if not self.bem.constrained:
            return psi
        C = self.bem.constraints
        if "VC" not in self._cache:
            VC = self.solve_V(C)
            self._cache["VC"] = (VC, dense_cholesky_solver(C.T @ VC))
        VC, solve_c = self._cache["VC"]
        return psi - VC @ solve_c(np.tensordot(C.T, psi, axes=1))

    def Psi(self, U) -> np.ndarray:
        """Psi = P B U (CG on V; on the first call together with V^{-1} C)."""
        U = np.asarray(U, float)
        rhs = self._b(U)
        if self.bem.constrained and "VC" not in self._cache:
            C = self.bem.constraints
            both = self.solve_V(np.column_stack([rhs.reshape(rhs.shape[0], -1), C]))
            VC = both[:, -C.shape[1]:]
            self._cache["VC"] = (VC, dense_cholesky_solver(C.T @ VC))
            return self._project(both[:, :-C.shape[1]].reshape(rhs.shape))
        return self._project(self.solve_V(rhs))

    def _s(self, x):
        x = np.asarray(x, float)
        return self._w(x) + self._bt(self._project(self.solve_V(self._b(x))))

    @property
    def S_hat(self) -> _Op:
        """W + B^T P B as a symmetric LinearOperator (inner CG solves)."""
        n = self.d * self.bem.V_space.ndof
        return _Op((n, n), self._s, self._s)

    def solve_gmres(self, name: str, rhs: np.ndarray, shift=None):
        """Solve ``name`` ("K", "W", "S_hat", "V") x = rhs by GMRES (inner tolerance
        ``solver_tol``); ``shift``: optional (n, r) matrix Z added as Z Z^T (the
        stabilisation of W and S_hat on their kernel).  Returns (x, SolverInfo)."""
        op = {"K": self.K, "W": self.W, "S_hat": self.S_hat, "V": self.V}[name]
        if op.shape[0] != op.shape[1]:
            raise ValueError(f"{name} is not square ({op.shape}): no GMRES solve")
        mv = op.matvec
        if shift is not None:
            Z = np.asarray(shift, float).reshape(op.shape[0], -1)
            mv = (lambda f: (lambda x: f(x) + Z @ (Z.T @ x)))(op.matvec)
        x, info = gmres(mv, rhs, tol=self.settings.inner_tol, maxiter=self.settings.maxiter)
        self.solves.append(info)
        return x, info

    # ------------------------------------------------------------------ report
    def info(self, sampled_rows: int = 8) -> dict:
        """Per built operator: storage (bytes, dense bytes, ratio), blocks, ranks, build
        times, the estimated error (error_bound) and the measured one (sampled_error:
        exact rows against H); the iterations of the solves so far and CG's Lanczos
        condition estimates (NaN for GMRES)."""
        out = {}
        for name, H in self._H.items():
            d = H.info()
            d["cpu_s"] = getattr(H, "time_total", float("nan"))
            d["sampled_error"] = H.sampled_error(sampled_rows) if sampled_rows else None
            out[name] = d
        out["solves"] = [(s.iterations, s.converged) for s in self.solves]
        out["cond_estimates"] = [s.counts.get("cond_estimate", float("nan"))
                                 for s in self.solves]
        return out
