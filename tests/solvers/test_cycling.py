"""Cycling of the contact state is detected with and without a line search (issue 25's
leftover): the load steps of TwoBodyContact give every iterate its contact pattern as
the key, so a full-step Newton that returns to a pattern without decrease of the merit
reports "cycling", not "max_iter"."""

import numpy as np

from hpfebe.bodies import FEBody, RigidObstacle
from hpfebe.contact import ContactSettings, TwoBodyContact
from hpfebe.contact.loading import LoadSteps
from hpfebe.fem.elasticity import ElasticBody, rectangle_mesh
from hpfebe.solvers import newton


def _block_on_obstacle():
    """An elastic block pressed 1e-4 into a rigid obstacle (frictionless), its top held."""
    body = FEBody(ElasticBody(rectangle_mesh(0, 1, 0, 0.5, 4, 2), 1.0, 0.3))
    pr = TwoBodyContact(body, RigidObstacle(-1e-4), "bottom", eps_n=1e-3)
    return pr, body.dofs_on("top")


class _Alternating:
    """The load steps of ``steps`` whose Newton step jumps between the start x_a and a
    state x_b of another contact pattern: a two-cycle of full steps."""

    def __init__(self, steps, x_a, x_b):
        self.steps, self.x_a, self.x_b = steps, x_a, x_b

    def evaluate(self, x):
        return self.steps.evaluate(x)

    def slope(self, it, dx):
        return self.steps.slope(it, dx)

    def step(self, it):
        target = self.x_b if np.array_equal(it.x, self.x_a) else self.x_a
        return target - it.x


def test_full_step_newton_reports_cycling():
    pr, top = _block_on_obstacle()
    settings = ContactSettings(rtol=1e-12, max_iter=30, line_search=False)
    steps = LoadSteps(pr, None, top, 0.0, settings)
    steps.problem(1.0)
    x_a = steps.start(np.zeros(pr.ndofs), 1.0)
    x_b = x_a.copy()
    x_b[1::2] = 1e-3                     # lifted off: every contact point open
    it_a, it_b = steps.evaluate(x_a), steps.evaluate(x_b)
    assert it_a.key is not None and it_a.key != it_b.key     # the pattern is the key
    _, info = newton(_Alternating(steps, x_a, x_b), x_a, **settings.newton_options())
    assert not info.converged
    assert info.reason.startswith("cycling"), info.reason
    assert info.iterations < settings.max_iter


def test_full_step_newton_still_converges():
    """The check does not stop a full-step Newton that converges (the block's solve)."""
    pr, top = _block_on_obstacle()
    res = pr.solve(fixed_dofs=top, settings=ContactSettings(rtol=1e-10, max_iter=30))
    assert res.converged, res.reason
    assert np.all(res.p_n >= 0) and np.any(res.p_n > 0)
