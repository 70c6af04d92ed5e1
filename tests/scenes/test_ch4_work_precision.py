"""The Chapter 4 work-precision scene (hpfebe.scenes.ch4_work_precision): the Aitken
reference and its check, the fits, the parameters' errors, one real solve per
treatment, and the experiment's claims on a synthetic run."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hpfebe.scenes import ch4_work_precision as wp

ROOT = Path(__file__).resolve().parents[2]


def test_aitken_is_exact_on_a_geometric_sequence():
    # F(h) = 3 + 2 h^0.8 on h = 1/2, 1/4, 1/8: the limit 3 exactly
    f = 3.0 + 2.0 * np.array([0.5, 0.25, 0.125]) ** 0.8
    assert wp.aitken(f) == pytest.approx(3.0, rel=1e-12)
    assert wp.observed_rate(f) == pytest.approx(0.8, rel=1e-12)


def test_aitken_refuses_a_non_contracting_sequence():
    assert np.isnan(wp.aitken([1.0, 2.0, 4.0]))        # differences grow
    assert np.isnan(wp.aitken([1.0, 2.0, np.nan]))


def test_references_check_the_coarser_extrapolation():
    h = 1.0 / np.array([2, 4, 8, 16, 32])
    # an exact power law: both extrapolations agree, change 0
    r = wp.references(5.0 - h ** 0.8)
    assert r["reference"] == pytest.approx(5.0) and r["reference_change"] < 1e-12
    # a second term: the coarser triple is farther from the limit than the finer one
    r = wp.references(5.0 - h ** 0.8 + 0.3 * h ** 1.6)
    assert r["reference_change"] > 1e-4
    assert abs(r["reference"] - 5.0) < abs(r["reference_coarse"] - 5.0)
    # three meshes: no check possible (NaN, not a fabricated 0)
    assert np.isnan(wp.references((5.0 - h ** 0.8)[:3])["reference_change"])


def test_fit_slope_skips_non_positive_values():
    assert wp.fit_slope([1, 2, 4, 8], [1, 0.5, 0.25, 0.0]) == pytest.approx(-1.0)
    assert np.isnan(wp.fit_slope([1, 2], [1, np.nan]))


@pytest.mark.parametrize("kw, word", [(dict(ks=(2, 4)), "at least three"),
                                      (dict(ks=(2, 8, 4)), "increase"),
                                      (dict(factor=0.0), "factor"),
                                      (dict(omega_N=1.5), "omega_N"),
                                      (dict(timing_repeats=0), "timing_repeats")])
def test_parameters_name_the_bad_one(kw, word):
    with pytest.raises(ValueError, match=word):
        wp.WorkPrecisionScene(**kw)


def test_mesh_family_and_repeats():
    prm = wp.WorkPrecisionScene(repeat_max_k=8)
    q = prm.scene(4)
    assert tuple(q.stamp_cells) == (4, 8) and tuple(q.work_cells) == (16, 8)
    assert q.h_stamp == 0.25 and q.eps_n_factors == (10.0,)
    assert prm.repeats(8) == 2 and prm.repeats(16) == 1
    with pytest.raises(ValueError, match="treatment"):
        wp.solve(prm, "nitsche", 2)


def test_both_treatments_give_a_positive_force_of_the_same_size():
    """Coarsest mesh: both converge; the two treatments' forces (different discrete
    problems and friction laws) agree within 10 %, the mortar's vertical resultant
    carries no horizontal part (symmetric scene)."""
    prm = wp.WorkPrecisionScene(n_load=2)
    m, p = (wp.timed_solve(prm, tr, 2) for tr in wp.TREATMENTS)
    assert m["converged"] and p["converged"]
    assert m["force"] > 0 and p["force"] > 0
    assert abs(m["force"] / p["force"] - 1) < 0.1
    assert m["repeats"] == 2 and m["wall_max_s"] >= m["wall_s"] > 0


def test_rows_errors_against_each_treatments_own_reference():
    forces = {"mortar": lambda h: 7.0 + h ** 0.8, "penalty": lambda h: 6.0 + 2 * h ** 1.5}

    def fake(prm, tr, k):
        return dict(force=forces[tr](1.0 / k), converged=True, iterations=1, dof=k,
                    wall_s=1e-3 * k ** 2, wall_max_s=1e-3 * k ** 2, cpu_s=1e-3, repeats=1)

    rows, refs = wp.work_precision_rows(wp.WorkPrecisionScene(ks=(2, 4, 8, 16)), fake)
    t = pd.DataFrame(rows)
    assert refs["mortar"]["reference"] == pytest.approx(7.0)
    assert refs["penalty"]["reference"] == pytest.approx(6.0)
    assert refs["mortar"]["slope_h"] == pytest.approx(0.8)
    assert refs["penalty"]["slope_time"] == pytest.approx(-0.75)
    pen = t[t.treatment == "penalty"]
    assert np.allclose(pen.error, 2.0 * pen.h ** 1.5)

    if str(ROOT) not in sys.path:      # as `hpfebe run` does: the suite's experiments/
        sys.path.insert(0, str(ROOT))
    exp = importlib.import_module("experiments.ch4_work_precision")
    claims = {c.id: c for c in exp._claims(t, refs)}
    assert claims["monotone"].holds and claims["reference"].holds
    assert not claims["same_rate"].holds          # 0.8 against 1.5
    assert "0.80" in claims["same_rate"].evidence and "1.50" in claims["same_rate"].evidence
