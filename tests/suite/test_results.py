"""hpfebe.suite.results: the result contract, atomic writes, provenance, NaN policy."""

import json
import math

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from hpfebe.suite import results as res
from hpfebe.suite.claims import Claim
from hpfebe.suite.progressbar import progress
from hpfebe.suite.results import ArtefactResult, atomic_write, write_result


def _result(**kw):
    table = pd.DataFrame({"h_inv": [3, 6], "p": [1, 1], "err": [0.1, 0.05],
                          "rate": [np.nan, 1.0], "dof": [10, 20]})
    args = dict(name="table_9_1", table=table, published="table_9_1_fake.csv",
                keys=("h_inv", "p"), tolerances={"err": ("factor", 2.0)},
                claims=[Claim("rate ~ 1", True, "last rate 1.0")], notes="n",
                meta={"allow_nan_columns": ["rate"], "run_s": 1.5})
    args.update(kw)
    return ArtefactResult(**args)


def test_write_result_writes_csv_and_json(tmp_path):
    paths = write_result(_result(), tmp_path, {"a": 1})
    assert [p.name for p in paths] == ["table_9_1.csv", "table_9_1.json"]
    df = pd.read_csv(tmp_path / "table_9_1.csv")
    assert list(df.columns) == ["h_inv", "p", "err", "rate", "dof"]
    assert math.isnan(df.rate[0]) and df.err[1] == 0.05
    doc = json.loads((tmp_path / "table_9_1.json").read_text())
    assert doc["claims"] == [{"text": "rate ~ 1", "holds": True, "evidence": "last rate 1.0",
                              "kind": "thesis", "id": "", "explains": []}]
    assert doc["keys"] == ["h_inv", "p"] and doc["tolerances"] == {"err": ["factor", 2.0]}
    assert doc["published"] == "table_9_1_fake.csv" and doc["meta"]["run_s"] == 1.5
    # no temporary files left behind
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table_9_1.csv", "table_9_1.json"]


def test_claim_kinds_and_links_written(tmp_path):
    claims = [Claim("rate ~ 1", False, "rate 0.5", id="rate"),
              Claim("pre-asymptotic", True, "rate 0.99 on finer meshes", kind="explanation",
                    id="pre", explains=("rate", "cells:err[h_inv=3]")),
              Claim("ours faster", True, "x2", kind="beyond")]
    write_result(_result(claims=claims), tmp_path)
    doc = json.loads((tmp_path / "table_9_1.json").read_text())
    assert [c["kind"] for c in doc["claims"]] == ["thesis", "explanation", "beyond"]
    assert doc["claims"][1]["explains"] == ["rate", "cells:err[h_inv=3]"]
    assert doc["claims"][1]["id"] == "pre" and doc["claims"][2]["id"] == ""


def test_provenance_fields(tmp_path):
    write_result(_result(), tmp_path, {"degrees": [1, 2]}, run_info={"quick": True})
    prov = json.loads((tmp_path / "table_9_1.json").read_text())["provenance"]
    for key in ("git_commit", "packages", "python", "config", "date_utc", "host_cpu_count"):
        assert key in prov, key
    assert isinstance(prov["git_commit"], str) and prov["git_commit"]
    assert set(prov["packages"]) >= {"numpy", "scipy", "numba", "scikit-fem", "hpfebe"}
    assert prov["config"] == {"degrees": [1, 2]}
    assert prov["date_utc"].endswith("+00:00")
    assert prov["run"] == {"quick": True}


def test_figure_written_as_png(tmp_path):
    fig = Figure()
    fig.subplots().plot([1, 2], [3, 4])
    paths = write_result(_result(name="figure_9_1", figure=fig), tmp_path)
    assert (tmp_path / "figure_9_1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert paths[-1].name == "figure_9_1.json"  # the JSON (completion marker) comes last


def test_figure_artefact_without_figure_rejected(tmp_path):
    with pytest.raises(ValueError, match="figure"):
        write_result(_result(name="figure_9_1"), tmp_path)


def test_nan_rejected_naming_the_column(tmp_path):
    r = _result(meta={})
    with pytest.raises(ValueError, match="'rate'"):
        write_result(r, tmp_path)
    assert not list(tmp_path.iterdir())
    r.meta["allow_nan_columns"] = ["rate"]
    write_result(r, tmp_path)  # allowed once declared


def test_nan_in_object_column_rejected(tmp_path):
    table = pd.DataFrame({"h_inv": [3, 6], "p": [1, 1], "err": [0.1, 0.2],
                          "series": ["h", float("nan")]})
    with pytest.raises(ValueError, match="'series'"):
        write_result(_result(table=table, meta={}), tmp_path)


@pytest.mark.parametrize("kw, match", [
    (dict(keys=("nope",)), "key column 'nope'"),
    (dict(tolerances={"err": ("relative", 0.1)}), "tolerance for 'err'"),
    (dict(tolerances={"nope": ("abs", 0.1)}), "tolerance column 'nope'"),
    (dict(tolerances={"err": ("factor", 0.5)}), "tolerance value"),
    (dict(name="bad name"), "plain artefact id"),
    (dict(claims=[Claim("x", "yes", "")]), "Claim.holds"),
    (dict(claims=[Claim("x", True, kind="analysis")]), "Claim.kind"),
    (dict(claims=[Claim("x", True, explains=("cells:err",))]), "only explanation"),
    (dict(claims=[Claim("x", True, kind="explanation", explains=("nope",))]),
     "neither a claim id"),
    (dict(claims=[Claim("x", True, kind="hypothesis", explains="cells:err")]),
     "tuple of claim ids"),
    (dict(claims=[Claim("x", False, id="a"), Claim("y", True, id="a")]), "unique"),
])
def test_contract_violations(tmp_path, kw, match):
    with pytest.raises(ValueError, match=match):
        write_result(_result(**kw), tmp_path)


def test_atomic_write_failure_leaves_no_file(tmp_path):
    target = tmp_path / "x.csv"

    def writer(f):
        f.write("a,b\n1,2\n")
        raise RuntimeError("disk full (simulated)")

    with pytest.raises(RuntimeError, match="simulated"):
        atomic_write(target, writer)
    assert not target.exists()
    assert not list(tmp_path.iterdir())  # the temporary file is removed too


def test_atomic_write_failure_keeps_previous_file(tmp_path):
    target = tmp_path / "x.csv"
    atomic_write(target, lambda f: f.write("old\n"))

    def writer(f):
        f.write("new, half")
        raise KeyboardInterrupt  # an interrupted run

    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, writer)
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["x.csv"]


