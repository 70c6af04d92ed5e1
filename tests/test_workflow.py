"""The workflow: Snakefile dry runs, the experiment registry and the report builder."""

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from hpfebe.report import build_report, compare
from hpfebe.results import ArtefactResult, Claim, write_result

ROOT = Path(__file__).resolve().parents[1]


def _registry_module():
    spec = importlib.util.spec_from_file_location("_hpfebe_registry",
                                                  ROOT / "experiments" / "registry.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


def snakemake(*args, timeout=600):
    return subprocess.run([sys.executable, "-m", "snakemake", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


# --------------------------------------------------------------------------- Snakefile
def test_dry_run():
    r = snakemake("-n")
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout + r.stderr
    # the workflow profile (profiles/default) is picked up by a bare `snakemake`
    assert "profiles/default" in out


def test_dry_run_quick_passes_quick_flag():
    # --forceall: list every job even if results/ is up to date
    r = snakemake("-n", "--forceall", "-p", "--configfile", "config/quick.yaml")
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout + r.stderr
    assert "rule bem_laplace" in out
    assert "-m hpfebe run figure_bem_laplace --out results --quick" in out
    assert "--config config/quick.yaml" in out
    assert "NUMBA_NUM_THREADS=1" in out and "OMP_NUM_THREADS=1" in out


def test_one_rule_per_module():
    reg = _registry_module().discover(ROOT / "experiments")
    r = snakemake("--list-rules")
    assert r.returncode == 0, r.stdout + r.stderr
    rules = set(r.stdout.split())
    assert {"all", "report"} <= rules
    assert {e.name for e in reg} <= rules


def test_numba_kernels_compiled_once_first(tmp_path):
    """On a fresh machine (no results yet) one `hpfebe compile` job comes first and every
    module calling numba waits for it (no two jobs compile the same kernels); a module
    with NUMBA = False runs beside it.  (Modules whose results exist never wait: the
    stamp only orders jobs.)"""
    reg = _registry_module().discover(ROOT / "experiments")
    for d in ("experiments", "config", "report", "src", "profiles"):
        (tmp_path / d).symlink_to(ROOT / d)
    r = subprocess.run([sys.executable, "-m", "snakemake", "-n", "-s", str(ROOT / "Snakefile"),
                        "--configfile", "config/quick.yaml"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    blocks = {b.split(":", 1)[0].strip(): b for b in r.stdout.split("\nrule ")[1:]}
    assert "numba_cache" in blocks
    for e in reg:
        waits = "results/logs/numba_cache.json" in blocks[e.name].split("output:")[0]
        assert waits == e.numba, e.name
    assert any(not e.numba for e in reg)


def test_slurm_profile_dry_run():
    pytest.importorskip("snakemake_executor_plugin_slurm",
                        reason="snakemake-executor-plugin-slurm not installed "
                               "(pip install -e '.[cluster]')")
    r = snakemake("-n", "--profile", "profiles/slurm")
    assert r.returncode == 0, r.stdout + r.stderr


# --------------------------------------------------------------------------- registry
def test_registry_finds_demo():
    reg = _registry_module().discover(ROOT / "experiments")
    assert reg.find("figure_bem_laplace").name == "bem_laplace"
    assert reg.find("bem_laplace").artefacts == ("figure_bem_laplace",)
    with pytest.raises(KeyError, match="unknown artefact"):
        reg.find("table_0_0")


def test_registry_rules(tmp_path):
    registry = _registry_module()
    (tmp_path / "ch1_a.py").write_text('"""doc"""\nARTEFACTS = ("table_1_1", "figure_1_1")\n')
    (tmp_path / "helpers.py").write_text("X = 1\n")            # no ARTEFACTS: ignored
    (tmp_path / "_private.py").write_text('ARTEFACTS = ("table_7_7",)\n')  # ignored
    reg = registry.discover(tmp_path)
    assert [e.name for e in reg] == ["ch1_a"]
    assert list(reg.artefacts) == ["table_1_1", "figure_1_1"]

    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_1",)\n')
    with pytest.raises(ValueError, match="claimed by both"):
        registry.discover(tmp_path)
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = tuple(f"t{i}" for i in range(2))\n')
    with pytest.raises(ValueError, match="literal"):
        registry.discover(tmp_path)
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_2",)\nNUMBA = False\n')
    assert [e.numba for e in registry.discover(tmp_path)] == [True, False]
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_2",)\nNUMBA = "no"\n')
    with pytest.raises(ValueError, match="NUMBA must be"):
        registry.discover(tmp_path)
    (tmp_path / "ch1_b.py").unlink()
    (tmp_path / "report.py").write_text('ARTEFACTS = ("table_2_9",)\n')
    with pytest.raises(ValueError, match="reserved"):
        registry.discover(tmp_path)


# --------------------------------------------------------------------------- report
PUBLISHED = """# Thesis Table 9.9: a fake table for the test
series,h_inv,p,err,rate
h,3,1,0.01,
h,6,1,0.005,1.0
h,12,1,0.0025,1.0
h,24,1,0.00125,1.0
"""


@pytest.fixture
def fake_results(tmp_path):
    pub = tmp_path / "published"
    pub.mkdir()
    (pub / "table_9_9_fake.csv").write_text(PUBLISHED)
    (pub / "table_9_8_other.csv").write_text("# other\na,b\n1,2\n")
    res = tmp_path / "results"
    table = pd.DataFrame({
        "series": ["h", "h", "h", "h"],
        "h_inv": [3, 6, 12, 48],              # 24 not run, 48 not published
        "p": [1, 1, 1, 1],
        "err": [0.011, 0.0049, 0.02, 0.0003],  # h_inv=12 is off by a factor 8
        "rate": [np.nan, 1.17, -2.0, 2.0],
        "dof": [8, 16, 32, 128],
        "wall_time_s": [0.1, 0.2, 0.3, 0.4],
    })
    write_result(ArtefactResult(
        name="table_9_9", table=table, published="table_9_9_fake.csv",
        keys=("series", "h_inv", "p"),
        tolerances={"err": ("factor", 1.5), "rate": ("abs", 0.2)},
        claims=[Claim("rate ~ 1", False, "last common rate -2.0: h_inv=12 is off")],
        notes="h_inv=12 differs because of a deliberately wrong number.",
        meta={"allow_nan_columns": ["rate"], "run_s": 2.0}), res)
    fig = Figure()
    fig.subplots().plot([1, 2], [1, 4])
    write_result(ArtefactResult(name="figure_9_9", table=table[["h_inv", "err"]],
                                figure=fig, claims=[Claim("converges", True, "rate 2")],
                                notes="a figure note"), res)
    return res, pub, tmp_path / "report"


def test_report_builds_side_by_side(fake_results):
    res, pub, out = fake_results
    expected = {"table_9_9": "ch9", "figure_9_9": "ch9", "table_9_7": "ch9_missing"}
    paths = build_report(res, out, pub, expected=expected)
    assert {p.name for p in paths} == {"index.html", "report.md"}
    html = (out / "index.html").read_text()
    md = (out / "report.md").read_text()
    for text in (html, md):
        for col in ("err published", "err reproduced", "err difference", "err status",
                    "rate published", "rate reproduced"):
            assert col in text, col
        assert "not run" in text and "not published" in text
        assert "differs (explained)" in text          # table_9_9
        assert "not built" in text                    # table_9_7 has no result
        assert "not implemented" in text              # table_9_8: published only
        assert "a figure note" in text and "converges" in text
        assert "Provenance" in text
        assert "Thesis Table 9.9: a fake table for the test" in text
    # self-contained HTML: figure embedded, no external assets
    assert "data:image/png;base64," in html
    assert "<link" not in html and "src='http" not in html and 'src="http' not in html
    assert "<style>" in html
    # Markdown links the figure relative to the report directory
    assert "](../results/figure_9_9.png)" in md


def test_report_timing_has_compile_job(fake_results):
    """The Timing table: one row per module, the workflow's `hpfebe compile` job (its
    record in results/logs) as a row of its own, and the sums."""
    res, pub, out = fake_results
    (res / "logs").mkdir()
    (res / "logs" / "numba_cache.json").write_text(
        '{"wall_s": 31.5, "jit_compile_s": 30.25, "jit_s": 30.5, "steps_s": {}}')
    build_report(res, out, pub, expected={"table_9_9": "ch9", "figure_9_9": "ch9"})
    for text in ((out / "report.md").read_text(), (out / "index.html").read_text()):
        timing = text[text.index("Timing"):]
        assert "numba kernels" in timing and "31.5" in timing
        assert "33.5" in timing           # 31.5 + the module's run_s 2.0
    (res / "logs" / "numba_cache.json").write_text("{broken")   # ignored, no crash
    build_report(res, out, pub, expected={"table_9_9": "ch9", "figure_9_9": "ch9"})
    assert "numba kernels" not in (out / "report.md").read_text()


def test_compare_cells():
    pub = pd.read_csv(pd.io.common.StringIO(PUBLISHED), comment="#")
    rep = pd.DataFrame({"series": ["h", "h"], "h_inv": [3.0, 6.0], "p": [1, 1],
                        "err": [0.0149, 0.0076], "rate": [np.nan, 0.85]})
    cmp = compare(pub, rep, ("series", "h_inv", "p"),
                  {"err": ("factor", 1.5), "rate": ("abs", 0.15)})
    cells = {(r["key"]["h_inv"], c): r["cells"][c]["status"]
             for r in cmp.rows for c in ("err", "rate")}
    assert cells[(3, "err")] == "ok"          # ratio 1.49
    assert cells[(6, "err")] == "off"         # ratio 1.52
    assert cells[(3, "rate")] == "ok"         # both empty
    assert cells[(6, "rate")] == "ok"         # |diff| = 0.15
    assert cells[(12, "err")] == "not run"
    assert (cmp.n_ok, cmp.n_off, cmp.n_not_run, cmp.n_not_published) == (3, 1, 2, 0)


def test_report_without_results(tmp_path):
    build_report(tmp_path / "nothing", tmp_path / "out", tmp_path / "nopub",
                 expected={"figure_1_1": "ch1"})
    assert "not built" in (tmp_path / "out" / "report.md").read_text()
