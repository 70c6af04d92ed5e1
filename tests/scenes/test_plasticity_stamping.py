"""Stamping examples of Section 4.2.7 (hpfebe.scenes.stamping): the plastic work piece in
penalty contact through TwoBodyContact (FE and BE stamps agree, the dent stays, the
history of touch 1 is carried into touch 2), and figure_4_1 ... figure_4_12 through the
command line (quick configuration)."""

import json
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hpfebe.constitutive.j2 import J2Material
from hpfebe.scenes import (StampContact, curve_difference, lift_schedule,
                           stamp_body, touch, work_piece)

ROOT = Path(__file__).resolve().parents[2]
E, NU = 266926.0, 0.29
WORK = (-2.0, 2.0, -3.0, -1.0)


def _touch(kind, fe, box=(-1.0, 1.0, -1.0, 0.0), offset=None, tid=1):
    return touch(stamp_body(kind, box, 0.4, E, NU), fe, 4.2e-3, 4, 1, (1.0, -1.1),
                 StampContact(), offset=offset, touch_id=tid)


def test_fe_and_be_stamps_agree_and_leave_a_dent():
    mat = J2Material(E, NU, 4.0, 450.0, 1.0)
    out = {}
    for kind in ("FE", "BE"):
        fe = work_piece(WORK, 0.4, mat)
        tr = _touch(kind, fe)
        assert tr.converged, tr.reason
        assert [r.phase for r in tr.records] == ["load"] * 4 + ["unload"]
        # plastic under the stamp; the reaction grows while loading, vanishes unloaded
        f = np.array([r.force for r in tr.records])
        assert np.all(np.diff(f[:4]) > 0) and abs(f[-1]) < 1e-6 * f[3]
        assert tr.peak.fields["eps_p_norm"].max() > 1e-3
        # Newton: a handful of iterations per increment after the first
        assert max(r.iterations for r in tr.records[1:4]) <= 10
        out[kind] = (fe, tr)
    a, b = out["FE"][1], out["BE"][1]
    assert curve_difference([r.dev_sigma_X for r in a.records],
                            [r.dev_sigma_X for r in b.records]) < 0.02
    fe = out["FE"][0]
    top = fe.elastic.boundary_vertices("top")
    under = np.abs(fe.mesh.p[0, top]) < 0.99
    dent = -fe.elastic.nodal_displacement(a.u_work)[1, top][under].mean()
    assert 0.5 * 4.2e-3 < dent < 1.1 * 4.2e-3


def test_non_yielding_work_piece_is_solved():
    """sigma_Y far beyond the small-strain range: the stopping test's floor (a
    yield-level force, J2Material.stress_floor) must not accept an unsolved increment;
    the work piece stays elastic, its reaction balances the stamp's, no dent is left."""
    fe = work_piece(WORK, 0.4, J2Material(E, NU, 4e12, 450.0, 1.0))
    tr = _touch("FE", fe)
    assert tr.converged, tr.reason
    assert tr.peak.fields["eps_p_norm"].max() == 0
    f = np.array([r.force for r in tr.records])
    assert np.all(np.diff(f[:4]) > 0) and abs(f[-1]) < 1e-6 * f[3]
    c = tr.peak.result
    assert abs(c.total_forces()[0] - f[3]) <= 1e-6 * f[3]     # contact force = reaction
    assert np.abs(tr.u_work).max() <= 1e-6 * np.abs(tr.peak.u_work).max()    # no dent


def test_second_touch_continues_the_history():
    mat = J2Material(E, NU, 4.0, 450.0, 0.0)
    fe = work_piece(WORK, 0.4, mat)
    t1 = _touch("FE", fe, box=(0.4, 1.2, -1.0, 1.0))
    assert t1.converged
    alpha1 = fe.committed.alpha.copy()
    t2 = _touch("FE", fe, box=(-1.6, -0.8, -1.0, 1.0), offset=t1.u_work, tid=2)
    assert t2.converged, t2.reason
    assert t2.records[0].touch == 2
    # plastic strain only grows (alpha is monotone), both dents remain
    assert np.all(fe.committed.alpha >= alpha1 - 1e-15) and fe.committed.alpha.sum() > \
        alpha1.sum()
    top = fe.elastic.boundary_vertices("top")
    x = fe.mesh.p[0, top]
    uy = fe.elastic.nodal_displacement(t2.u_work)[1, top]
    for lo, hi in ((0.4, 1.2), (-1.6, -0.8)):
        assert -uy[(x > lo) & (x < hi)].mean() > 2e-3


