"""The command line: hpfebe --help / list / run / report."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from hpfebe import cli

ROOT = Path(__file__).resolve().parents[2]


def hpfebe(*args, cwd=ROOT, timeout=900):
    return subprocess.run([sys.executable, "-m", "hpfebe", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout)


def test_help_exit_0():
    r = hpfebe("--help")
    assert r.returncode == 0, r.stderr
    for cmd in ("list", "run", "report", "compile"):
        assert cmd in r.stdout


@pytest.mark.slow
def test_compile_writes_stamp(tmp_path):
    """`hpfebe compile --stamp F` readies every kernel the experiments call: afterwards a
    module run compiles nothing (numba's cache shared through NUMBA_CACHE_DIR; an empty
    one here, so this compiles everything once: ~1 min of CPU)."""
    import json
    import os

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "nbc"), NUMBA_NUM_THREADS="1")
    run = lambda *a: subprocess.run([sys.executable, "-m", "hpfebe", *a], cwd=ROOT, env=env,  # noqa: E731
                                    capture_output=True, text=True, timeout=900)
    r = run("compile", "--stamp", str(tmp_path / "stamp.json"))
    assert r.returncode == 0, r.stderr
    rec = json.loads((tmp_path / "stamp.json").read_text())
    assert {"laplace", "lame", "projected_cg"} <= set(rec["steps_s"])
    r = run("run", "figure_3_2", "--quick", "--out", str(tmp_path / "res"))
    assert r.returncode == 0, r.stderr
    prov = json.loads((tmp_path / "res" / "figure_3_2.json").read_text())["provenance"]
    assert prov["run"]["jit_compile_s"] == 0.0
    # the second call finds the tree's kernels readied (ready.json) and runs no warm-up
    r = run("compile", "--stamp", str(tmp_path / "again.json"))
    assert r.returncode == 0 and "compiled before into" in r.stderr, r.stderr
    assert json.loads((tmp_path / "again.json").read_text())["steps_s"] == {}
    r = run("compile", "--force", "--stamp", str(tmp_path / "forced.json"))
    assert r.returncode == 0, r.stderr
    forced = json.loads((tmp_path / "forced.json").read_text())
    assert set(forced["steps_s"]) == set(rec["steps_s"]) and forced["jit_compile_s"] == 0.0


@pytest.mark.skipif(shutil.which("hpfebe") is None, reason="console script not on PATH")
def test_console_script_help():
    r = subprocess.run(["hpfebe", "--help"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "usage: hpfebe" in r.stdout


def test_run_help_mentions_options():
    r = hpfebe("run", "--help")
    assert r.returncode == 0
    for opt in ("--quick", "--out", "--config"):
        assert opt in r.stdout


def test_list_shows_demo():
    r = hpfebe("list")
    assert r.returncode == 0, r.stderr
    line = next(l for l in r.stdout.splitlines() if l.startswith("figure_bem_laplace"))
    assert "bem_laplace" in line.split()[1]


def test_list_from_another_directory(tmp_path):
    """The experiments are found relative to the repository, not the cwd."""
    r = hpfebe("list", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "figure_bem_laplace" in r.stdout


def test_unknown_artefact_clear_error(tmp_path):
    r = hpfebe("run", "table_99_99", "--out", str(tmp_path))
    assert r.returncode == 2
    assert "unknown artefact 'table_99_99'" in r.stderr
    assert "figure_bem_laplace" in r.stderr  # lists what is known
    assert "Traceback" not in r.stderr
    assert not list(tmp_path.iterdir())


def test_missing_config_file_clear_error(tmp_path):
    r = hpfebe("run", "figure_bem_laplace", "--config", str(tmp_path / "nope.yaml"),
               "--out", str(tmp_path))
    assert r.returncode == 2 and "config file not found" in r.stderr


def test_no_command_prints_help():
    r = hpfebe()
    assert r.returncode == 2 and "usage" in r.stdout


def test_merge_config():
    base = {"quick": False, "m": {"a": 1, "b": {"c": 2, "d": 3}}, "n": [1, 2]}
    over = {"quick": True, "m": {"b": {"c": 5}}, "n": [3]}
    assert cli.merge(base, over) == {"quick": True, "m": {"a": 1, "b": {"c": 5, "d": 3}},
                                     "n": [3]}


@pytest.mark.slow
def test_run_demo_quick(tmp_path):
    """The whole pipeline on the demo (compiles numba on a cold cache: up to ~1 min)."""
    r = hpfebe("run", "figure_bem_laplace", "--quick", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    for ext in ("csv", "json", "png"):
        assert (tmp_path / f"figure_bem_laplace.{ext}").stat().st_size > 0, ext
    doc = json.loads((tmp_path / "figure_bem_laplace.json").read_text())
    assert doc["provenance"]["run"]["quick"] is True
    assert doc["claims"][0]["holds"] is True, doc["claims"][0]["evidence"]
    assert doc["provenance"]["config"]["n_per_side"] == [2, 4, 8]  # quick.yaml merged

    out = tmp_path / "report"
    r = hpfebe("report", "--results", str(tmp_path), "--out", str(out))
    assert r.returncode == 0, r.stderr
    html = (out / "index.html").read_text()
    assert "figure_bem_laplace" in html and "data:image/png;base64," in html


def test_published_columns_checked(tmp_path):
    import pandas as pd

    from hpfebe.suite.results import ArtefactResult

    (tmp_path / "table_9_9_x.csv").write_text("# caption\nh_inv,err\n2,0.1\n")
    table = pd.DataFrame({"h_inv": [2], "err": [0.1]})
    ok = ArtefactResult("table_9_9", table, published="table_9_9_x.csv", keys=("h_inv",),
                        tolerances={"err": ("factor", 2.0)})
    cli._check_published(ok, tmp_path)
    bad = ArtefactResult("table_9_9", table.rename(columns={"err": "error"}),
                         published="table_9_9_x.csv", keys=("h_inv",),
                         tolerances={"error": ("factor", 2.0)})
    with pytest.raises(ValueError, match="'error'"):
        cli._check_published(bad, tmp_path)
    missing = ArtefactResult("table_9_9", table, published="nope.csv")
    with pytest.raises(ValueError, match="not found"):
        cli._check_published(missing, tmp_path)


def test_quick_run_without_out_keeps_full_results(tmp_path, monkeypatch):
    """`hpfebe run X --quick` without --out writes to results/quick/ (here a scratch
    folder), never over the full results in results/."""
    monkeypatch.setattr(cli, "QUICK_OUT", tmp_path / "quick")
    assert cli.main(["-q", "run", "figure_bem_laplace", "--quick"]) == 0
    doc = json.loads((tmp_path / "quick" / "figure_bem_laplace.json").read_text())
    assert doc["provenance"]["run"]["quick"] is True
    assert doc["provenance"]["run"]["job"] == "bem_laplace"


def test_run_names_a_job(tmp_path):
    """An artefact id runs its scene's job only; the job's rule name works too."""
    from hpfebe.suite.registry import discover

    reg = discover(ROOT / "experiments")
    job = next(j for j in reg.jobs if j.scene is not None)
    assert reg.find_jobs(job.artefacts[0]) == (job,)
    assert reg.find_jobs(job.rule) == (job,)
    assert reg.find_jobs(job.experiment.name) == job.experiment.jobs
    with pytest.raises(KeyError, match="unknown artefact"):
        reg.find_jobs("table_0_0")


def test_run_several_names_one_after_another(tmp_path):
    """`hpfebe run A B` runs both jobs in one process (a SLURM bundle's command), each
    result with its own job in the provenance; an unknown name is refused before any job
    runs."""
    assert cli.main(["-q", "run", "figure_bem_laplace", "ch2_coercivity", "--quick",
                     "--out", str(tmp_path)]) == 0
    jobs = {a: json.loads((tmp_path / f"{a}.json").read_text())["provenance"]["run"]["job"]
            for a in ("figure_bem_laplace", "figure_coercivity")}
    assert jobs == {"figure_bem_laplace": "bem_laplace", "figure_coercivity": "ch2_coercivity"}
    out = tmp_path / "refused"
    assert cli.main(["-q", "run", "bem_laplace", "table_0_0", "--out", str(out)]) == 2
    assert not out.exists() or not any(out.iterdir())
