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

    def broken_savefig(f, **kw):
        f.write(b"\x89PNG partial")
        raise OSError("simulated crash while writing the figure")

    monkeypatch.setattr(fig, "savefig", broken_savefig)
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


def test_progress_is_quiet_without_tty():
    bar = progress(range(3))
    assert list(bar) == [0, 1, 2]
    assert bar.disable  # pytest captures stderr: not a TTY


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