def test_write_result_interrupted_mid_write(tmp_path, monkeypatch):
    """A failure while the figure is being written: no PNG and no JSON appear (the CSV
    written before is complete), so the result does not look finished."""
    fig = Figure()
    fig.subplots().plot([1, 2], [3, 4])

    def broken_png(figure, **kw):            # the PNG of the figure (suite.figures.png_bytes)
        raise OSError("simulated crash while writing the figure")

    monkeypatch.setattr("hpfebe.suite.figures.png_bytes", broken_png)
    with pytest.raises(OSError, match="simulated"):
        write_result(_result(name="figure_9_2", figure=fig), tmp_path)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["figure_9_2.csv"]
    assert res.read_result(tmp_path, "figure_9_2") is None


def test_fsync_failure_leaves_no_file(tmp_path, monkeypatch):
    def fail(fd):
        raise OSError("simulated fsync failure")

    monkeypatch.setattr(res.os, "fsync", fail)
    with pytest.raises(OSError, match="fsync"):
        write_result(_result(), tmp_path)
    assert not list(tmp_path.iterdir())


def test_json_is_strict_with_non_finite_meta(tmp_path):
    write_result(_result(meta={"allow_nan_columns": ["rate"], "residual": float("inf"),
                               "x": np.float64(np.nan), "n": np.int64(3)}), tmp_path)
    text = (tmp_path / "table_9_1.json").read_text()
    doc = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert doc["meta"]["residual"] == "Infinity" and doc["meta"]["x"] == "NaN"
    assert doc["meta"]["n"] == 3


def test_progress_is_quiet_without_tty(capsys):
    assert list(progress(range(3), desc="cases")) == [0, 1, 2]
    assert capsys.readouterr().err == ""          # pytest captures stderr: not a TTY
    assert list(progress(range(3), desc="cases", disable=False)) == [0, 1, 2]
    assert "cases" in capsys.readouterr().err     # the bar, when asked for


def test_suite_facade_is_light_and_complete():
    """``hpfebe.suite`` exports the names the experiments use, each the object of the
    module that defines it, and imports none of them (nor pandas) until asked."""
    import subprocess
    import sys

    code = ("import sys, hpfebe.suite as s; "
            "print(sorted(m for m in ('pandas', 'matplotlib', 'hpfebe.suite.results', "
            "'hpfebe.suite.report') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
    import importlib

    import hpfebe.suite as suite

    for name in suite.__all__:
        obj = getattr(suite, name)
        home = importlib.import_module(f"hpfebe.suite.{suite._API[name]}")
        assert obj is getattr(home, name), name
    for name in ("Claim", "ArtefactResult", "progress", "rate_claim", "range_claim",
                 "joint_claim", "beats_uniform_claim", "from_config", "CELLS_PREFIX"):
        assert name in suite.__all__


# --------------------------------------------------------------------------- exports
def _mesh(shift=0.0):
    import meshio
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))],
                       point_data={"u": np.full(3, shift)})


def _mode(path):
    import os
    import stat
    mask = os.umask(0)
    os.umask(mask)
    return stat.S_IMODE(path.stat().st_mode), 0o666 & ~mask


