"""What every solver returns and the one backward-error rule (DESIGN.md): :class:`SolverInfo`
(converged flag and reason, iterations, residual history), :class:`Iterate` (what a
problem returns at a point x), the :class:`NewtonProblem` protocol, :class:`SingularStep`
(a Newton system that cannot be solved), and :data:`BACKWARD_TOL` with the verdict on an
iterate that Newton cannot improve any more.

A problem tells Newton three things (the :class:`NewtonProblem` protocol):

    evaluate(x) -> Iterate      residual on the free unknowns, merit, force scale of the
                                stopping test, contact pattern (for cycling), data
    step(it)    -> dx           the Newton step: J(x) dx = -residual (raise
                                :class:`SingularStep` with the reason if it cannot)
    slope(it, dx) -> float      directional derivative of the merit along dx

Stopping test: ||residual|| <= atol + tol * it.scale (norm ``norm``).  The merit is
whatever the problem's globalisation needs: an energy for a potential problem (penalty,
Tresca), ||R||_2 otherwise (Coulomb).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

EPS = float(np.finfo(float).eps)


class SingularStep(Exception):
    """The Newton system could not be solved; the message is the reason."""


@dataclass
class Iterate:
    """What a problem returns at a point x (see module doc)."""

    x: np.ndarray
    residual: np.ndarray
    merit: float
    scale: float = 1.0
    key: Any = None
    data: Any = None


class NewtonProblem(Protocol):
    def evaluate(self, x: np.ndarray) -> Iterate: ...

    def step(self, it: Iterate) -> np.ndarray: ...

    def slope(self, it: Iterate, dx: np.ndarray) -> float: ...


@dataclass
class SolverInfo:
    """Diagnostics of every solver: converged flag and reason, iterations, the residual
    norm of every iterate (index 0 = start), the accepted step lengths; ``load_factor``
    for a step of a load path, ``steps`` for the steps of a load path or the inner
    solves of an outer iteration."""

    converged: bool
    reason: str
    iterations: int = 0
    residuals: list = field(default_factory=list)
    step_lengths: list = field(default_factory=list)
    merits: list = field(default_factory=list)
    load_factor: float | None = None
    predictor_used: bool = False
    steps: list = field(default_factory=list)
    counts: dict = field(default_factory=dict)
    backward_error: float = float("nan")


def residual_norm(r: np.ndarray, norm) -> float:
    if r.size == 0:
        return 0.0
    return float(np.abs(r).max()) if norm == np.inf else float(np.linalg.norm(r))


# accepted backward error of an iterate Newton cannot improve (six digits in the
# equation; the stopping tolerance itself is usually far smaller)
BACKWARD_TOL = 1e-6


def roundoff_verdict(info: SolverInfo, it: Iterate, norm, what: str) -> None:
    """Newton cannot improve the iterate any more: accept it only if its backward error
    ||R|| / scale (the relative residual of the equation, scale-free) is below
    BACKWARD_TOL; otherwise the system is too ill-conditioned for the answer to be
    trusted."""
    be = residual_norm(it.residual, norm) / max(it.scale, np.finfo(float).tiny)
    info.backward_error = be
    if be <= BACKWARD_TOL:
        info.converged = True
        info.reason = (f"converged ({what}; backward error {be:.1e}, the residual is "
                       "limited by the conditioning)")
    else:
        info.reason = (f"ill-conditioned: {what} with backward error {be:.1e} > "
                       f"{BACKWARD_TOL:.1e}; the answer cannot be trusted")
