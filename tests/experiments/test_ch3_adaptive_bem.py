"""Figures 3.2-3.9 (adaptive h-BEM with Coulomb friction, experiments/ch3_adaptive_bem/)
through the command line, quick configuration: every artefact written, its claims
decided, the published numbers met.  The numerics are tested in the core
(tests/adaptivity/test_bem_adaptive_core.py, tests/spaces/test_prolongation.py)."""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe import cli
from hpfebe.suite.results import read_result

ARTEFACTS = ("figure_3_2", "figure_3_3", "figure_3_4", "figure_3_5", "figure_3_6",
             "figure_3_7", "figure_3_8", "figure_3_9")
LABELS = ("adaptive (3.107)", "adaptive (3.107) balanced")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("ch3_adaptive_bem")
    assert cli.main(["-q", "run", "figure_3_2", "--quick", "--out", str(out)]) == cli.EXIT_OK
    return {name: read_result(out, name) for name in ARTEFACTS}


def _holds(doc):
    return [c["holds"] for c in doc["claims"]]


def test_quick_run_produces_all_artefacts_with_decided_claims(quick_run):
    for name, got in quick_run.items():
        assert got is not None, name
        doc, _ = got
        assert doc["has_figure"] and doc["claims"], name
        assert doc["meta"]["eps_n"] == pytest.approx(1e-7 * 0.5)
        assert "Choices where the thesis is silent" in doc["notes"]
    for name in ("figure_3_2", "figure_3_5", "figure_3_6", "figure_3_9", "figure_3_7"):
        assert all(h is not None for h in _holds(quick_run[name][0])), name
    # the 4 x 4 initial mesh has 22 free DOF as the thesis's coarsest mesh
    assert _holds(quick_run["figure_3_3"][0])[0] is True
    assert quick_run["figure_3_4"][1].dof.iloc[0] == 22


def test_newton_converges_at_every_step(quick_run):
    for name in ("figure_3_4", "figure_3_8"):
        doc, t = quick_run[name]
        assert t.newton_converged.all(), name
        assert (t.newton_iterations <= 10).all(), name
        assert (t.newton_final_residual < 1e-8).all(), name
        newton = [c for c in doc["claims"] if c["text"].startswith("(solver)")]
        assert newton and newton[0]["holds"] is True


def test_adaptive_below_uniform_at_comparable_dof_example1(quick_run):
    t = quick_run["figure_3_6"][1]
    un = t[t.refinement == "uniform"]
    for label in LABELS:
        ad = t[t.refinement == label]
        d, e = float(ad.dof.iloc[-1]), float(ad.err_true.iloc[-1])
        assert un.dof.min() <= d <= un.dof.max()
        e_un = np.exp(np.interp(np.log(d), np.log(un.dof[un.err_true > 0]),
                                np.log(un.err_true[un.err_true > 0])))
        assert e < e_un, label
        # the error decreases along the adaptive sequence
        assert np.all(np.diff(ad.err_true.to_numpy()) <= 1e-12), label


def test_colorbars_decide_d(quick_run):
    r = quick_run["figure_3_5"][1]
    main = r[(r.d == 6e-4) & (r.C_pen == 1e-7)]
    assert (main[["rel_dev_max", "rel_dev_min"]].to_numpy() < 0.05).all()
    assert _holds(quick_run["figure_3_2"][0])[0] is False    # d = 0.6e-4 does not match
    assert quick_run["figure_3_5"][0]["meta"]["d_matching_colorbars"] == pytest.approx(6e-4)
    r2 = quick_run["figure_3_9"][1]
    assert (r2[["rel_dev_max", "rel_dev_min"]].to_numpy() < 0.1).all()


@pytest.mark.parametrize("section, match", [
    ("indicators: [nonsense]", "indicator variant"),
    ("n_steps: 0", "n_steps"),
    ("n_stepz: 3", "unknown key"),
])
def test_wrong_config_is_rejected(tmp_path, capsys, section, match):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(f"ch3_adaptive_bem:\n  {section}\n")
    rc = cli.main(["run", "figure_3_2", "--config", str(cfg), "--out", str(tmp_path)])
    assert rc == cli.EXIT_USAGE             # a config error is a usage error (exit 2)
    err = capsys.readouterr().err
    assert match in err and "bad.yaml" in err


def test_paraview_exports_of_the_final_state(quick_run):
    """Figs. 3.4 and 3.8 export the last adaptive mesh (U, eta) and its contact state
    along Gamma_C (pressure, tangential traction, slip, state) for ParaView."""
    for name in ("figure_3_4", "figure_3_8"):
        exports = quick_run[name][0]["exports"]
        assert sorted(e.rsplit("/", 1)[-1] for e in exports) == [
            f"{name}_final_contact.vtu", f"{name}_final_mesh.vtu"], exports