def test_exports_land_in_results_vtu(tmp_path):
    """One mesh per key: <out>/vtu/<name>_<key>.vtu with the usual mode, listed in the
    JSON relative to <out>; nothing VTU at the top of <out>; the JSON still last."""
    import meshio
    paths = write_result(_result(exports={"final": _mesh(2.0)}), tmp_path)
    vtu = tmp_path / "vtu" / "table_9_1_final.vtu"
    assert vtu in paths and paths[-1].name == "table_9_1.json"
    assert not list(tmp_path.glob("*.vtu"))
    assert np.allclose(meshio.read(vtu).point_data["u"], 2.0)
    mode, usual = _mode(vtu)
    assert mode == usual
    doc = json.loads((tmp_path / "table_9_1.json").read_text())
    assert doc["exports"] == ["vtu/table_9_1_final.vtu"]
    assert sorted(p.name for p in (tmp_path / "vtu").iterdir()) == ["table_9_1_final.vtu"]


def test_export_series_gets_a_pvd(tmp_path):
    """A list of (load step, mesh): one VTU per step and a PVD collection (written
    after its VTUs) that names them relative to vtu/, with the steps' times."""
    import meshio
    steps = [(0.5, _mesh(0.0)), (1.0, _mesh(1.0)), (2.0, _mesh(4.0))]
    paths = write_result(_result(exports={"steps": steps, "last": _mesh(4.0)}), tmp_path)
    d = tmp_path / "vtu"
    names = [p.relative_to(tmp_path).as_posix() for p in paths[1:-1]]  # csv ... json
    assert names == ["vtu/table_9_1_steps_0.vtu", "vtu/table_9_1_steps_1.vtu",
                     "vtu/table_9_1_steps_2.vtu", "vtu/table_9_1_steps.pvd",
                     "vtu/table_9_1_last.vtu"]
    text = (d / "table_9_1_steps.pvd").read_text()
    for k, (t, _) in enumerate(steps):
        assert f'timestep="{t!r}" part="0" file="table_9_1_steps_{k}.vtu"' in text
    assert np.allclose(meshio.read(d / "table_9_1_steps_2.vtu").point_data["u"], 4.0)
    assert _mode(d / "table_9_1_steps.pvd")[0] == _mode(d / "table_9_1_steps.pvd")[1]
    doc = json.loads((tmp_path / "table_9_1.json").read_text())
    assert doc["exports"] == names


@pytest.mark.parametrize("exports, match", [
    ({"a b": None}, "identifier"),
    ({"x": "not a mesh"}, "meshio.Mesh or a non-empty list"),
    ({"x": []}, "non-empty"),
    ({"x": [(1.0, "mesh")]}, "meshio.Mesh"),
    ({"x": [(1.0, None), (0.5, None)]}, "meshio.Mesh"),
])
def test_bad_exports_refused_before_writing(tmp_path, exports, match):
    with pytest.raises(ValueError, match=match):
        write_result(_result(exports=exports), tmp_path)
    assert not list(tmp_path.iterdir())


def test_series_times_must_increase(tmp_path):
    for times in ((1.0, 1.0), (2.0, 1.0), (0.0, float("nan")), (True, 2.0)):
        with pytest.raises(ValueError, match="strictly increasing"):
            write_result(_result(exports={"s": [(t, _mesh()) for t in times]}), tmp_path)
    assert not list(tmp_path.iterdir())


def test_exports_ask_the_job_watch_before_every_rename(tmp_path, monkeypatch):
    """The before_rename hook of the job watch is called for every VTU and PVD; when it
    raises (the parent Snakemake is gone) the file does not land and no temporary is
    left."""
    from hpfebe.suite import watch
    asked = []

    def hook(path):
        asked.append(path.name)
        if path.suffix == ".pvd":
            raise watch.Terminated(15, "parent gone")

    monkeypatch.setattr(watch, "before_rename", hook)
    steps = [(1.0, _mesh()), (2.0, _mesh())]
    with pytest.raises(watch.Terminated):
        write_result(_result(exports={"one": _mesh(), "s": steps}), tmp_path)
    assert asked == ["table_9_1.csv", "table_9_1_one.vtu", "table_9_1_s_0.vtu",
                     "table_9_1_s_1.vtu", "table_9_1_s.pvd"]
    assert sorted(p.name for p in (tmp_path / "vtu").iterdir()) == [
        "table_9_1_one.vtu", "table_9_1_s_0.vtu", "table_9_1_s_1.vtu"]
    assert not (tmp_path / "table_9_1.json").exists()


def test_stale_vtu_temporaries_in_results_vtu_removed(tmp_path):
    """A VTU or PVD temporary left in results/vtu/ by a job killed outright (kill -9)
    is removed before the next run of its module; finished exports stay."""
    from hpfebe.cli import remove_stale_temporaries

    d = tmp_path / "vtu"
    d.mkdir()
    stale = [d / ".figure_9_1_final.k1ll3d.vtu", d / ".figure_9_1_steps.k1ll3d.pvd"]
    keep = [d / "figure_9_1_final.vtu", d / ".figure_9_2_final.k1ll3d.vtu"]
    for p in stale + keep:
        p.write_bytes(b"x")
    assert sorted(remove_stale_temporaries(tmp_path, ["figure_9_1"])) == sorted(stale)
    assert all(p.exists() for p in keep) and not any(p.exists() for p in stale)
