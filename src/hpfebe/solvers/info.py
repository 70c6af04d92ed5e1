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

The one backward-error rule (:func:`backward_error`, :func:`is_converged`): an iterate
is converged when ||residual|| <= atol + tol * it.scale (norm ``norm``), i.e. when its
backward error ||R|| / (scale + atol / tol) is at most tol.  ``it.scale`` is the force
scale of the equation at the iterate (the largest load, body and contact force), and
``atol / tol`` a reference force of the problem's *data* (the force its prescribed
displacement or load produces, e.g. :func:`hpfebe.scenes.stamping.reference_force`),
never a constant: the rule is then scale-free (it does not change when lengths, moduli
or prescribed displacements are scaled together with the forces), and an iterate whose
forces are round-off of the data forces (a rigid lift without load) is converged.  A
constant floor is not: above the forces of a tiny prescribed displacement it accepts
the start (measured: a stamp pressed by 4.2e-12 "converged" after 0 Newton iterations
with a force 14.7 x the linear one).  The merit is whatever the problem's globalisation
needs: an energy for a potential problem (penalty, Tresca), ||R||_2 otherwise
(Coulomb).
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


def backward_error(it: Iterate, norm, tol: float = 0.0, atol: float = 0.0) -> float:
    """||R|| / (scale + atol / tol): the relative residual of the equation at the
    iterate, against its force scale and the problem's reference force atol / tol (the
    floor of the stopping test; module doc).  Scale-free."""
    ref = atol / tol if tol > 0 else 0.0
    return residual_norm(it.residual, norm) / max(it.scale + ref, np.finfo(float).tiny)


def is_converged(it: Iterate, norm, tol: float, atol: float = 0.0) -> bool:
    """The stopping test of the module doc: ||R|| <= atol + tol * scale (backward error
    at most tol)."""
    return residual_norm(it.residual, norm) <= atol + tol * it.scale


# accepted backward error of an iterate Newton cannot improve (six digits in the
# equation; the stopping tolerance itself is usually far smaller)
BACKWARD_TOL = 1e-6


def roundoff_verdict(info: SolverInfo, it: Iterate, norm, what: str, tol: float = 0.0,
                     atol: float = 0.0) -> None:
    """Newton cannot improve the iterate any more: accept it only if its backward error
    ||R|| / (scale + atol / tol) (:func:`backward_error`: the relative residual of the
    equation, scale-free) is below BACKWARD_TOL; otherwise the system is too
    ill-conditioned for the answer to be trusted."""
    be = backward_error(it, norm, tol, atol)
    info.backward_error = be
    if be <= BACKWARD_TOL:
        info.converged = True
        info.reason = (f"converged ({what}; backward error {be:.1e}, the residual is "
                       "limited by the conditioning)")
    else:
        info.reason = (f"ill-conditioned: {what} with backward error {be:.1e} > "
                       f"{BACKWARD_TOL:.1e}; the answer cannot be trusted")
