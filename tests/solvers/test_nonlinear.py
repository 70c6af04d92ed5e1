"""Tests of the one iteration layer (hpfebe.solvers)."""

import numpy as np
import pytest

from hpfebe.solvers import SolverInfo, fixed_point


def test_fixed_point_converges_on_a_contraction():
    x, info = fixed_point(lambda x: 0.5 * x + 1.0, np.zeros(3), tol=1e-12)
    assert info.converged and np.allclose(x, 2.0, atol=1e-11)
    assert info.iterations == len(info.residuals) > 30


def test_fixed_point_detects_divergence_and_the_cap():
    x, info = fixed_point(lambda x: -1.5 * x + 1.0, np.zeros(2), tol=1e-10, max_iter=500)
    assert not info.converged and info.reason.startswith("diverged")
    x, info = fixed_point(lambda x: -x + 1.0, np.zeros(2), tol=1e-10, max_iter=7)
    assert not info.converged and info.reason == "max_iter" and info.iterations == 7


def test_fixed_point_stops_on_a_failed_inner_solve():
    bad = SolverInfo(False, "line search failed")
    x, info = fixed_point(lambda x: (x + 1, bad), np.zeros(1), tol=1e-8)
    assert not info.converged and "line search failed" in info.reason
    assert info.steps == [bad]


@pytest.mark.parametrize("kw", [{"tol": 0.0}, {"tol": np.nan}, {"max_iter": 0},
                                {"max_iter": True}])
def test_fixed_point_bad_input(kw):
    args = dict(tol=1e-8)
    args.update(kw)
    with pytest.raises(ValueError, match=list(kw)[0]):
        fixed_point(lambda x: x, np.zeros(1), **args)
