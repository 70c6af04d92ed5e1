"""The one home of iteration: semismooth Newton with a line search on a merit function,
round-off, cycling and divergence detection, a load path (increments, commit on
convergence, step cut and retry on failure), and one :class:`SolverInfo` returned by
every solver.

A problem tells Newton three things (the :class:`NewtonProblem` protocol):

    evaluate(x) -> Iterate      residual on the free unknowns, merit, force scale of the
                                stopping test, contact pattern (for cycling), data
    step(it)    -> dx           the Newton step: J(x) dx = -residual (raise
                                :class:`SingularStep` with the reason if it cannot)
    slope(it, dx) -> float      directional derivative of the merit along dx

Stopping test: ||residual|| <= atol + tol * it.scale (norm ``norm``).  The merit is
whatever the problem's globalisation needs: an energy for a potential problem (penalty,
Tresca), ||R||_2 otherwise (Coulomb).

A load path (:func:`load_path`) runs Newton for each load factor of an increasing
sequence; a problem's history (e.g. the slip of a friction law) is updated by
``commit(x)`` only after a converged step, and a failed step is halved and retried from
the committed state (at most ``max_cuts`` times).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Protocol

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


@dataclass
class LineSearch:
    """Armijo backtracking: accept alpha in 1, 1/2, 1/4, ... with
    merit(x + alpha dx) <= merit(x) + c alpha slope + slack |merit(x)|; after
    ``max_halvings`` halvings either fail ("line search failed") or, with
    ``accept_last``, take the last trial step.  ``enabled=False``: always the full
    step."""

    c: float = 1e-4
    slack: float = 1e-14
    max_halvings: int = 30
    accept_last: bool = False
    enabled: bool = True


def _norm(r: np.ndarray, norm) -> float:
    if r.size == 0:
        return 0.0
    return float(np.abs(r).max()) if norm == np.inf else float(np.linalg.norm(r))


def _line_search(problem, it: Iterate, dx: np.ndarray, ls: LineSearch):
    """(alpha, new iterate) or (alpha, None) if the search failed."""
    if not ls.enabled:
        return 1.0, problem.evaluate(it.x + dx)
    slope = problem.slope(it, dx)
    alpha = 1.0
    for k in range(ls.max_halvings + 1):
        trial = problem.evaluate(it.x + alpha * dx)
        ok = np.isfinite(trial.merit) and \
            trial.merit <= it.merit + ls.c * alpha * slope + ls.slack * abs(it.merit)
        if ok or (ls.accept_last and k == ls.max_halvings):
            return alpha, trial
        alpha *= 0.5
    return alpha, None


# accepted backward error of an iterate Newton cannot improve (six digits in the
# equation; the stopping tolerance itself is usually far smaller)
BACKWARD_TOL = 1e-6


def _roundoff_verdict(info: SolverInfo, it: Iterate, norm, what: str) -> None:
    """Newton cannot improve the iterate any more: accept it only if its backward error
    ||R|| / scale (the relative residual of the equation, scale-free) is below
    BACKWARD_TOL; otherwise the system is too ill-conditioned for the answer to be
    trusted."""
    be = _norm(it.residual, norm) / max(it.scale, np.finfo(float).tiny)
    info.backward_error = be
    if be <= BACKWARD_TOL:
        info.converged = True
        info.reason = (f"converged ({what}; backward error {be:.1e}, the residual is "
                       "limited by the conditioning)")
    else:
        info.reason = (f"ill-conditioned: {what} with backward error {be:.1e} > "
                       f"{BACKWARD_TOL:.1e}; the answer cannot be trusted")


def newton(problem: NewtonProblem, x0: np.ndarray, tol: float, max_iter: int = 50,
           atol: float = 0.0, norm=np.inf, line_search: LineSearch | None = None,
           predictor: Callable[[Iterate], np.ndarray | None] | None = None,
           roundoff_stop: bool = False, divergence: float = 1e12):
    """Semismooth Newton from x0.  Returns (final iterate, SolverInfo).

    ``predictor``: an optional first candidate (e.g. a linear "bonded" solution), taken
    when its merit is lower; it counts as an iteration.  ``roundoff_stop``: a Newton
    update at round-off level relative to x ends the iteration as converged (for
    ill-conditioned systems whose residual floor lies above tol) - as converged only if
    the backward error ||R|| / scale is below BACKWARD_TOL = 1e-6, else
    "ill-conditioned".  Cycling: a contact
    pattern (``Iterate.key``) met before without decrease of the merit since then ends
    the iteration ("cycling"), or as converged if the step was at round-off level
    (stagnation).  Divergence: a non-finite residual, or one above ``divergence`` times
    the initial residual and force scale."""
    ls = line_search or LineSearch()
    it = problem.evaluate(np.asarray(x0, dtype=float))
    res = [_norm(it.residual, norm)]
    info = SolverInfo(False, "max_iter", 0, res, [], [it.merit])

    def done(i: Iterate) -> bool:
        return _norm(i.residual, norm) <= atol + tol * i.scale

    if done(it):
        info.converged, info.reason = True, "converged"
        return it, info
    if predictor is not None:
        cand = predictor(it)
        if cand is not None:
            pit = problem.evaluate(cand)
            if np.all(np.isfinite(pit.residual)) and pit.merit < it.merit:
                it, info.predictor_used, info.iterations = pit, True, 1
                res.append(_norm(it.residual, norm))
                info.merits.append(it.merit)
                if done(it):
                    info.converged, info.reason = True, "converged"
                    return it, info
    seen = {}
    for k in range(info.iterations + 1, int(max_iter) + 1):
        try:
            dx = problem.step(it)
        except SingularStep as e:
            info.reason = str(e)
            return it, info
        xmax = np.abs(it.x).max(initial=0.0)
        if roundoff_stop and np.abs(dx).max(initial=0.0) <= 64 * EPS * xmax:
            # the k-th Newton system was solved (and counts), its update is not taken;
            # converged only if the backward error of the iterate is small
            info.iterations = k
            _roundoff_verdict(info, it, norm, "Newton update at round-off level")
            return it, info
        alpha, new = _line_search(problem, it, dx, ls)
        if new is None:
            info.reason = "line search failed"
            return it, info
        it = new
        info.iterations = k
        info.step_lengths.append(alpha)
        r = _norm(it.residual, norm)
        res.append(r)
        info.merits.append(it.merit)
        if not np.isfinite(r) or r > divergence * max(res[0], it.scale):
            info.reason = f"diverged: residual {r:.3e} at iteration {k}"
            return it, info
        if done(it):
            info.converged, info.reason = True, "converged"
            return it, info
        if it.key is not None:
            if it.key in seen and it.merit >= seen[it.key][1] - 1e-14 * abs(it.merit):
                if alpha * np.abs(dx).max() <= 1e-8 * np.abs(it.x).max():
                    _roundoff_verdict(info, it, norm, "stagnation at round-off level")
                else:
                    info.reason = (f"cycling: contact state of iterate {seen[it.key][0]} "
                                   f"repeated at {k} without decrease of the merit")
                return it, info
            seen[it.key] = (k, it.merit)
    info.reason = "max_iter"
    return it, info


class LoadStep(Protocol):
    """One load factor of a load path: a Newton problem, its start and its commit."""

    def problem(self, lam: float) -> NewtonProblem: ...

    def start(self, x: np.ndarray, lam: float) -> np.ndarray: ...

    def commit(self, it: Iterate) -> None: ...

    def record(self, it: Iterate, info: SolverInfo) -> None: ...


def load_path(steps: LoadStep, factors, x0: np.ndarray, max_cuts: int = 0,
              lam0: float = 0.0, **newton_kw):
    """Algorithm 4.1: Newton for every load factor of the increasing sequence
    ``factors``, the history committed after each converged step; a failed step is cut
    in half and retried from the committed state, at most ``max_cuts`` times in all.
    Returns (last iterate, SolverInfo with one SolverInfo per attempted step in
    ``steps``)."""
    queue = [float(f) for f in factors]
    x, last = np.asarray(x0, dtype=float), None
    total = SolverInfo(True, "converged")
    cuts = 0
    lam_done = lam0
    while queue:
        lam = queue[0]
        it, info = newton(steps.problem(lam), steps.start(x, lam), **newton_kw)
        info.load_factor = lam
        steps.record(it, info)
        total.steps.append(info)
        total.iterations += info.iterations
        last = it
        if info.converged:
            steps.commit(it)
            x, lam_done = it.x, lam
            queue.pop(0)
        elif cuts < max_cuts:
            cuts += 1
            queue.insert(0, 0.5 * (lam_done + lam))
        else:
            total.converged = False
            n = len(total.steps)
            total.reason = f"load step {n}/{n + len(queue) - 1}: {info.reason}"
            break
    return last, total


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
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be positive and finite, got {tol!r}")
    if isinstance(max_iter, bool) or int(max_iter) != max_iter or max_iter < 1:
        raise ValueError(f"max_iter must be a positive integer, got {max_iter!r}")
    x = np.asarray(x0, dtype=float)
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
        inc = _norm(x_new - x, norm)
        info.iterations = k
        info.residuals.append(inc)
        if not np.isfinite(inc) or not np.all(np.isfinite(x_new)):
            info.reason = f"diverged: non-finite iterate at iteration {k}"
            return x, info
        x = x_new
        if inc <= tol * max(_norm(x, norm), np.finfo(float).tiny) and k >= min_iter:
            info.converged, info.reason = True, "converged"
            return x, info
        if inc > divergence * smallest:
            info.reason = (f"diverged: increment {inc:.3e} at iteration {k} exceeds "
                           f"{divergence:g} x the smallest ({smallest:.3e})")
            return x, info
        smallest = min(smallest, inc)
    return x, info
