"""The one load path (Algorithm 4.1, :func:`load_path`): Newton for each load factor of an
increasing sequence; a problem's history (e.g. the slip of a friction law, the plastic
state of a body) is updated by ``commit(x)`` only after a converged step, and a failed
step is halved and retried from the committed state (at most ``max_cuts`` times)."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..checks import array, boolean, integer, real
from .info import Iterate, NewtonProblem, SolverInfo
from .newton import newton


class LoadStep(Protocol):
    """One load factor of a load path: a Newton problem, its start and its commit."""

    def problem(self, lam: float) -> NewtonProblem: ...

    def start(self, x: np.ndarray, lam: float) -> np.ndarray: ...

    def commit(self, it: Iterate) -> None: ...

    def record(self, it: Iterate, info: SolverInfo) -> None: ...


def load_path(steps: LoadStep, factors, x0: np.ndarray, max_cuts: int = 0,
              lam0: float = 0.0, cuts_per_step: bool = False, **newton_kw):
    """Algorithm 4.1: Newton for every load factor of a sequence, the history committed
    after each converged step; a failed step is cut in half and retried from the
    committed state.

    Parameters
    ----------
    steps : LoadStep
        the problem at each load factor (``problem``, ``start``, ``commit``, ``record``)
    factors : sequence of float
        the load factors, usually increasing (an unloading path may turn back); none
        repeats the one before
    x0 : ndarray
        the start of the first step
    max_cuts : int
        how many times a failed step may be halved, in all (default 0: no cuts)
    lam0 : float
        the load factor of ``x0`` (default 0)
    cuts_per_step : bool
        count ``max_cuts`` between two factors of ``factors`` instead of in all
    **newton_kw
        passed to :func:`~hpfebe.solvers.newton` (``tol`` is required)

    Returns
    -------
    it : Iterate
        the last iterate; the solution is ``it.x``
    info : SolverInfo
        ``converged`` and ``reason`` of the path, the Newton iterations in all, and in
        ``info.steps`` one SolverInfo per attempted step (cuts included), each with its
        ``load_factor``
    """
    factors = array("load factors", factors, ndim=1, min_size=1)
    lam0 = real("lam0", lam0)
    # loading and unloading alike (a path may turn back); a repeated factor is a step of
    # length zero, whose cut would be the committed state itself
    if np.any(np.diff(np.concatenate([[lam0], factors])) == 0):
        raise ValueError(f"load factors must each differ from the one before (the first "
                         f"from lam0 = {lam0:g}), got {factors.tolist()!r}")
    max_cuts = integer("max_cuts", max_cuts, lo=0)
    cuts_per_step = boolean("cuts_per_step", cuts_per_step)
    queue = [float(f) for f in factors]
    given = set(queue)              # the factors asked for (the others are cuts)
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
            if cuts_per_step and lam in given:
                cuts = 0
        elif cuts < max_cuts:
            cuts += 1
            queue.insert(0, 0.5 * (lam_done + lam))
        else:
            total.converged = False
            n = len(total.steps)
            total.reason = f"load step {n}/{n + len(queue) - 1}: {info.reason}"
            break
    return last, total
