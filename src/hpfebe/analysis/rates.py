"""Observed convergence rates and Aitken extrapolation."""

from __future__ import annotations

import numpy as np


def observed_rates(h, err) -> np.ndarray:
    """rate_k = log(err_{k-1} / err_k) / log(h_{k-1} / h_k), NaN for the first entry.

    ``h`` may be a mesh size (rates in h) or a number of degrees of freedom passed as
    1/DOF (then the rate is with respect to DOF^-1)."""
    h = np.asarray(h, dtype=float)
    err = np.asarray(err, dtype=float)
    if h.shape != err.shape or h.ndim != 1:
        raise ValueError(f"h and err must be 1D of equal length, got {h.shape}, {err.shape}")
    if np.any(h <= 0) or np.any(err <= 0):
        raise ValueError("h and err must be positive to compute rates")
    rates = np.full(h.shape, np.nan)
    rates[1:] = np.log(err[:-1] / err[1:]) / np.log(h[:-1] / h[1:])
    return rates


def aitken(x0: float, x1: float, x2: float) -> float:
    """Aitken's delta^2 extrapolation of the limit of x0, x1, x2 (consecutive terms of a
    geometrically converging sequence)."""
    denom = (x2 - x1) - (x1 - x0)
    if denom == 0.0:
        raise ValueError("Aitken extrapolation: second difference is zero "
                         "(sequence already converged or not geometric)")
    return x2 - (x2 - x1) ** 2 / denom
