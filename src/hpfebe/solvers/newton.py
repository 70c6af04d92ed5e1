"""Semismooth Newton with an Armijo line search on a merit function (:func:`newton`):
round-off, cycling and divergence detection, an optional predictor; the problem is a
:class:`~hpfebe.solvers.info.NewtonProblem` (residual, step, slope), the result a
:class:`~hpfebe.solvers.info.SolverInfo`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..checks import array, integer, real
from .info import EPS, Iterate, NewtonProblem, SingularStep, SolverInfo, backward_error, \
    is_converged, residual_norm, roundoff_verdict


@dataclass
class LineSearch:
    """Armijo backtracking: accept alpha in 1, 1/2, 1/4, ... with
    merit(x + alpha dx) <= merit(x) + c alpha slope + slack |merit(x)|; after
    ``max_halvings`` halvings either fail ("line search failed") or, with
    ``accept_last``, take the last trial step.  ``enabled=False``: always the full
    step.  ``refine``: when the accepted alpha is below 1, halve it further (at most
    ``refine`` times, within ``max_halvings``) while the merit decreases, and take the
    lowest merit: residual evaluations are cheap beside a Newton system, and the first
    acceptable alpha of a far iterate is often not the best one (measured, Example 1 of
    Section 4.2.7, h = 0.05: first increment 40 -> 24 iterations with refine = 3, the
    residual evaluations about the same)."""

    c: float = 1e-4
    slack: float = 1e-14
    max_halvings: int = 30
    accept_last: bool = False
    enabled: bool = True
    refine: int = 0


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
        if ok and alpha < 1.0 and ls.refine > 0:
            return _refined(problem, it, dx, ls, alpha, trial, k)
        if ok or (ls.accept_last and k == ls.max_halvings):
            return alpha, trial
        alpha *= 0.5
    return alpha, None


def _refined(problem, it: Iterate, dx: np.ndarray, ls: LineSearch, alpha: float, trial,
             k: int):
    """The accepted (alpha, trial) of :func:`_line_search` halved further while the
    merit decreases (``ls.refine`` times at most, ``ls.max_halvings`` in all)."""
    best, last = (alpha, trial), trial
    for _ in range(min(int(ls.refine), ls.max_halvings - k)):
        a = 0.5 * best[0]
        last = problem.evaluate(it.x + a * dx)
        if not (np.isfinite(last.merit) and last.merit < best[1].merit):
            break
        best = (a, last)
    if last is not best[1]:
        # the problem's last evaluation is the returned iterate (bodies caching their
        # state at the last point see the point taken)
        best = (best[0], problem.evaluate(best[1].x))
    return best


def newton(problem: NewtonProblem, x0: np.ndarray, tol: float, max_iter: int = 50,
           atol: float = 0.0, norm=np.inf, line_search: LineSearch | None = None,
           predictor: Callable[[Iterate], np.ndarray | None] | None = None,
           roundoff_stop: bool = False, divergence: float = 1e12):
    """Semismooth Newton from x0.

    Parameters
    ----------
    problem : NewtonProblem
        ``evaluate(x) -> Iterate``, ``step(it) -> dx``, ``slope(it, dx)``
    x0 : ndarray
        the start
    tol : float
        the relative tolerance of the stopping test (required)
    max_iter : int
        at most this many iterations (default 50)
    atol : float
        the absolute part of the stopping test (default 0)
    norm : float
        the order of the residual norm (default inf)
    line_search : LineSearch, optional
        the backtracking rule (default ``LineSearch()``)
    predictor : callable, optional
        ``predictor(it) -> x or None``, a first candidate (see below)
    roundoff_stop : bool
        stop at round-off level updates (see below; default False)
    divergence : float
        the factor of the divergence test (default 1e12)

    Returns
    -------
    it : Iterate
        the final iterate; the solution is ``it.x``
    info : SolverInfo
        ``converged``, ``reason``, ``iterations``, the residual history and
        ``backward_error``

    Notes
    -----
    Stopping test (the backward-error rule of :mod:`.info`): ||R|| <= atol + tol * scale,
    ``atol`` tol times a reference force of the problem's data (never a constant: a
    floor above the forces of the data accepts a wrong start).
    ``info.backward_error`` is ||R|| / (scale + atol / tol) of the returned iterate.

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
    tol = real("tol", tol, nonnegative=True)
    atol = real("atol", atol, nonnegative=True)
    if tol == 0 and atol == 0:
        raise ValueError("tol and atol must not both be zero")
    max_iter = integer("max_iter", max_iter, lo=0)
    x0 = array("x0", x0)
    ls = line_search or LineSearch()
    integer("line_search.refine", ls.refine, lo=0)
    it = problem.evaluate(x0)
    info = SolverInfo(False, "max_iter", 0, [residual_norm(it.residual, norm)], [],
                      [it.merit])
    it, info = _iterate(problem, it, info, tol, max_iter, atol, norm, ls, predictor,
                        roundoff_stop, divergence)
    info.backward_error = backward_error(it, norm, tol, atol)
    return it, info


def _iterate(problem, it, info, tol, max_iter, atol, norm, ls, predictor, roundoff_stop,
             divergence):
    """The iteration of :func:`newton` from the evaluated start ``it``."""
    res = info.residuals

    def done(i: Iterate) -> bool:
        return is_converged(i, norm, tol, atol)

    if done(it):
        info.converged, info.reason = True, "converged"
        return it, info
    if predictor is not None:
        cand = predictor(it)
        if cand is not None:
            pit = problem.evaluate(cand)
            if np.all(np.isfinite(pit.residual)) and pit.merit < it.merit:
                it, info.predictor_used, info.iterations = pit, True, 1
                res.append(residual_norm(it.residual, norm))
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
            roundoff_verdict(info, it, norm, "Newton update at round-off level", tol,
                             atol)
            return it, info
        alpha, new = _line_search(problem, it, dx, ls)
        if new is None:
            info.reason = "line search failed"
            return it, info
        it = new
        info.iterations = k
        info.step_lengths.append(alpha)
        r = residual_norm(it.residual, norm)
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
                    roundoff_verdict(info, it, norm, "stagnation at round-off level",
                                     tol, atol)
                else:
                    info.reason = (f"cycling: contact state of iterate {seen[it.key][0]} "
                                   f"repeated at {k} without decrease of the merit")
                return it, info
            seen[it.key] = (k, it.merit)
    info.reason = "max_iter"
    return it, info
