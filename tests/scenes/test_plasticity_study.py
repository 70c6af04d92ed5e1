"""The study of Section 4.2.7 in hpfebe.scenes.plasticity / plasticity_fields: the
parameters refuse what the figures cannot use, the load branches and tables read the
records right, and the field measures hold on one small run (a dent, zero difference of
a run to itself, exports of every touch)."""

from types import SimpleNamespace

import numpy as np
import pytest

from hpfebe.scenes import StepRecord, TouchResult, plasticity, plasticity_fields


def _rec(touch, phase, force, dev, its=3):
    return StepRecord(touch, phase, 0.0, force, dev, 0.0, its, 1)


def _run(records_per_touch, converged=True, h=0.5):
    touches = [TouchResult(records=list(r), converged=converged) for r in records_per_touch]
    return plasticity.Run(1, "FE", 1.0, h, "bbar", None, touches, 0.0)


@pytest.mark.parametrize("kw,name", [
    (dict(thetas=(1.5,)), "thetas"), (dict(thetas=()), "thetas"),
    (dict(h_levels=()), "h_levels"), (dict(h_levels=(0.2, -0.1), h_figure=0.2), "h_levels"),
    (dict(h_figure=0.3), "h_figure"), (dict(bebe_h_levels=(0.4, 0.5)), "bebe_h_levels"),
    (dict(close_tol=0.0), "close_tol"), (dict(zone_tol=-1.0), "zone_tol"),
    (dict(n_load=0), "n_load")])
def test_study_refuses_bad_parameters(kw, name):
    with pytest.raises(ValueError, match=name):
        plasticity.StampingStudy(**kw)


def test_branch_starts_where_the_previous_touch_ended():
    """Figure 4.5's curves: touch 2 starts at touch 1's last (unloaded) state; the
    unloading increments are not part of a loading branch."""
    r = _run([[_rec(1, "load", 1.0, 2.0), _rec(1, "load", 2.0, 3.0),
               _rec(1, "unload", 0.1, 1.5)],
              [_rec(2, "load", 1.5, 2.5), _rec(2, "unload", 0.2, 1.0)]])
    f1, s1 = r.branch(1)
    np.testing.assert_array_equal(f1, [0.0, 1.0, 2.0])
    np.testing.assert_array_equal(s1, [0.0, 2.0, 3.0])
    f2, s2 = r.branch(2)
    np.testing.assert_array_equal(f2, [0.1, 1.5])
    np.testing.assert_array_equal(s2, [1.5, 2.5])
    assert r.iterations == [3] * 5
    np.testing.assert_array_equal(r.load_curve("force"), [1.0, 2.0, 1.5])


def test_successive_differences_and_rows():
    a = _run([[_rec(1, "load", 1.0, 2.0), _rec(1, "load", 2.0, 4.0)]])
    b = _run([[_rec(1, "load", 1.0, 2.0), _rec(1, "load", 2.0, 5.0)]])
    c = _run([[_rec(1, "load", 1.0, 2.0), _rec(1, "load", 2.0, 5.0)]], converged=False)
    # relative to the finer run's peak: |5 - 4| / 5
    assert plasticity.successive_differences([a, b, c]) == [pytest.approx(0.2), None]
    runs = {(1, "FE", 1.0, 0.5, "bbar"): a, (2, "BE", 1.0, 0.5, "bbar"): b}
    rows = plasticity.curve_rows(runs, 1)
    assert [r["increment"] for r in rows] == [1, 2] and rows[0]["coupling"] == "FE/FE"
    rows = plasticity.bebe_rows({1.0: {"BE/BE": a, "FE/FE": b}})
    assert [r["coupling"] for r in rows] == ["BE/BE"] * 2 + ["FE/FE"] * 2
    stats = plasticity.run_statistics(runs, [("BE/BE theta=1", c)])
    assert stats["runs"] == 2 and stats["newton_total"] == 12
    assert stats["all_converged"] is False         # the BE/BE run failed


def test_peak_plastic_area_of_bebe_cells():
    peak = SimpleNamespace(fields={"eps_p_norm": np.array([0.0, 2e-4, 5e-4])})
    fe = SimpleNamespace(cells=SimpleNamespace(areas=np.array([1.0, 2.0, 4.0])))
    run = plasticity.Run(2, "BE/BE", 1.0, 1.0, "crossed", fe,
                         [TouchResult(peak=peak)], 0.0)
    assert plasticity_fields.peak_plastic_area(run, 1e-4) == 6.0
    assert plasticity_fields.peak_plastic_area(run, 1e-3) == 0.0


@pytest.fixture(scope="module")
def small_run():
    prm = plasticity.StampingStudy(h_levels=(1.0,), h_figure=1.0, n_load=3, n_unload=1)
    return prm, prm.run_example(2, "FE", 1.0, 1.0)


def test_fields_of_one_small_run(small_run):
    prm, run = small_run
    assert run.converged, run.touches[-1].reason
    ((k, mean, deepest),) = plasticity_fields.dent_depths(run)
    assert k == 1 and 0 < mean <= deepest <= 1.1 * prm.ex2_u     # a permanent dent
    assert plasticity_fields.zone_comparison(run, run, prm.zone_tol) == (0.0, 0.0)
    assert plasticity.plastic_area(run, prm.zone_tol) > 0
    pw, cw, ps, cs = plasticity_fields.deformed_bodies(run, run.touches[0].peak, 100.0, 1.0)
    assert pw.shape == (run.fe.mesh.p.shape[1], 2) and cw.max() < len(pw)
    assert cs.max() < len(ps)
    assert set(plasticity_fields.touch_exports(run, "FEFE", 1.0)) == {
        "FEFE_touch1_work", "FEFE_touch1_stamp"}
    row, = plasticity.summary_rows(prm, {(2, "FE", 1.0, 1.0, "bbar"): run}, 2)
    assert row["converged"] and row["newton_total"] == sum(run.iterations)
