"""Tests of experiments/ch4_adaptive_fefe.py (Figures 4.13-4.16, adaptive FE/FE contact)."""

from __future__ import annotations

import math
from pathlib import Path

import meshio
import numpy as np
import pytest
import yaml

from experiments import ch4_adaptive_fefe as mod
from hpfebe.results import validate, write_result

ROOT = Path(__file__).resolve().parents[1]


def _quick_config():
    full = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["ch4_adaptive_fefe"]
    quick = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())["ch4_adaptive_fefe"]
    return {**full, **quick}


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("results")
    results = mod.run(_quick_config(), quick=True)
    for r in results:
        write_result(r, tmp)
    return results, tmp


def test_quick_run_produces_all_artefacts(quick_run):
    results, tmp = quick_run
    assert [r.name for r in results] == list(mod.ARTEFACTS)
    for r in results:
        validate(r)
        assert r.figure is not None
        assert r.claims and all(c.holds is not None for c in r.claims), r.name
        assert r.meta["run_s"] < 20
    vtus = sorted(p.name for p in tmp.glob("*.vtu"))
    assert len(vtus) == 4 and all(v.startswith("figure_4_16_") for v in vtus), vtus
    mesh = meshio.read(tmp / vtus[0])
    assert np.all(np.isfinite(mesh.point_data["displacement"]))


def test_adaptive_indicator_below_uniform_at_comparable_dof(quick_run):
    results, _ = quick_run
    for r, body in ((results[1], "slave"), (results[2], "master")):
        t = r.table
        ad, un = t[t["mode"] == "adaptive"], t[t["mode"] == "uniform"]
        d, e = ad[f"dof_{body}"].iloc[-1], ad[f"eta_{body}"].iloc[-1]
        # uniform meshes bracket the last adaptive DOF
        assert un[f"dof_{body}"].min() <= d <= un[f"dof_{body}"].max()
        e_u = math.exp(np.interp(math.log(d), np.log(un[f"dof_{body}"]),
                                 np.log(un[f"eta_{body}"])))
        assert e < e_u
        assert r.claims[0].holds is True
        # indicator decreases along the adaptive sequence
        assert ad[f"eta_{body}"].iloc[-1] < ad[f"eta_{body}"].iloc[0]


def test_newton_converges_every_step(quick_run):
    results, _ = quick_run
    t = results[1].table
    assert t["newton_converged"].all()
    for s in t["newton_per_load_step"]:
        its = [int(i) for i in s.split()]
        assert len(its) >= 5 and max(its) <= 10
    assert results[1].meta["newton_all_converged"]


def test_meshes_conforming_and_labelled(quick_run):
    results, _ = quick_run
    assert results[0].table["conforming"].all()
    assert results[0].table["h_min_slave"].iloc[-1] < results[0].table["h_min_slave"].iloc[0]


def test_refine_keeps_conformity_and_relabels():
    m = mod.label(mod.rectangle_mesh(*mod.BOX_M, 4, 2, kind="tri"), mod.BOX_M)
    marked = np.zeros(m.t.shape[1], bool)
    marked[:3] = True
    r = mod.refine(m, mod.BOX_M, marked)
    assert r.t.shape[1] > m.t.shape[1]
    assert mod.is_conforming(r, mod.BOX_M)
    total = sum(len(v) for v in r.boundaries.values())
    assert total == r.boundary_facets().size
    top = r.p[:, r.facets[:, r.boundaries["top"]].ravel()]
    assert np.allclose(top[1], 0.0)


def test_displacement_between_dirichlet_values(quick_run):
    results, _ = quick_run
    t = results[3].table
    assert t["uy_min"].min() >= -1e-12 and t["uy_max"].max() <= 5e-4 * (1 + 1e-9)
    assert results[3].claims[0].holds is True