def test_open_start_solves_open_increments_at_once():
    """Two unloading increments: the second starts from the first (contact open) moved
    rigidly, which is its solution (no Newton iteration); the secant extrapolation
    (open_start=False) iterates to the same state."""
    mat = J2Material(E, NU, 4.0, 450.0, 1.0)
    out = {}
    for flag in (True, False):
        fe = work_piece(WORK, 0.4, mat)
        tr = touch(stamp_body("FE", (-1.0, 1.0, -1.0, 0.0), 0.4, E, NU), fe, 4.2e-3, 4, 2,
                   (1.0, -1.1), StampContact(open_start=flag))
        assert tr.converged, tr.reason
        assert [r.phase for r in tr.records[-2:]] == ["unload", "unload"]
        out[flag] = tr
    new, old = out[True], out[False]
    assert new.records[-1].iterations == 0 < old.records[-1].iterations
    assert [r.iterations for r in new.records[:-1]] == \
        [r.iterations for r in old.records[:-1]]
    scale = np.abs(old.u_work).max()
    assert np.abs(new.u_work - old.u_work).max() <= 1e-8 * scale
    with pytest.raises(ValueError, match="open_start"):
        StampContact(open_start="yes")


def test_bonded_predictor_only_in_the_first_increments(monkeypatch):
    """bonded_increments = 2: the bonded predictor is tried in increments 1-2 only (later
    ones start from the secant extrapolation); None tries it in every increment; the
    states agree to the solver's tolerance."""
    from hpfebe.contact.loading import LoadSteps
    calls = []
    orig = LoadSteps.bonded_predictor
    monkeypatch.setattr(LoadSteps, "bonded_predictor",
                        lambda self, it: calls.append(1) or orig(self, it))
    mat = J2Material(E, NU, 4.0, 450.0, 1.0)
    out = {}
    for n in (2, None):
        calls.clear()
        fe = work_piece(WORK, 0.4, mat)
        tr = touch(stamp_body("FE", (-1.0, 1.0, -1.0, 0.0), 0.4, E, NU), fe, 4.2e-3, 5, 0,
                   (1.0, -1.1), StampContact(bonded_increments=n))
        assert tr.converged, tr.reason
        out[n] = (len(calls), tr)
    assert out[2][0] == 2 and out[None][0] == 5
    f2 = np.array([r.force for r in out[2][1].records])
    fn = np.array([r.force for r in out[None][1].records])
    assert np.abs(f2 - fn).max() <= 1e-6 * np.abs(fn).max()
    for bad in (-1, 1.5):
        with pytest.raises(ValueError, match="bonded_increments"):
            StampContact(bonded_increments=bad)


def test_bad_input():
    with pytest.raises(ValueError, match="kind"):
        stamp_body("XE", (0, 1, 0, 1), 0.5, E, NU)
    with pytest.raises(ValueError, match="h"):
        stamp_body("FE", (0, 1, 0, 1), 0.0, E, NU)
    with pytest.raises(ValueError, match="n_load"):
        lift_schedule(1e-3, 0, 1)
    with pytest.raises(ValueError, match="mu_f"):
        StampContact(mu_f=-0.1)
    with pytest.raises(ValueError, match="curves"):
        curve_difference([1.0], [1.0, 2.0])


