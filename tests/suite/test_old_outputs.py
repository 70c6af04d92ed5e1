"""A cluster job's old outputs are set aside, not removed, until it has succeeded
(hpfebe.suite.old_outputs, the Snakefile's patch of Snakemake's output removal)."""

import os
import subprocess
import sys

from hpfebe.suite import old_outputs


def _results(tmp_path):
    out = tmp_path / "results" / "tables"
    out.mkdir(parents=True)
    a, b = out / "table_3_1.csv", out / "table_3_2.csv"
    a.write_text("old a\n")
    b.write_text("old b\n")
    os.utime(a, (1e9, 1e9))
    return a, b


def test_a_failed_job_gets_its_old_outputs_back(tmp_path):
    a, b = _results(tmp_path)
    missing = a.parent / "table_3_3.csv"
    moved = old_outputs.set_aside("j1", [a, b, missing], root=tmp_path / "aside")
    assert moved == [a, b] and not a.exists() and not b.exists()
    a.write_text("new a, then the job failed\n")       # (written before it stopped)
    assert old_outputs.restore("j1") == [a, b]
    assert a.read_text() == "old a\n" and b.read_text() == "old b\n"
    assert a.stat().st_mtime == 1e9                     # a rename: the mtime is kept
    assert not missing.exists() and not any((tmp_path / "aside").rglob("*"))


def test_a_successful_job_drops_its_old_outputs(tmp_path):
    a, b = _results(tmp_path)
    old_outputs.set_aside("j2", [a, b], root=tmp_path / "aside")
    a.write_text("new a\n")
    b.write_text("new b\n")
    old_outputs.drop("j2")
    assert a.read_text() == "new a\n" and b.read_text() == "new b\n"
    assert not any((tmp_path / "aside").rglob("*"))
    assert old_outputs.restore("j2") == []              # nothing left to put back


def test_a_restarted_job_sets_aside_the_first_old_outputs_again(tmp_path):
    a, b = _results(tmp_path)
    old_outputs.set_aside("j3", [a, b], root=tmp_path / "aside")
    b.write_text("new b of the first attempt\n")
    old_outputs.set_aside("j3", [a, b], root=tmp_path / "aside")   # the restart
    old_outputs.restore("j3")
    assert b.read_text() == "old b\n"


def test_an_ending_snakemake_puts_back_what_is_still_aside(tmp_path):
    a, b = _results(tmp_path)
    code = ("import sys\nfrom pathlib import Path\nfrom hpfebe.suite import old_outputs\n"
            "old_outputs.set_aside(7, list(map(Path, sys.argv[2:])), Path(sys.argv[1]))\n"
            "assert not Path(sys.argv[2]).exists()\n"
            "raise SystemExit(1)\n")
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "aside"), str(a),
                           str(b)], capture_output=True, text=True)
    assert proc.returncode == 1, proc.stderr
    assert a.read_text() == "old a\n" and b.read_text() == "old b\n"
