"""Polyak's projected conjugate gradients [53] for the bound-constrained quadratic
program

    min 1/2 x^T A x - b^T x   subject to   x <= upper   (A SPD, upper may be +inf),

the inner frictionless contact problem of Algorithms 4.3 and 4.4 (Section 4.3.3): CG on
the face of the active set, compiled (:func:`_polyak_kernel`, a numba kernel; the KKT
test of :func:`_kkt_met`).  :func:`projected_cg` validates its input and returns
(x, :class:`~hpfebe.solvers.SolverInfo`); :func:`polyak_solve` is the same iteration on
input prepared once for a sequence of QPs with the same A (:class:`BoundQP`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..checks import integer, real
from .info import SolverInfo

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
    tol = real("tol", tol, positive=True)
    if np.any(np.isnan(u)):
        raise ValueError("upper contains NaN")
    max_iter = 20 * n + 100 if max_iter is None else integer("max_iter", max_iter, lo=1)
    return _projected_cg_checked(A, b, u, x0, tol, max_iter)


def _projected_cg_checked(A, b, u, x0, tol: float, max_iter: int):
    """:func:`projected_cg` on validated input (A, b, u contiguous float arrays)."""
    x = np.minimum(np.zeros(b.size) if x0 is None else np.asarray(x0, dtype=float), u)
    res = np.empty(max_iter + 1)
    status, steps, nres = _polyak_kernel(A, b, u, x, tol, max_iter, res)
    return x, pcg_info(status, steps, nres, res, int(np.count_nonzero(x >= u)))


def _per_node(v, n: int) -> np.ndarray:
    """``v`` (a scalar or an (n,) vector) as a contiguous float vector (n,)."""
    if isinstance(v, np.ndarray) and v.shape == (n,) and v.dtype == np.float64 and \
            v.flags.c_contiguous:
        return v
    return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=float), (n,)))


def pcg_info(status, steps, nres, res, active: int) -> SolverInfo:
    """The SolverInfo of one projected-CG solve (:func:`_polyak_kernel`'s outputs and
    the final active set size)."""
    return SolverInfo(status == 1, _PCG_REASONS[status], int(steps),
                      res[:min(nres, res.size)].tolist(),
                      counts=dict(cg_steps=int(steps), active=int(active)))


@dataclass
class BoundQP:
    """The matrix of a sequence of bound-constrained QPs with one A (the contact QP of
    body 1 in the node frames, Algorithm 4.4 step 2): A and b as contiguous float arrays,
    the bound factor ``nA`` = :func:`_frobenius_bound` of A and a residual buffer, built
    once (:meth:`of`) and solved for many right-hand sides and bounds (:meth:`solve`)."""

    A: np.ndarray
    b: np.ndarray
    nA: float
    res: np.ndarray

    @classmethod
    def of(cls, A, b) -> "BoundQP":
        A = np.ascontiguousarray(A, dtype=float)
        b = np.ascontiguousarray(b, dtype=float)
        n = b.size
        if b.ndim != 1 or A.shape != (n, n):
            raise ValueError(f"A must be ({n}, {n}), got {A.shape}")
        return cls(A, b, _frobenius_bound(A), np.empty(20 * n + 101))

    def solve(self, rhs, upper, x0, tol: float):
        """Projected CG for A x = rhs, x <= upper from x0 (clipped to upper; None: 0),
        without re-validating the shapes.  Returns (x, SolverInfo)."""
        n = self.b.size
        x = np.minimum(np.zeros(n) if x0 is None else np.asarray(x0, dtype=float), upper)
        max_iter = 20 * n + 100
        res = np.empty(max_iter + 1)
        status, steps, nres = _polyak_core(self.A, rhs, upper, x, float(tol), max_iter, res,
                                           self.nA)
        return x, pcg_info(status, steps, nres, res, int(np.count_nonzero(x >= upper)))
