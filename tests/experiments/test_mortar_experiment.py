"""The ch4_mortar experiment (Table 4.1, Figures 4.17-4.20 and the beyond artefacts) runs
in quick mode, scene by scene, and writes valid results."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:        # as `hpfebe run` does: the suite's experiments/
    sys.path.insert(0, str(ROOT))

import experiments.ch4_mortar as m  # noqa: E402
from experiments.ch4_mortar import table  # noqa: E402

from hpfebe.scenes.mortar_runs import PUBLISHED_TABLE  # noqa: E402


def _quick_config() -> dict:
    cfg = {}
    for f in ("config.yaml", "quick.yaml"):
        cfg.update(yaml.safe_load((ROOT / "config" / f).read_text())["ch4_mortar"])
    return cfg


def test_quick_run(tmp_path):
    out = subprocess.run([sys.executable, "-m", "hpfebe", "run", "ch4_mortar", "--quick",
                          "--out", str(tmp_path)], capture_output=True, text=True, timeout=300,
                         cwd=ROOT)
    assert out.returncode == 0, out.stderr[-2000:]
    df = pd.read_csv(tmp_path / "table_4_1.csv")
    assert len(df) == 16
    # every cell either converged with a count or reports why not
    assert ((df["converged"] & df["iterations"].notna()) |
            (~df["converged"] & df["reason"].str.len().gt(0))).all()
    for name in m.ARTEFACTS[1:]:
        assert (tmp_path / f"{name}.png").exists()
        doc = json.loads((tmp_path / f"{name}.json").read_text())
        assert all(c["kind"] in ("thesis", "explanation", "hypothesis", "beyond")
                   for c in doc["claims"])
    # exact agreement is stored as 0, not as a plotting floor
    cmp = pd.read_csv(tmp_path / "figure_solver_comparison.csv")
    assert (cmp["rel_difference"] >= 0).all() and (cmp["rel_difference"] != 1e-17).all()


def test_scenes_partition_the_artefacts():
    arts = [a for s in m.SCENES.values() for a in s]
    assert sorted(arts) == sorted(m.ARTEFACTS) and len(arts) == len(set(arts))


def test_a_scene_computes_only_its_artefacts(monkeypatch):
    """The sweep scene runs neither the damping sweep nor the Table 4.1 problem."""
    def fail(*a, **k):
        raise AssertionError("not needed by the sweep scene")

    monkeypatch.setattr(m, "damping_sweep", fail)
    monkeypatch.setattr(m, "_table_problem", fail)
    res = m.run(_quick_config(), quick=True, scenes=("sweep",))
    assert [r.name for r in res] == ["figure_4_18"]
    ids = {c.id for c in res[0].claims}
    for c in res[0].claims:          # every link names a claim of the artefact
        assert all(x in ids for x in c.explains)


def test_unknown_scene_is_refused():
    try:
        m.run(_quick_config(), quick=True, scenes=("nope",))
    except ValueError as exc:
        assert "nope" in str(exc)
    else:
        raise AssertionError("an unknown scene must be refused")


def test_symmetry_explanation_links_only_the_off_cells():
    """The Table 4.1 explanation names exactly the off cells it tests, and holds only if
    our counts are symmetric there in both readings."""
    rows = [dict(omega_D=a, omega_N=b, iterations=float(v or np.nan), converged=v is not None,
                 iterations_tresca=float(v or np.nan))
            for (a, b), v in PUBLISHED_TABLE.items()]
    df = pd.DataFrame(rows)
    df.loc[(df.omega_D == 0.3) & (df.omega_N == 0.9), ["iterations", "iterations_tresca"]] = 23.0
    c = table._symmetry_claim(df, [(0.3, 0.9)])
    assert c.kind == "explanation" and c.holds is True
    assert c.explains == ("counts", "cells:iterations[omega_D=0.3,omega_N=0.9]")
    df.loc[(df.omega_D == 0.3) & (df.omega_N == 0.9), "iterations_tresca"] = 30.0
    assert table._symmetry_claim(df, [(0.3, 0.9)]).holds is False
    assert table._symmetry_claim(df, []).holds is None