def _run(artefact: str, out: Path):
    r = subprocess.run([sys.executable, "-m", "hpfebe", "run", artefact, "--quick",
                        "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]


def _claims(out: Path, name: str) -> dict:
    return {c["id"]: c for c in json.loads((out / f"{name}.json").read_text())["claims"]}


def test_experiment_quick(tmp_path):
    """figure_4_1 ... figure_4_12 through the command line (quick configuration), one
    scene per example: asking for an artefact of one computes only its example."""
    _run("figure_4_5", tmp_path)
    assert {p.stem for p in tmp_path.glob("figure_4_*.json")} == {
        f"figure_4_{i}" for i in range(1, 6)}                    # Example 1 only
    _run("figure_4_12", tmp_path)
    for i in range(1, 13):
        assert (tmp_path / f"figure_4_{i}.png").exists()
        d = json.loads((tmp_path / f"figure_4_{i}.json").read_text())
        assert d["claims"]
    d5 = json.loads((tmp_path / "figure_4_5.json").read_text())
    assert d5["meta"]["all_converged"] and d5["claims"][0]["holds"] is True
    assert "bebe_s" not in d5["meta"]                              # no BE/BE in Example 1
    d10 = json.loads((tmp_path / "figure_4_10.json").read_text())
    assert d10["meta"]["all_converged"] and d10["meta"]["bebe_s"] > 0   # BE/BE computed
    assert set(d10["meta"]["bebe_s_per_theta"]) == {"1", "0"}           # both hardenings
    assert all("theta=0" in c["evidence"] for c in d10["claims"])
    for i in (10, 11, 12):
        d = json.loads((tmp_path / f"figure_4_{i}.json").read_text())
        assert all(c["holds"] is not None for c in d["claims"][:2])     # decided
    # claim kinds: the thesis's statements; the convergence at X is a hypothesis (two
    # shrinking differences are no rate), locking and the BE/BE mesh study are ours
    for i in range(1, 12):
        assert all(c["kind"] == "thesis" for c in _claims(tmp_path, f"figure_4_{i}")
                   .values())
    c12 = _claims(tmp_path, "figure_4_12")
    assert {k: c["kind"] for k, c in c12.items()} == {
        "close": "thesis", "bebe": "thesis", "converges": "hypothesis",
        "locking": "beyond", "bebe_study": "beyond"}
    # BE/BE mesh study (bebe_h_levels, three meshes, thetas[0]): present and decided
    d12 = json.loads((tmp_path / "figure_4_12.json").read_text())
    assert len(d12["meta"]["bebe_study_s_per_h"]) == 3
    study = c12["bebe_study"]
    assert "BE/BE converges under mesh refinement" in study["text"]
    assert study["holds"] is not None
    assert "BE/BE vs FE/FE on the same mesh" in study["evidence"]


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64") or sys.platform == "darwin",
                    reason="pypardiso is a dependency on x86_64 Linux/Windows only")
def test_pardiso_is_the_sparse_lu_where_it_is_a_dependency(monkeypatch):
    """pyproject declares pypardiso on x86_64 (MKL wheels): its library is found and
    used, not silently replaced by SuperLU (unless HPFEBE_PARDISO=0 asks for that)."""
    from hpfebe.contact.newton_matrix import ENV_PARDISO, FixedPatternLU
    monkeypatch.delenv(ENV_PARDISO, raising=False)
    assert FixedPatternLU({}).backend == "pardiso"
    monkeypatch.setenv(ENV_PARDISO, "0")
    assert FixedPatternLU({}).backend == "superlu"


def test_pardiso_and_superlu_touches_agree(monkeypatch):
    """One touch with each sparse LU of the fixed-pattern Newton systems: the same
    records to the Newton tolerance (rtol 1e-8; the iteration counts may differ by
    round-off)."""
    from hpfebe.contact.newton_matrix import ENV_PARDISO
    mat = J2Material(E, NU, 4.0, 450.0, 1.0)
    out = {}
    for env in ("1", "0"):
        monkeypatch.setenv(ENV_PARDISO, env)
        tr = _touch("FE", work_piece(WORK, 0.4, mat))
        assert tr.converged, tr.reason
        out[env] = tr
    for ra, rb in zip(out["1"].records, out["0"].records, strict=True):
        assert abs(ra.force - rb.force) <= 1e-6 * abs(out["0"].records[3].force)
        assert abs(ra.dev_sigma_X - rb.dev_sigma_X) <= 1e-6 * rb.dev_sigma_X
