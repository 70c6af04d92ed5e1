"""LineSearch.refine (hpfebe.solvers.newton): an accepted step below 1 is halved further
while the merit decreases, and the lowest merit is taken."""

import numpy as np
import pytest

from hpfebe.solvers import Iterate, LineSearch, newton


class Arctan:
    """R(x) = arctan(x) componentwise: full Newton steps overshoot from |x| > 1.39."""

    def __init__(self):
        self.points = []               # every evaluated x

    def evaluate(self, x):
        self.points.append(np.array(x, dtype=float))
        r = np.arctan(x)
        return Iterate(np.array(x, dtype=float), r, float(np.linalg.norm(r)))

    def step(self, it):
        return -it.residual * (1.0 + it.x ** 2)

    def slope(self, it, dx):
        return -it.merit


def _merit(x):
    return float(np.linalg.norm(np.arctan(x)))


def test_refine_takes_the_lowest_merit_of_the_halvings():
    x0 = np.array([5.5])     # Armijo accepts alpha = 1/4 (|R| 1.39), 1/8 is far lower
    plain, pinfo = newton(Arctan(), x0, tol=1e-12, line_search=LineSearch(slack=0.0))
    pr = Arctan()
    ref, rinfo = newton(pr, x0, tol=1e-12, line_search=LineSearch(slack=0.0, refine=4))
    assert pinfo.converged and rinfo.converged
    assert abs(ref.x[0]) < 1e-12 and abs(plain.x[0]) < 1e-12
    # the first step: plain Armijo takes the first acceptable alpha, refine a smaller one
    # with a lower merit, the lowest among alpha, alpha / 2, ... tried
    dx0 = -np.arctan(x0) * (1 + x0 ** 2)
    a_plain, a_ref = pinfo.step_lengths[0], rinfo.step_lengths[0]
    assert a_plain < 1.0 and a_ref < a_plain
    assert _merit(x0 + a_ref * dx0) < _merit(x0 + a_plain * dx0)
    assert _merit(x0 + a_ref * dx0) <= _merit(x0 + 0.5 * a_ref * dx0) or \
        a_ref == a_plain / 2 ** 4
    assert rinfo.iterations <= pinfo.iterations
    # the problem's last evaluation is the iterate taken
    np.testing.assert_array_equal(pr.points[-1], ref.x)


def test_refine_zero_is_plain_armijo_and_full_steps_are_kept():
    x0 = np.array([6.0, -3.0])
    a, ai = newton(Arctan(), x0, tol=1e-12, line_search=LineSearch())
    b, bi = newton(Arctan(), x0, tol=1e-12, line_search=LineSearch(refine=0))
    np.testing.assert_array_equal(a.x, b.x)
    assert ai.step_lengths == bi.step_lengths
    # near the root Newton's full step is accepted and not refined
    c, ci = newton(Arctan(), np.array([0.5]), tol=1e-12, line_search=LineSearch(refine=5))
    assert ci.converged and set(ci.step_lengths) == {1.0}


@pytest.mark.parametrize("bad", [-1, 1.5, True])
def test_refine_bad_input_is_named(bad):
    with pytest.raises(ValueError, match="refine"):
        newton(Arctan(), np.array([1.0]), tol=1e-8, line_search=LineSearch(refine=bad))
