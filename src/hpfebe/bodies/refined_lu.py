"""Dense solves of the plastic BE body's cell-strain Jacobians J = I - M_pp D_p
(:mod:`hpfebe.bodies.plastic_be`) by an LU in single precision refined in double
(mixed-precision iterative refinement, the scheme of LAPACK's dsgesv): the O(n^3)
factorisation in float32 runs about twice as fast as in float64 (measured, n = 570, one
OpenBLAS thread: sgetrf 3.2 ms, numpy's dgesv 4.7-5.0 ms, scipy's dgetrf 5.8 ms), the
O(n^2) refinement steps in double make every solve backward stable as a double LU:
accepted when ||J x - b||_inf <= sqrt(n) eps ||J||_F ||x||_inf (dsgesv's test with the
Frobenius norm, one BLAS dot, for the row-sum norm: never below eps ||J||_inf ||x||_inf).

The factors of one J also serve a nearby J' (the next Newton iterate on the same plastic
set, the inner solution after the last step): refinement with the residual of J' then
converges while ||I - F^-1 J'|| < 1, checked by the decrease of the residual; a factor
that does not converge fast enough is reported (None) and the caller factorises anew.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
from scipy.linalg import lapack

EPS = np.finfo(float).eps


class RefinedLU:
    """Single-precision LU factors of the double matrix J (square, finite), kept with J
    for the residuals of :meth:`solve`.  ``pl``: a label of what J belongs to (the
    plastic cells it was built on), for the caller's reuse test."""

    def __init__(self, J: np.ndarray, pl=None):
        J = np.asarray(J, dtype=float)
        if J.ndim != 2 or J.shape[0] != J.shape[1]:
            raise ValueError(f"J must be a square matrix, got shape {J.shape}")
        self.J, self.pl = J, pl
        self.lu, self.piv, info = lapack.sgetrf(J.astype(np.float32), overwrite_a=True)
        if info < 0:
            raise ValueError(f"illegal value in argument {-info} of sgetrf")
        # info > 0: an exact zero pivot in single precision - no factor to refine with
        self.singular = info > 0
        self._dlu = None

    def _solve32(self, r: np.ndarray, s: float | None = None) -> np.ndarray:
        """F^-1 r in single precision, r scaled to unit size first (a residual of
        1e-35 would be subnormal in float32); ``s``: max|r| if known."""
        s = float(np.abs(r).max(initial=0.0)) if s is None else s
        if s == 0.0 or not math.isfinite(s):
            return np.zeros_like(r) if s == 0.0 else np.full_like(r, np.nan)
        x, info = lapack.sgetrs(self.lu, self.piv, (r * (1.0 / s)).astype(np.float32),
                                overwrite_b=True)
        if info != 0:
            raise ValueError(f"illegal value in argument {-info} of sgetrs")
        x = x.astype(float)
        x *= s
        return x

    def solve(self, b: np.ndarray, J: np.ndarray | None = None, max_refine: int = 30,
              min_rate: float = 0.5):
        """x with J x = b (J: default the factorised matrix; b a vector or a matrix of
        right-hand sides) by refinement from the single-precision solve, or None when
        it does not converge: the residual above the acceptance test after
        ``max_refine`` steps, or decreasing by less than the factor ``min_rate`` in a
        step (a factor too far from J)."""
        J = self.J if J is None else J
        b = np.asarray(b, dtype=float)
        if self.singular:
            return None
        # ||J||_F (one BLAS dot) for dsgesv's ||J||_inf: sqrt(n) ||J||_F >= ||J||_inf
        bound = math.sqrt(J.shape[0]) * EPS * float(np.linalg.norm(J))
        x = self._solve32(b)
        last = math.inf
        for _ in range(max_refine + 1):
            r = J @ x
            np.subtract(b, r, out=r)
            rn = np.abs(r).max(axis=0)
            worst = float(rn.max())
            if not math.isfinite(worst):
                return None
            if np.all(rn <= bound * np.abs(x).max(axis=0)):
                return x
            if worst > min_rate * last:
                return None
            last = worst
            x += self._solve32(r, worst if r.ndim == 1 else None)
        return None

    def solve_or_exact(self, b: np.ndarray) -> np.ndarray:
        """:meth:`solve` with J, falling back to a double LU of J (kept) when the
        refinement does not converge (J too ill-conditioned for single precision)."""
        x = self.solve(b)
        if x is not None:
            return x
        if self._dlu is None:
            self._dlu = sla.lu_factor(self.J, check_finite=False)
        return sla.lu_solve(self._dlu, b, check_finite=False)
