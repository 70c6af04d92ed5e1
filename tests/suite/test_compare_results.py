"""tools/compare_results.py on two tiny synthetic results folders."""

import importlib.util
import json
import sys
from pathlib import Path

import pandas as pd
import pytest

TOOL = Path(__file__).resolve().parents[2] / "tools" / "compare_results.py"


@pytest.fixture(scope="module")
def cr():
    spec = importlib.util.spec_from_file_location("compare_results", TOOL)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["compare_results"] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


def _write(d: Path, name: str, table: dict, claims=()):
    d.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(table).to_csv(d / f"{name}.csv", index=False)
    (d / f"{name}.json").write_text(json.dumps(
        {"name": name, "claims": [{"text": t, "holds": h, "evidence": "e"}
                                  for t, h in claims]}))


BASE = {"h": [1, 2, 4], "err": [1.0, 0.25, 0.0625], "res": [1.0, 2e-16, 0.0],
        "series": ["h", "h", "p"], "wall_time_s": [0.1, 0.2, 0.3]}


def _pair(tmp_path, new=None, claims_new=(("rate ~2", True),)):
    old, nw = tmp_path / "old", tmp_path / "new"
    _write(old, "table_x", BASE, [("rate ~2", True)])
    _write(nw, "table_x", {**BASE, **(new or {})}, claims_new)
    return old, nw


def test_identical_and_roundoff_pass(cr, tmp_path, capsys):
    old, new = _pair(tmp_path, {"err": [1.0 + 1e-12, 0.25, 0.0625],
                                "res": [1.0, 1e-15, 5e-15],  # round-off wrt max 1
                                "wall_time_s": [9.0, 9.0, 9.0]})  # timing: skipped
    assert cr.main([str(old), str(new)]) == 0
    assert "OK   table_x" in capsys.readouterr().out


def test_value_difference_fails(cr, tmp_path, capsys):
    old, new = _pair(tmp_path, {"err": [1.0, 0.25, 0.07]})
    assert cr.main([str(old), str(new)]) == 1
    out = capsys.readouterr().out
    assert "DIFF table_x" in out and "'err'" in out and "row 2" in out
    assert cr.main([str(old), str(new), "--rtol", "0.2"]) == 0
    assert cr.main([str(old), str(new), "--atol", "0.01"]) == 0
    # a column entirely at round-off has a tiny floor: only --atol accepts it
    t = pd.DataFrame({"res": [1e-15, 2e-16]})
    assert cr.compare_tables(t, t.assign(res=[3e-15, 2e-16]))
    assert not cr.compare_tables(t, t.assign(res=[3e-15, 2e-16]), atol=1e-14)


def test_text_column_missing_column_and_rows(cr, tmp_path):
    old, new = _pair(tmp_path, {"series": ["h", "p", "p"]})
    assert any("'series'" in d for d in cr.compare_artefact("table_x", old, new, 1e-9)
               .differences)
    t = pd.DataFrame(BASE)
    diffs = cr.compare_tables(t, t.drop(columns="err").iloc[:2])
    assert any("missing in NEW" in d and "err" in d for d in diffs)
    assert any("row count" in d for d in diffs)


def test_claims_holds_changed_and_missing(cr, tmp_path, capsys):
    old, new = _pair(tmp_path, claims_new=[("rate ~2", False), ("extra", None)])
    assert cr.main([str(old), str(new)]) == 1
    out = capsys.readouterr().out
    assert "holds changed True -> False" in out and "missing in OLD: 'extra'" in out


def test_artefacts_on_one_side_are_info(cr, tmp_path, capsys):
    old, new = _pair(tmp_path)
    _write(old, "figure_y", {"a": [1.0]})
    assert cr.main([str(old), str(new)]) == 0
    assert "INFO figure_y" in capsys.readouterr().out
    assert cr.main([str(old), str(new), "--require-all"]) == 1
    assert cr.main([str(old), str(new), "--only", "table_x"]) == 0
    assert cr.main([str(old), str(tmp_path / "nope")]) == 2


def test_rename(cr, tmp_path, capsys):
    old, new = _pair(tmp_path)
    t = pd.DataFrame(BASE).rename(columns={"err": "error"})
    t.to_csv(new / "table_x.csv", index=False)
    assert cr.main([str(old), str(new)]) == 1
    assert cr.main([str(old), str(new), "--rename", "err=error"]) == 0
    assert "renamed err -> error" in capsys.readouterr().out
    assert cr.main([str(old), str(new), "--rename", "err"]) == 2


def test_thread_settings_warning(cr, tmp_path):
    old, new = _pair(tmp_path)
    doc = json.loads((new / "table_x.json").read_text())
    doc["provenance"] = {"threads_env": {"OPENBLAS_NUM_THREADS": "2"}}
    (new / "table_x.json").write_text(json.dumps(doc))
    rep = cr.compare_artefact("table_x", old, new)
    assert rep.ok and any("thread settings differ" in i for i in rep.info)


def test_nan_and_skipped_columns(cr):
    t = pd.DataFrame({"rate": [float("nan"), 2.0], "norm_S": [1.0, 2.0]})
    assert cr.compare_tables(t, t.copy()) == []
    assert cr.compare_tables(t, t.assign(rate=[1.0, 2.0]))  # NaN vs number differs
    assert cr.compare_tables(t, t.assign(norm_S=[1.0, 3.0]))  # not a timing column
    assert cr.is_skipped_column("t_solve_s") and cr.is_skipped_column("jit")
    assert not cr.is_skipped_column("norm_S")
