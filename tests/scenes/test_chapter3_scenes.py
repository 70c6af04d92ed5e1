"""The Chapter 3 scenes' tables and ParaView fields (hpfebe.scenes.penalty,
hpfebe.scenes.adaptive_bem): Table 3.1's err column and its Aitken limit, the stress
test's breakdown summary, the contact state exported along Gamma_C."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hpfebe.analysis import aitken
from hpfebe.constitutive import OPEN, SLIP
from hpfebe.scenes import adaptive_bem
from hpfebe.scenes import penalty as scene


def _rows(prm, limit=0.11):
    """Synthetic Table 3.1 sweep rows: norm = limit - c h (+ a plane offset)."""
    rows = []
    for plane, off in (("strain", 0.0), ("stress", 0.001)):
        for n in prm.n_per_side:
            for C in prm.C_eps:
                rows.append(dict(plane=plane, kind="C_eps h", C_eps=C, n=n, dof=2 * (3 * n - 1),
                                 eps=C / n, norm=limit + off - C * 1e3 / n - 0.01 / n,
                                 newton_iterations=1, final_residual=1e-12,
                                 min_pressure=1.0, max_pressure=2.0, wall_time_s=0.0,
                                 assembly_s=0.0))
            rows.append(dict(rows[-1], kind="fixed", C_eps=math.nan, eps=2.5e-5))
    return rows


def test_table_3_1_rows_from_the_aitken_limit():
    prm = scene.PenaltyScene(n_per_side=(4, 8, 16), C_eps=(1e-5, 1e-6))
    rows = _rows(prm)
    ulim, best = scene.aitken_limits(rows, prm)
    seq = [r["norm"] for r in rows if r["plane"] == "strain" and r["C_eps"] == 1e-6]
    assert ulim["strain"] == pytest.approx(aitken(*seq[-3:]), rel=1e-15)
    assert best == min(prm.planes, key=lambda pl: abs(prm.norm_scale * ulim[pl]
                                                      - scene.PUBLISHED_ULIM))
    table = scene.error_rows(rows, prm, ulim, best)
    assert [(r["C_eps"], r["n"]) for r in table] == [(1e-5, 4), (1e-5, 8), (1e-5, 16),
                                                      (1e-6, 4), (1e-6, 8), (1e-6, 16)]
    other = "stress" if best == "strain" else "strain"
    for r in table:
        assert r["err"] == abs(prm.norm_scale * (ulim[best] - r["norm_S"]))
        assert r["err_unscaled"] * prm.norm_scale == pytest.approx(r["err"], rel=1e-14)
        assert r["err_" + other] > 0
    assert list(table[0])[:8] == ["C_eps", "dof", "eps", "err", "err_published_ulim",
                                  "err_unscaled", "norm_S", "ulim_S"]


def test_breakdown_summary_of_the_stress_test():
    C = [1e-4, 1e-8, 1e-12, 1e-16, 1e-20]
    acc = [True, True, True, False, False]
    rows = [dict(problem="flat", p=1, C_eps=c, accepted=a, converged=c > 1e-20,
                 lapack_warning=c < 1e-14, condition_number=1.0 / c,
                 newton_iterations=2, penalty_error=max(c, 1e-11)) for c, a in zip(C, acc)]
    s = scene.breakdown_summary(rows)[("flat", 1)]
    assert s["not_accepted"] == [1e-16, 1e-20] and s["first_not_accepted"] == 1e-16
    assert s["failed"] == [1e-20] and s["false_convergence"] == [1e-16]
    assert s["first_lapack_warning"] == 1e-16 and s["max_cond"] == 1e20
    assert s["penalty_error_saturates_at"] == 1e-16 and s["min_penalty_error"] == 1e-11


def test_penalty_exports_carry_the_contact_state():
    """Flat obstacle, full contact: the pressure (1/eps)(U_n - g)_+ > 0 and state slip
    at every point, no tangential traction; the tilted obstacle leaves points open."""
    prm = scene.PenaltyScene()
    flat = scene.representative_exports(prm, 4, 1, 1e-7 / 4, -prm.d)
    c = flat["contact"].point_data
    assert np.all(c["p_n"] > 0) and np.all(c["state"] == SLIP) and np.all(c["t_t"] == 0)
    assert np.allclose(c["g_n"], -c["p_n"] * 1e-7 / 4, rtol=1e-9, atol=0)
    assert np.allclose(c["slip"], c["g_t"])
    assert flat["boundary"].point_data["displacement"].shape[1] == 3
    tilted = scene.representative_exports(prm, 16, 1, 1e-7 / 16,
                                          scene.tilted_gap(prm.d, 4e-4))
    st = tilted["contact"].point_data["state"]
    assert (st == OPEN).any() and (st == SLIP).any()
    assert np.all(tilted["contact"].point_data["slip"][st == OPEN] == 0)


def test_adaptive_bem_colour_bar_rows_and_consistency_ratio():
    u = np.zeros((3, 3, 2))
    u[..., 0], u[..., 1] = np.linspace(-1e-4, 1e-4, 9).reshape(3, 3), 5e-4
    rows = adaptive_bem.range_rows(1, "literal", 6e-4, 1e-7, u)
    assert [r["quantity"] for r in rows] == ["ux_range", "uy_range"]
    assert rows[0]["min"] == -1e-4 and rows[0]["published_max"] == 0.1243e-3
    assert rows[0]["rel_dev_max"] == pytest.approx((0.1243e-3 - 1e-4) / 0.2486e-3)
    # eta^2 = traction^2 + w^2 consistency^2: traction 3, consistency 4e-4 per element
    lit, bal = np.sqrt(9 + 16e-8) * np.ones(4), np.sqrt(9 + 100 * 16e-8) * np.ones(4)
    assert adaptive_bem.consistency_ratio(lit, bal, 10.0) == pytest.approx(4e-4 / 3,
                                                                          rel=1e-6)
