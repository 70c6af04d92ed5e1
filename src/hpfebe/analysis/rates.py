"""Observed convergence rates, log-log interpolation and fitted slopes, Aitken
extrapolation."""

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


def _positive_1d(name: str, a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1D, got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(f"{name} must be finite and positive (log-log data), got {a}")
    return a


def loglog_interpolate(x: float, xs, ys) -> float:
    """The curve (xs, ys), piecewise linear in log-log, evaluated at x:
    exp(interp(log x, log xs, log ys)).  ``xs`` need not be sorted but must be distinct;
    ValueError if x lies outside [min xs, max xs] (no extrapolation) or any datum is not
    positive."""
    xs, ys = _positive_1d("xs", xs), _positive_1d("ys", ys)
    if xs.shape != ys.shape or xs.size < 1:
        raise ValueError(f"xs and ys must be non-empty and of equal length, got {xs.size}, "
                         f"{ys.size}")
    x = float(x)
    if not (np.isfinite(x) and x > 0):
        raise ValueError(f"x must be finite and positive, got {x!r}")
    order = np.argsort(xs, kind="stable")
    xs, ys = xs[order], ys[order]
    if np.any(np.diff(xs) == 0):
        raise ValueError(f"xs must be distinct, got {xs}")
    if x < xs[0] or x > xs[-1]:
        raise ValueError(f"x = {x:g} lies outside the data range [{xs[0]:g}, {xs[-1]:g}] "
                         "(no extrapolation)")
    return float(np.exp(np.interp(np.log(x), np.log(xs), np.log(ys))))


def fitted_rate(x, y, last: int | None = None) -> float:
    """Least-squares slope of log y against log x over the last ``last`` points (all if
    None): e.g. x = DOF, y = error gives the (negative) algebraic rate in DOF."""
    x, y = _positive_1d("x", x), _positive_1d("y", y)
    if x.shape != y.shape:
        raise ValueError(f"x and y must have equal length, got {x.size}, {y.size}")
    if last is not None:
        if isinstance(last, bool) or not isinstance(last, (int, np.integer)) or last < 2:
            raise ValueError(f"last must be an integer >= 2 or None, got {last!r}")
        x, y = x[-last:], y[-last:]
    if x.size < 2 or np.ptp(x) == 0:
        raise ValueError(f"fitted_rate needs at least 2 distinct x values, got {x}")
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])
