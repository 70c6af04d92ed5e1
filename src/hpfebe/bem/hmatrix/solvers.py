"""Krylov solvers on the compressed operators: preconditioned CG for the SPD single
layer V, GMRES for the K / W systems, and the block-diagonal (near-field Cholesky)
preconditioner.  Each returns its :class:`~hpfebe.solvers.info.SolverInfo` (converged
flag, reason, iterations, residual history; DESIGN.md).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla
from numba import njit

from ...solvers.info import SolverInfo


@njit(cache=True)
def _block_cholesky_solve(r0s, r1s, loff, Lflat, x, y):
    """y[r0:r1] = (L L^T)^{-1} x[r0:r1] per block, L lower triangular (row-major)."""
    for b in range(r0s.shape[0]):
        r0, r1 = r0s[b], r1s[b]
        m = r1 - r0
        base = loff[b]
        for a in range(m):                      # L z = x
            s = x[r0 + a]
            for c in range(a):
                s -= Lflat[base + a * m + c] * y[r0 + c]
            y[r0 + a] = s / Lflat[base + a * m + a]
        for a in range(m - 1, -1, -1):          # L^T y = z
            s = y[r0 + a]
            for c in range(a + 1, m):
                s -= Lflat[base + c * m + a] * y[r0 + c]
            y[r0 + a] = s / Lflat[base + a * m + a]


class BlockJacobi:
    """(diag_b A_tt)^{-1} over the diagonal near-field blocks of an SPD H-matrix (broken
    numbering): a Cholesky factor per leaf cluster, applied by numba triangular solves."""

    def __init__(self, H):
        r0s, r1s, Ls = [], [], []
        for b in H.diag_blocks:
            r0, r1, blk = H.diagonal_block(int(b))
            Ls.append(np.linalg.cholesky(0.5 * (blk + blk.T)).ravel())
            r0s.append(r0)
            r1s.append(r1)
        self.r0s, self.r1s = np.array(r0s, np.int64), np.array(r1s, np.int64)
        self.loff = np.concatenate([[0], np.cumsum([len(L) for L in Ls])]).astype(np.int64)
        self.L = np.concatenate(Ls)
        self.n = H.shape[0]

    def solve(self, x: np.ndarray) -> np.ndarray:
        """The preconditioner on a vector or on the columns of a matrix."""
        x = np.asarray(x, dtype=float)
        if x.ndim == 2:
            return np.column_stack([self.solve(x[:, q]) for q in range(x.shape[1])])
        y = np.empty(self.n)
        _block_cholesky_solve(self.r0s, self.r1s, self.loff, self.L,
                              np.ascontiguousarray(x), y)
        return y


def cg(apply_A, b: np.ndarray, precond=None, tol: float = 1e-10, maxiter: int = 2000
       ) -> tuple[np.ndarray, SolverInfo]:
    """Preconditioned conjugate gradients for SPD A, on one right-hand side or on the
    columns of ``b`` at once (independent recursions sharing each matvec of a column
    block; a column stops when ||r_q|| <= tol ||b_q||, Euclidean).  ``apply_A``,
    ``precond``: callables on vectors or column blocks.  SolverInfo.residuals: the
    largest relative residual of the active columns per iteration;
    ``SolverInfo.counts["cond_estimate"]``: the Lanczos estimate of the condition number
    of the preconditioned operator (the extreme eigenvalues of CG's tridiagonal matrix
    T_k, Saad, "Iterative Methods", Sect. 6.7.3; a lower bound that tightens with k),
    the largest over the columns."""
    b = np.asarray(b, dtype=float)
    one = b.ndim == 1
    B = b.reshape(b.shape[0], -1)
    X = np.zeros_like(B)
    bn = np.linalg.norm(B, axis=0)
    active = bn > 0.0
    R = B.copy()
    info = SolverInfo(converged=False, reason="", residuals=[1.0 if active.any() else 0.0])
    Z = precond(R) if precond is not None else R.copy()
    P = Z.copy()
    rz = np.einsum("ij,ij->j", R, Z)
    it = 0
    alphas, betas = [], []          # per iteration, every column (NaN: inactive)
    while active.any() and it < maxiter:
        it += 1
        cols = np.flatnonzero(active)
        AP = apply_A(P[:, cols])
        pAp = np.einsum("ij,ij->j", P[:, cols], AP)
        if not np.all(np.isfinite(pAp)) or np.any(pAp <= 0.0):
            info.iterations = it
            info.reason = f"breakdown: p^T A p = {pAp.min():.3e} (A not SPD?)"
            return (X[:, 0] if one else X), info
        alpha = rz[cols] / pAp
        alphas.append(np.full(B.shape[1], np.nan))
        alphas[-1][cols] = alpha
        betas.append(np.full(B.shape[1], np.nan))
        X[:, cols] += alpha * P[:, cols]
        R[:, cols] -= alpha * AP
        rel = np.linalg.norm(R[:, cols], axis=0) / bn[cols]
        info.residuals.append(float(rel.max()))
        active[cols[rel <= tol]] = False
        cols = np.flatnonzero(active)
        if len(cols) == 0:
            break
        Zc = precond(R[:, cols]) if precond is not None else R[:, cols]
        rz_new = np.einsum("ij,ij->j", R[:, cols], Zc)
        betas[-1][cols] = rz_new / rz[cols]
        P[:, cols] = Zc + (rz_new / rz[cols]) * P[:, cols]
        rz[cols] = rz_new
    info.iterations = it
    info.counts["cond_estimate"] = _lanczos_condition(np.array(alphas), np.array(betas))
    if not active.any():
        info.converged = True
        info.reason = f"converged: ||r|| / ||b|| <= {tol:.1e} for every column"
    else:
        info.reason = (f"not converged in {maxiter} iterations: ||r|| / ||b|| = "
                       f"{info.residuals[-1]:.2e}")
    return (X[:, 0] if one else X), info


def _lanczos_condition(alphas: np.ndarray, betas: np.ndarray) -> float:
    """max over the columns of lambda_max / lambda_min of CG's Lanczos matrix: T_kk =
    1/alpha_k + beta_{k-1}/alpha_{k-1}, T_{k,k-1} = sqrt(beta_{k-1})/alpha_{k-1}."""
    best = float("nan")
    for q in range(alphas.shape[1] if alphas.ndim == 2 else 0):     # a loop over columns
        a = alphas[:, q][np.isfinite(alphas[:, q])]
        if len(a) == 0:
            continue
        b = betas[:len(a) - 1, q]
        diag = 1.0 / a
        diag[1:] += b / a[:-1]
        ev = (sla.eigvalsh_tridiagonal(diag, np.sqrt(b) / a[:-1]) if len(a) > 1
              else diag)
        if ev[0] > 0.0:
            best = float(np.nanmax([best, ev[-1] / ev[0]]))
    return best


def gmres(apply_A, b: np.ndarray, precond=None, tol: float = 1e-10, restart: int = 100,
          maxiter: int = 20) -> tuple[np.ndarray, SolverInfo]:
    """Restarted GMRES (scipy) for a general A: ||r|| <= tol ||b||; ``maxiter`` restart
    cycles of ``restart`` inner steps."""
    b = np.asarray(b, dtype=float)
    n = b.shape[0]
    A = spla.LinearOperator((n, n), matvec=apply_A, dtype=float)
    M = None if precond is None else spla.LinearOperator((n, n), matvec=precond, dtype=float)
    res: list[float] = []
    bnorm = float(np.linalg.norm(b))
    x, flag = spla.gmres(A, b, rtol=tol, atol=0.0, restart=restart, maxiter=maxiter, M=M,
                         callback=lambda pr: res.append(float(pr) * bnorm),
                         callback_type="pr_norm")
    rn = float(np.linalg.norm(b - apply_A(x)))
    ok = flag == 0
    info = SolverInfo(converged=ok, iterations=len(res), residuals=res,
                      reason=(f"converged: ||r|| / ||b|| = {rn / max(bnorm, 1e-300):.2e}"
                              if ok else f"gmres did not converge (flag {flag}): "
                              f"||r|| / ||b|| = {rn / max(bnorm, 1e-300):.2e}"))
    return x, info


def require(info: SolverInfo, what: str) -> None:
    """Raise if an inner solve did not converge: a silent wrong answer is worse."""
    if not info.converged:
        raise np.linalg.LinAlgError(f"{what}: {info.reason}")


def dense_cholesky_solver(A: np.ndarray):
    """Solve with a small dense SPD matrix (the constraint systems C^T V^-1 C)."""
    f = sla.cho_factor(A)
    return lambda y: sla.cho_solve(f, y)
