"""The one load path (hpfebe.solvers.load_path): commit on convergence, cut and retry,
the cut budget in all or per given load factor."""

import numpy as np

from hpfebe.solvers import Iterate, SingularStep, load_path


class _Steps:
    """x = lambda by one Newton step, which is refused (SingularStep) when the load
    factor moves more than ``reach`` from the committed one."""

    def __init__(self, reach: float):
        self.reach, self.done, self.lam = reach, 0.0, 0.0
        self.commits, self.tried = [], []

    def problem(self, lam):
        self.lam = lam
        self.tried.append(lam)
        return self

    def start(self, x, lam):
        return x.copy()

    def commit(self, it):
        self.done = self.lam
        self.commits.append(self.lam)

    def record(self, it, info):
        pass

    def evaluate(self, x):
        r = x - self.lam
        return Iterate(x, r, float(r @ r))

    def step(self, it):
        if abs(self.lam - self.done) > self.reach:
            raise SingularStep("step too long")
        return -it.residual

    def slope(self, it, dx):
        return -2.0 * it.merit


def test_cuts_in_all_and_per_step():
    # each unit increment needs three cuts: 1 -> 0.5 -> 0.25, 0.5, 1 -> 0.75, 1
    steps = _Steps(0.3)
    it, info = load_path(steps, [1.0, 2.0], np.zeros(1), max_cuts=3, tol=1e-12)
    assert not info.converged and info.reason.endswith("step too long")
    assert steps.commits == [0.25, 0.5, 0.75, 1.0]          # no cut left for 2.0
    steps = _Steps(0.3)
    it, info = load_path(steps, [1.0, 2.0], np.zeros(1), max_cuts=3, cuts_per_step=True,
                         tol=1e-12)
    assert info.converged, info.reason
    assert steps.commits == [0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0]
    assert np.allclose(it.x, 2.0) and len(info.steps) == len(steps.tried) == 14
    assert info.iterations == sum(s.iterations for s in info.steps)
