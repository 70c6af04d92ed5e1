"""Outer iterations x_{k+1} = update(x_k) (Uzawa, Dirichlet-to-Neumann, ...) with the
stopping and divergence rules of :func:`fixed_point`."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ..checks import InputTypeError, array, integer, real
from .info import SolverInfo, residual_norm


def fixed_point(update: Callable[[np.ndarray], Any], x0: np.ndarray, tol: float,
                max_iter: int = 100, norm=np.inf, divergence: float = 1e6,
                min_iter: int = 1):
    """Outer iterations x_{k+1} = update(x_k) (Uzawa, Dirichlet-to-Neumann, ...) with the
    stopping and divergence rules of this module.

    ``update(x)`` returns the next iterate, or (next iterate, SolverInfo of the inner
    solve), the latter collected in ``info.steps``; an inner solve that did not converge
    ends the iteration with its reason.  Stop when ||x_{k+1} - x_k|| <= tol *
    max(||x_{k+1}||, tiny) (relative increment, ``info.residuals``); "diverged" when
    the increment is not finite or exceeds ``divergence`` times the smallest increment
    seen; "max_iter" after ``max_iter`` updates.  Returns (x, SolverInfo)."""
    tol = real("tol", tol, positive=True)
    max_iter = integer("max_iter", max_iter, lo=1)
    min_iter = integer("min_iter", min_iter, lo=1)
    divergence = real("divergence", divergence, positive=True, finite=False)
    if not callable(update):
        raise InputTypeError(f"update must be a callable x -> next iterate, got "
                             f"{update!r}")
    x = array("x0", x0)
    info = SolverInfo(False, "max_iter")
    smallest = np.inf
    for k in range(1, int(max_iter) + 1):
        out = update(x)
        if isinstance(out, tuple):
            x_new, inner = out
            info.steps.append(inner)
            if not inner.converged:
                info.iterations = k
                info.reason = f"inner solve {k}: {inner.reason}"
                return x, info
        else:
            x_new = out
        x_new = np.asarray(x_new, dtype=float)
        inc = residual_norm(x_new - x, norm)
        info.iterations = k
        info.residuals.append(inc)
        if not np.isfinite(inc) or not np.all(np.isfinite(x_new)):
            info.reason = f"diverged: non-finite iterate at iteration {k}"
            return x, info
        x = x_new
        if inc <= tol * max(residual_norm(x, norm), np.finfo(float).tiny) and k >= min_iter:
            info.converged, info.reason = True, "converged"
            return x, info
        if inc > divergence * smallest:
            info.reason = growth_reason(inc, k, divergence, smallest)
            return x, info
        smallest = min(smallest, inc)
    return x, info


def growth_reason(inc: float, k: int, divergence: float, smallest: float) -> str:
    """The reason of :func:`fixed_point`'s divergence test (also of the compiled loops
    that follow its rules, :func:`hpfebe.solvers.uzawa.tresca_uzawa`)."""
    return (f"diverged: increment {inc:.3e} at iteration {k} exceeds {divergence:g} x the "
            f"smallest ({smallest:.3e})")
