"""The Chapter 2 scene's tables (hpfebe.scenes.interface): the published-format part
tables with their observed rates, the work-precision timings, the solution fields."""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe.scenes import interface


def _sweep():
    """A synthetic sweep: series h at p = 1, 2 (e = h^(p+1), h^p), series p on one mesh
    (e = 2^-p), rows deliberately out of order."""
    rows = []
    for p in (2, 1):
        for fh in (8, 2, 4):
            rows.append(dict(series="h", p=p, fe_h_inv=fh, be_h_inv=fh + 1, dof=10 * fh,
                             fe_l2=fh ** -(p + 1.0), fe_h1=fh ** -float(p),
                             be_l2=2.0 * fh ** -(p + 1.0), be_h1=3.0 * fh ** -float(p),
                             be_energy=fh ** -1.5, be_h1_interp=fh ** -1.0,
                             wall_time_s=0.1, lambda_nit=10.0))
    for p in (1, 3, 2):
        rows.append(dict(series="p", p=p, fe_h_inv=4, be_h_inv=6, dof=50 * p,
                         fe_l2=2.0 ** -p, fe_h1=2.0 ** -p, be_l2=2.0 ** -p, be_h1=2.0 ** -p,
                         be_energy=2.0 ** -p, be_h1_interp=2.0 ** -p, wall_time_s=0.1,
                         lambda_nit=10.0))
    return {k: [r[k] for r in rows] for k in rows[0]}


def test_part_table_sorts_groups_and_measures_rates():
    t = interface.part_table(_sweep(), "fe", "fe_h_inv")
    # groups in the order of the sweep (h: p = 2 then 1; then p), sorted within
    assert list(t["series"]) == ["h"] * 6 + ["p"] * 3
    assert list(t["p"]) == [2, 2, 2, 1, 1, 1, 1, 2, 3]
    assert list(t["h_inv"][:3]) == [2, 4, 8] and t["h_inv"].dtype.kind == "i"
    r = t["l2_rate"]
    assert np.isnan(r[0]) and np.isnan(r[3]) and np.isnan(r[6])
    assert np.allclose(r[[1, 2]], 3.0) and np.allclose(r[[4, 5]], 2.0)
    assert np.allclose(t["h1_rate"][[1, 2, 4, 5]], [2, 2, 1, 1])
    # series p: rates w.r.t. p of e = 2^-p: log(2) / log(p / p_prev)
    assert np.allclose(r[7:], [np.log(2) / np.log(2), np.log(2) / np.log(1.5)])
    assert "trace_energy_error" not in t


def test_part_table_be_adds_the_trace_energy_columns():
    t = interface.part_table(_sweep(), "be", "be_h_inv")
    assert list(t["h_inv"][:3]) == [3, 5, 9]
    assert np.allclose(t["trace_energy_error"][:3], np.array([2, 4, 8]) ** -1.5)
    assert np.isnan(t["trace_energy_rate"][0])
    assert np.allclose(t["h1_error"][:3], 3.0 * np.array([2, 4, 8]) ** -2.0)


def test_work_precision_rows_take_the_minimum_of_the_repeats():
    # the sweep's own timing (1e3 s each) is slower than any real one of this tiny run,
    # and within the (large) budget: the minimum is a repeat's, the maximum the sweep's
    prm = interface.ConvergenceScene(timing_repeats=2, timing_budget_s=1e4)
    rows = [dict(problem="smooth", series="h", p=1, fe_h_inv=2, be_h_inv=3,
                 assembly_s=1e3, solve_s=1e3, wall_time_s=2e3, fe_h1=0.1)]
    out = interface.work_precision_rows(prm, rows)
    assert out[0]["fe_h1"] == 0.1
    assert out[0]["assembly_s"] < 1e3 and out[0]["solve_s"] < 1e3
    assert out[0]["wall_time_s"] < out[0]["wall_time_max_s"] == 2e3
    assert out[0]["timings"] == 2


def test_work_precision_rows_stop_repeating_a_run_at_the_timing_budget():
    # 200 s of (recorded) timings is past the 100 s budget: that run keeps its one
    # timing; the other (0.1 s recorded, real solves of a tiny run well below 100 s on
    # any machine) is timed timing_repeats times
    prm = interface.ConvergenceScene(timing_repeats=3, timing_budget_s=100.0)
    rows = [dict(problem="smooth", series="h", p=1, fe_h_inv=2, be_h_inv=3,
                 assembly_s=a, solve_s=a, wall_time_s=2 * a) for a in (100.0, 0.05)]
    slow, fast = interface.work_precision_rows(prm, rows)
    assert slow["timings"] == 1
    assert slow["wall_time_s"] == slow["wall_time_max_s"] == 200.0
    assert fast["timings"] == 3 and fast["wall_time_s"] <= 0.1


@pytest.mark.parametrize("bad", [dict(timing_repeats=0), dict(timing_repeats="3"),
                                 dict(timing_budget_s=0.0), dict(timing_budget_s=np.nan)])
def test_convergence_scene_rejects_bad_timing_parameters(bad):
    with pytest.raises((TypeError, ValueError), match="timing_"):
        interface.ConvergenceScene(**bad)


def test_solution_fields_meet_the_exact_solution():
    model, sol, d2, vals = interface.solution_fields("smooth", 5, 6, 10.0)
    x, y = d2.p
    assert vals.shape == (d2.p.shape[1],)
    assert np.max(np.abs(vals - interface.problem("smooth").u(x, y))) < 0.02
    with pytest.raises(ValueError, match="problem"):
        interface.solution_fields("smoth", 5, 6, 10.0)
