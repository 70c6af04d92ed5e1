"""The readings of Chapters 2-3 (hpfebe.scenes.interface_readings, penalty_readings,
adaptive_bem_readings) on small hand-made tables: each verdict flips with its data."""

import numpy as np
import pandas as pd

from hpfebe.scenes import adaptive_bem_readings as ar, interface_readings as ir, \
    penalty_readings as pr


def test_first_linear_mesh_and_monotone_order():
    n = np.array([2, 4, 8, 16])
    assert pr.first_linear(n, [0.5, 0.9, 1.0], 0.15) == 8
    assert pr.first_linear(n, [0.5, 0.6, 0.7], 0.15) is None
    assert pr.monotone([16, 8, 8]) and pr.monotone([None, 16, 4])
    assert not pr.monotone([8, 16])


def test_penalty_newton_bound():
    data = pd.DataFrame(dict(newton_iterations=[1, 3], final_residual=[1e-12, 1e-11],
                             min_pressure=[0.0, 0.1]))
    assert pr.newton(data)[0] is True
    assert pr.newton(data.assign(newton_iterations=[1, 11]))[0] is False


def test_interface_factor_2_and_exponential():
    assert ir.factor_2(pd.Series([0.6, 1.9]))[0] is True
    holds, ev = ir.factor_2(pd.Series([0.6, 2.1]))
    assert holds is False and "2.100" in ev
    assert ir.exponential(pd.DataFrame(dict(fe_h1=[1.0, 0.2, 0.05])))[0] is True
    assert ir.exponential(pd.DataFrame(dict(fe_h1=[1.0, 0.5])))[0] is False
    assert ir.solution_range(0.001, 0.499, 0.5)[0] and not ir.solution_range(0, 0.4, 0.5)[0]


def test_interface_max_rel_diff_and_threshold_growth():
    a = pd.DataFrame({c: [1.0, 2.0] for c in ir.ERRORS})
    assert ir.max_rel_diff(a, a) == 0.0
    assert np.isclose(ir.max_rel_diff(a.assign(fe_l2=[1.1, 2.0]), a), 0.1)
    main = pd.DataFrame(dict(alpha=0.0, p=[1, 2, 3], lambda_star=[1.5, 4.0, 8.0],
                             lemma_bound=[2.0, 5.0, 7.0]))
    assert ir.threshold_growth(main)[0] is True
    assert ir.lemma(main)[0] is False      # 8 > 7 at p = 3


def test_adaptive_late_undecided_with_few_steps():
    holds, ev = ar.late([{}, {}, {}])
    assert holds is None and "2 refinement steps" in ev
