"""Tests of experiments/ch3_adaptive_bem.py (Figures 3.2-3.9, adaptive h-BEM with
Coulomb friction)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from experiments import ch3_adaptive_bem as mod
from hpfebe.results import validate

ROOT = Path(__file__).resolve().parents[1]


def _quick_config():
    full = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["ch3_adaptive_bem"]
    quick = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())["ch3_adaptive_bem"]
    return {**full, **quick}


@pytest.fixture(scope="module")
def quick_run():
    return mod.run(_quick_config(), quick=True)


def _by_name(results):
    return {r.name: r for r in results}


def test_quick_run_produces_all_artefacts_with_decided_claims(quick_run):
    assert [r.name for r in quick_run] == list(mod.ARTEFACTS)
    for r in quick_run:
        validate(r)
        assert r.figure is not None, r.name
        assert r.claims, r.name
        assert r.meta["run_s"] < 20
        assert r.meta["eps_n"] == pytest.approx(1e-7 * 0.5)
    res = _by_name(quick_run)
    # decided: the colorbar / d question, Newton, adaptive vs uniform, Example 2 start
    for name in ("figure_3_2", "figure_3_5", "figure_3_6", "figure_3_9", "figure_3_7"):
        assert all(c.holds is not None for c in res[name].claims), name
    # the 4 x 4 initial mesh has 22 free DOF as the thesis's coarsest mesh
    assert res["figure_3_3"].claims[0].holds
    assert res["figure_3_4"].table.dof.iloc[0] == 22


def test_newton_converges_at_every_step(quick_run):
    res = _by_name(quick_run)
    for name in ("figure_3_4", "figure_3_8"):
        t = res[name].table
        assert t.newton_converged.all(), name
        assert (t.newton_iterations <= 10).all(), name
        assert (t.newton_final_residual < 1e-8).all(), name
    newton = [c for c in res["figure_3_4"].claims if c.text.startswith("(solver)")]
    assert newton and newton[0].holds


def test_adaptive_below_uniform_at_comparable_dof_example1(quick_run):
    t = _by_name(quick_run)["figure_3_6"].table
    un = t[t.refinement == "uniform"]
    for label in mod.VARIANT_LABEL.values():
        ad = t[t.refinement == label]
        d, e = float(ad.dof.iloc[-1]), float(ad.err_true.iloc[-1])
        assert un.dof.min() <= d <= un.dof.max()
        e_un = np.exp(np.interp(np.log(d), np.log(un.dof[un.err_true > 0]),
                                np.log(un.err_true[un.err_true > 0])))
        assert e < e_un, label
        # the error decreases along the adaptive sequence
        assert np.all(np.diff(ad.err_true.to_numpy()) <= 1e-12), label


def test_colorbars_decide_d(quick_run):
    res = _by_name(quick_run)
    r = res["figure_3_5"].table
    main = r[(r.d == 6e-4) & (r.C_pen == 1e-7)]
    assert (main[["rel_dev_max", "rel_dev_min"]].to_numpy() < 0.05).all()
    assert res["figure_3_2"].claims[0].holds is False   # d = 0.6e-4 does not match
    assert res["figure_3_5"].meta["d_matching_colorbars"] == pytest.approx(6e-4)
    r2 = res["figure_3_9"].table
    assert (r2[["rel_dev_max", "rel_dev_min"]].to_numpy() < 0.1).all()


def test_positive_homogeneity_in_d():
    """The penalty problem is positively homogeneous in d: U(d/10) = U(d)/10."""
    prm = mod._params({}, quick=True)
    m = mod.initial_mesh(4)
    a = mod.solve_on(m, prm, mod.gap_function(1, 6e-4), 5e-8)
    b = mod.solve_on(m, prm, mod.gap_function(1, 6e-5), 5e-8)
    assert np.allclose(b["U"], a["U"] / 10, rtol=1e-8, atol=1e-14)


def test_embedding_is_exact_on_nested_meshes():
    """A coarse P1/P0 solution written on a refinement keeps its values: the error of a
    solution against itself embedded is zero, and the trace agrees at the fine nodes."""
    prm = mod._params({}, quick=True)
    gap = mod.gap_function(1, 6e-4)
    coarse = mod.solve_on(mod.initial_mesh(4), prm, gap, 5e-8)
    fine_mesh = mod.common_refinement(mod.initial_mesh(8), mod.initial_mesh(4).refine([0, 5]))
    assert fine_mesh.n_elements == 32 + 0   # the bisections are already in the 8-mesh
    fine = mod.solve_on(fine_mesh, prm, gap, 5e-8)
    U, P = mod.embed(coarse, fine["op"])
    Ul = coarse["U"].reshape(-1, 2)
    x = fine_mesh.a
    ref = mod.trace_at(coarse["op"].mesh, coarse["op"].V_space, Ul, x)
    Uf = fine["op"].V_space.evaluate(U.reshape(-1, 2), np.arange(fine_mesh.n_elements),
                                     np.full(fine_mesh.n_elements, -1.0))
    assert np.allclose(Uf, ref, atol=1e-15)
    assert mod.true_error(fine, fine) == 0.0
    assert mod.true_error(coarse, fine) > 0.0


def test_wrong_input_is_rejected():
    with pytest.raises(ValueError, match="indicator variant"):
        mod._params({"indicators": ["nonsense"]}, quick=True)
    with pytest.raises(ValueError, match="n_steps"):
        mod._params({"n_steps": 0}, quick=True)
    with pytest.raises(ValueError, match="example"):
        mod.gap_function(3, 1e-4)


def test_longer_run_starts_with_the_thesis_run():
    """The figures take the first n_steps + 1 records of the longer run (Fig. 3.6
    extension): refinement is deterministic, so they equal those of a shorter run."""
    prm = mod._params({}, quick=True)
    short = mod.adaptive_run(1, 6e-4, prm, 5e-8, 2)
    long_ = mod._truncate(mod.adaptive_run(1, 6e-4, prm, 5e-8, 3), 2)
    assert len(short) == len(long_) == 3
    for a, b in zip(short, long_):
        assert np.array_equal(a["mesh"].nodes, b["mesh"].nodes)
        assert np.array_equal(a["marked"], b["marked"])
        assert np.allclose(a["state"]["U"], b["state"]["U"], rtol=0, atol=1e-15)
    assert not long_[-1]["marked"].any()
