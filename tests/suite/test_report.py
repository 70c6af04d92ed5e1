"""The report builder: side-by-side tables, statuses, timing."""

import base64
import dataclasses
import io
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from hpfebe.suite.claims import Claim
from hpfebe.suite.published import compare
from hpfebe.suite.report import (MAX_FIGURE_WIDTH, READING_KEY, build_report, chapter_of,
                                 claim_kind, collect)
from hpfebe.suite.results import ArtefactResult, write_result

ROOT = Path(__file__).resolve().parents[2]


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
    for col in ("err published", "err reproduced", "err ratio", "err status",
                "rate published", "rate reproduced", "rate difference", "rate status"):
        assert col in md, col
    assert "| h | 12 | 1 | 0.0025 | 0.02 | x8 | off | 1 | -2 | -3 | off |" in md
    # HTML: a two-row header, the column over its published | reproduced | ... cells
    assert '<th class="g" colspan="4">err</th>' in html
    assert '<th class="g" colspan="4">rate</th>' in html
    assert ("<th>published</th><th>reproduced</th><th>ratio</th><th>status</th>"
            "<th>published</th><th>reproduced</th><th>difference</th><th>status</th>") in html
    for text in (html, md):
        assert "not run" in text and "not published" in text
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
    # table_9_9: an off cell and a failed thesis claim, neither linked to an explanation
    # (the notes and the claim's evidence explain nothing by themselves)
    assert "## table_9_9\n\n*table* - module `ch9` - status: **differs (unexplained)**" in md
    assert "1 off cell in column err (series=h, h_inv=12, p=1): unexplained" in md
    assert "thesis claim (no id: nothing can link it) differs: rate ~ 1: unexplained" in md


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


# --------------------------------------------------------------------------- status rules
#: the fake's off cells (_rates_table's defaults): err at h_inv=12 (x8) and rate at
#: h_inv=12 (-2.0 against 1.0); rate at h_inv=6 (1.17) is within 0.2
ERR = (0.011, 0.0049, 0.02, 0.0003)


def _rates_table(err=ERR):
    return pd.DataFrame({"series": ["h"] * 4, "h_inv": [3, 6, 12, 48], "p": [1] * 4,
                         "err": list(err), "rate": [np.nan, 1.17, -2.0, 2.0]})


def _status(tmp_path, claims, err=ERR, name="table_9_9"):
    """Write table_9_9 (against the published fake) with ``claims``; its entry."""
    pub = tmp_path / "published"
    pub.mkdir(exist_ok=True)
    (pub / "table_9_9_fake.csv").write_text(PUBLISHED)
    res = tmp_path / "results"
    write_result(ArtefactResult(
        name=name, table=_rates_table(err), published="table_9_9_fake.csv",
        keys=("series", "h_inv", "p"),
        tolerances={"err": ("factor", 1.5), "rate": ("abs", 0.2)}, claims=claims,
        meta={"allow_nan_columns": ["rate"]}), res)
    return {e.name: e for e in collect(res, pub)}[name]


def test_status_matches(tmp_path):
    pub = tmp_path / "published"
    pub.mkdir()
    (pub / "table_9_9_fake.csv").write_text(PUBLISHED)
    res = tmp_path / "results"
    write_result(ArtefactResult(
        name="table_9_9", table=pd.read_csv(pd.io.common.StringIO(PUBLISHED), comment="#"),
        published="table_9_9_fake.csv", keys=("series", "h_inv", "p"),
        tolerances={"err": ("factor", 1.5)},
        claims=[Claim("rate ~ 1", True, "rate 1.0"),
                Claim("ours beats it", False, "no", kind="beyond"),
                Claim("a coincidence", False, "no", kind="hypothesis", id="h",
                      explains=("cells:*",))],
        meta={"allow_nan_columns": ["rate"]}), res)
    (e,) = collect(res, pub)
    # a failed beyond claim and a failed hypothesis do not make it differ from the thesis
    assert e.status == "matches" and e.off_items == []


def test_status_explained_needs_a_link_to_an_explanation_that_holds(tmp_path):
    failed = Claim("rate ~ 1", False, "last common rate -2.0", id="rate")
    expl = Claim("h_inv=12 is a deliberate typo: the same run with the right number "
                 "gives 0.0025", True, "rerun: 0.0025", kind="explanation", id="typo",
                 explains=("rate", "cells:*"))
    e = _status(tmp_path, [failed, expl])
    assert e.status == "differs (explained)"
    assert {(i.what, i.column or i.claim["id"]) for i in e.off_items} == {
        ("cell", "err"), ("cell", "rate"), ("claim", "rate")}
    assert all(i.by == ["typo"] for i in e.off_items)
    build_report(tmp_path / "results", tmp_path / "out", tmp_path / "published")
    md = (tmp_path / "out" / "report.md").read_text()
    assert "status: **differs (explained)**" in md
    assert "1 off cell in column err (series=h, h_inv=12, p=1): explained by typo" in md
    assert "thesis claim [rate] differs: rate ~ 1: explained by typo" in md
    assert "**explanation, holds**: [typo] h_inv=12 is a deliberate typo" in md
    assert "(explains: rate, cells:*) - rerun: 0.0025" in md
    # the same explanation failing explains nothing
    e = _status(tmp_path, [failed, dataclasses.replace(expl, holds=False)])
    assert e.status == "differs (unexplained)"
    assert all(i.dead == ["typo"] and i.level == 0 for i in e.off_items)
    # an undecided explanation (holds None: e.g. over zero converged runs) neither
    e = _status(tmp_path, [failed, dataclasses.replace(expl, holds=None)])
    assert e.status == "differs (unexplained)"
    # a failed thesis claim left unlinked: unexplained, whatever else is explained
    e = _status(tmp_path, [failed, dataclasses.replace(expl, explains=("cells:*",))])
    assert e.status == "differs (unexplained)"
    assert [i.what for i in e.off_items if i.level == 0] == ["claim"]


def test_status_hypothesis(tmp_path):
    failed = Claim("rate ~ 1", False, "rate -2.0", id="rate")
    hyp = Claim("the thesis's 0.0025 looks like a rounding of ours", True, "0.02 ~ 0.0025?",
                kind="hypothesis", id="round", explains=("cells:*",))
    expl = Claim("the rate follows from the err cell", True, "log2(0.0049/0.02)",
                 kind="explanation", id="follows", explains=("rate",))
    e = _status(tmp_path, [failed, hyp, expl])
    assert e.status == "differs (hypothesis)"
    # the best link counts: an explanation beside the hypothesis makes it explained
    e = _status(tmp_path, [failed, hyp, expl,
                           dataclasses.replace(expl, id="cells", explains=("cells:*",))])
    assert e.status == "differs (explained)"
    # a hypothesis that fails links nothing
    e = _status(tmp_path, [failed, dataclasses.replace(hyp, holds=False), expl])
    assert e.status == "differs (unexplained)"


def test_status_cells_by_column_and_row(tmp_path):
    """cells:<col>[key=value] links the off cells of the rows with those key values only
    (numbers compared as numbers: "12" = 12.0)."""
    e_ = lambda *specs: _status(tmp_path, [Claim(
        "typo", True, "rerun", kind="explanation", id="x", explains=specs)],
        err=(0.011, 0.02, 0.02, 0.0003))     # err off at h_inv=6 and 12, rate at 12
    e = e_("cells:err[h_inv=12]", "cells:rate")
    assert e.status == "differs (unexplained)"
    unlinked = [(i.column, i.key["h_inv"]) for i in e.off_items if i.level == 0]
    assert unlinked == [("err", 6)]
    assert e_("cells:err[h_inv=12.0,series=h]", "cells:err[h_inv=6]",
              "cells:rate").status == "differs (explained)"
    assert e_("cells:err", "cells:rate[p=1]").status == "differs (explained)"
    assert e_("cells:*[h_inv=6]", "cells:*[h_inv=12]").status == "differs (explained)"
    # names that match nothing in the table are reported, not silently ignored
    e = e_("cells:*", "cells:nope", "cells:err[n=3]", "cells:err[h_inv]")
    assert e.status == "differs (explained)"
    assert len(e.link_problems) == 3
    assert any("'nope' is not a judged column" in p for p in e.link_problems)
    assert any("['n'] are not key columns" in p for p in e.link_problems)


def test_undecided_claim_and_thesis_only_counts(tmp_path):
    """holds None is undecided (not holding); the summary counts thesis claims only."""
    claims = [Claim("converged runs show rate 1", None, "0 converged runs", id="rate"),
              Claim("rate ~ 1", True, "rate 1.0"),
              Claim("(ours) faster", False, "no", kind="beyond"),
              Claim("(ours) more", True, "yes", kind="beyond"),
              Claim("mesh", True, "x", kind="explanation", explains=("cells:*",)),
              Claim("guess", None, "x", kind="hypothesis", explains=("rate",))]
    res = tmp_path / "r"
    write_result(ArtefactResult(name="figure_9_9", table=_rates_table(), figure=_fig(),
                                claims=claims, meta={"allow_nan_columns": ["rate"]}), res)
    build_report(res, tmp_path / "out", tmp_path / "nopub", expected={"figure_9_9": "ch9"})
    md = (tmp_path / "out" / "report.md").read_text()
    row = next(line for line in md.splitlines() if line.startswith("| figure_9_9"))
    cells = [c.strip() for c in row.split("|")[1:-1]]
    assert cells[3] == "no published numbers"   # a failed beyond claim is no difference
    assert cells[5] == "1 / 0 (+1 undecided)"
    assert cells[6] == ("1 explanation, 1 hypothesis (1 undecided), 2 beyond the thesis "
                        "(1 fails)")
    assert "- **undecided**: [rate] converged runs show rate 1 - 0 converged runs" in md
    assert "### Beyond the thesis" in md and "### Explanations and hypotheses" in md
    assert ("**hypothesis, undecided**: guess (explains: rate; it does not hold, so it "
            "explains nothing)") in md
    # the status counts: per chapter and in all, thesis claims only
    counts = md[md.index("## Status counts"):md.index("## Summary")]
    assert "| chapter 9 | 1 | 0 | 0 | 0 | 0 | 1 | 1 / 0 / 1 |" in counts
    assert "| all | 1 | 0 | 0 | 0 | 0 | 1 | 1 / 0 / 1 |" in counts


def test_results_without_kinds_are_thesis_claims(fake_results):
    """Results written before claims had kinds: every claim counts as a thesis claim,
    without links."""
    res, pub, _ = fake_results
    js = res / "table_9_9.json"
    doc = json.loads(js.read_text())
    doc["claims"] = [{"text": "rate ~ 1", "holds": False, "evidence": "e"},
                     {"text": "(analysis) typo", "holds": True, "evidence": "e"}]
    js.write_text(json.dumps(doc))
    e = {e.name: e for e in collect(res, pub)}["table_9_9"]
    assert e.status == "differs (unexplained)"
    assert [claim_kind(c) for c in e.claims] == ["thesis", "thesis"]


def _fig(width_in=4.0):
    fig = Figure(figsize=(width_in, 3))
    fig.subplots().plot([1, 2], [1, 4])
    return fig


def test_reading_and_chapters(tmp_path):
    res = tmp_path / "r"
    write_result(ArtefactResult(name="figure_dtn_map", table=pd.DataFrame({"x": [1]}),
                                figure=_fig(), meta={READING_KEY: "symmetric reading"}),
                 res, run_info={"module": "ch4_mortar"})
    write_result(ArtefactResult(name="figure_bem_laplace", table=pd.DataFrame({"x": [1]}),
                                figure=_fig()), res, run_info={"module": "bem_laplace"})
    entries = {e.name: e for e in collect(res, tmp_path / "nopub")}
    assert entries["figure_dtn_map"].chapter == "4"
    assert entries["figure_bem_laplace"].chapter == "other"
    assert chapter_of("table_2_1", "bem_laplace") == "2"
    build_report(res, tmp_path / "out", tmp_path / "nopub")
    md = (tmp_path / "out" / "report.md").read_text()
    html = (tmp_path / "out" / "index.html").read_text()
    assert "status: **no published numbers** - reading: *symmetric reading*" in md
    assert "| no published numbers - reading: symmetric reading |" in md
    assert "reading: <i>symmetric reading</i>" in html
    counts = md[md.index("## Status counts"):md.index("## Summary")]
    lines = [line for line in counts.splitlines() if line.startswith("| ")]
    assert [line.split("|")[1].strip() for line in lines] == [
        "chapter", "chapter 4", "other (no thesis chapter)", "all"]


def test_timing_one_row_per_job(tmp_path):
    """Jobs are scenes of a module: one Timing row per job (provenance.run.job), the
    module for results without a job, and the sums."""
    res = tmp_path / "r"
    for name, run in (("figure_9_1", {"module": "ch9", "job": "ch9__a", "scene": "a",
                                      "module_wall_time_s": 3.0, "jit_s": 0.5,
                                      "jit_compile_s": 0.5}),
                      ("figure_9_2", {"module": "ch9", "job": "ch9__a", "scene": "a",
                                      "module_wall_time_s": 3.0, "jit_s": 0.5,
                                      "jit_compile_s": 0.5}),
                      ("figure_9_3", {"module": "ch9", "job": "ch9__b", "scene": "b",
                                      "module_wall_time_s": 5.25, "jit_s": 1.0,
                                      "jit_compile_s": 0.0}),
                      ("figure_8_1", {"module": "ch8", "module_wall_time_s": 2.0})):
        write_result(ArtefactResult(name=name, table=pd.DataFrame({"x": [1]}),
                                    figure=_fig()), res, run_info=run)
    build_report(res, tmp_path / "out", tmp_path / "nopub")
    md = (tmp_path / "out" / "report.md").read_text()
    timing = md[md.index("## Timing"):].split("\n## ")[0]
    assert "| ch9__a | figure_9_1, figure_9_2 | 3.0 | 0.5 | 0.5 |" in timing
    assert "| ch9__b | figure_9_3 | 5.2 | 0.0 | 1.0 |" in timing
    assert "| ch8 | figure_8_1 | 2.0 | - | - |" in timing
    assert "| all jobs (sum) | 3 jobs | 10.2 | 0.5 | 1.5 |" in timing
    assert "module `ch9` - job `ch9__b` - status" in md


def test_legibility_markup_notes_and_figures(tmp_path):
    """No raw markup in the HTML, a module's shared notes shown once, figures embedded
    at most MAX_FIGURE_WIDTH wide."""
    shared = ("The shared method. " + "Long text " * 30 + "ends. Uses ``two_pass = true`` "
              "and :func:`dtn`. ")
    res = tmp_path / "r"
    for i, extra in ((1, "First only."), (2, "Second `only`."), (3, "")):
        write_result(ArtefactResult(
            name=f"figure_9_{i}", table=pd.DataFrame({"x": [1]}),
            figure=_fig(width_in=20.0 if i == 1 else 4.0), notes=shared + extra,
            claims=[Claim("``u_x`` grows", True, "`max` 2")]), res,
            run_info={"module": "ch9"})
    build_report(res, tmp_path / "out", tmp_path / "nopub")
    html = (tmp_path / "out" / "index.html").read_text()
    md = (tmp_path / "out" / "report.md").read_text()
    assert "`" not in html
    assert "<code>two_pass = true</code>" in html and "<code>dtn</code>" in html
    assert "<code>u_x</code> grows" in html and "<code>only</code>" in html
    for text in (html, md):
        assert text.count("The shared method.") == 1
    assert "First only." in md and "Second `only`." in md
    assert md.count("see [figure_9_1](#figure_9_1)") == 2
    assert "Uses `two_pass = true` and `dtn`." in md
    from PIL import Image
    b64 = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", html)
    widths = [Image.open(io.BytesIO(base64.b64decode(b))).width for b in b64]
    assert Image.open(res / "figure_9_1.png").width > MAX_FIGURE_WIDTH
    assert max(widths) == MAX_FIGURE_WIDTH and len(widths) == 3


def test_shown_columns_beside_the_judged_ones(tmp_path):
    """Published columns without a tolerance are shown beside ours, not judged (Table
    4.3's Newton iterations)."""
    pub = tmp_path / "published"
    pub.mkdir()
    (pub / "table_9_9_fake.csv").write_text("# fake\nk,newton,pen\n1,175,1e-6\n2,520,2e-6\n")
    res = tmp_path / "r"
    write_result(ArtefactResult(
        name="table_9_9", table=pd.DataFrame({"k": [1, 2], "newton": [13, 20],
                                              "pen": [1.1e-6, 2.1e-6]}),
        published="table_9_9_fake.csv", keys=("k",), tolerances={"pen": ("factor", 2.0)},
        meta={READING_KEY: "two-pass penalty contact"}), res)
    (e,) = collect(res, pub)
    assert e.status == "matches" and e.comparison.shown == ["newton"]
    assert e.status_text == "matches - reading: two-pass penalty contact"
    build_report(res, tmp_path / "out", pub)
    md = (tmp_path / "out" / "report.md").read_text()
    assert "| ok | 175 | 13 | x0.0743 |" in md and "Not judged: newton." in md


def test_figure_encoding_cache(tmp_path, monkeypatch):
    """The report's re-encoded PNGs come from a cache keyed on the bytes: the same bytes
    with or without it, one entry per distinct figure, a damaged entry encoded again."""
    from hpfebe.suite.report import figures as rf

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    res = tmp_path / "r"
    for i, w in ((1, 20.0), (2, 4.0)):
        write_result(ArtefactResult(name=f"figure_9_{i}", table=pd.DataFrame({"x": [1]}),
                                    figure=_fig(width_in=w)), res, run_info={"module": "ch9"})
    pngs = [res / "figure_9_1.png", res / "figure_9_2.png"]
    fresh = [rf.encode_for_html(p.read_bytes()) for p in pngs]
    assert [rf.png_for_html(p) for p in pngs] == fresh           # encoded, then stored
    entries = sorted((tmp_path / "cache" / "hpfebe" / "report-png").glob("*.png"))
    assert len(entries) == 2
    assert [rf.png_for_html(p) for p in pngs] == fresh           # from the cache
    entries[0].write_bytes(b"damaged")
    assert [rf.png_for_html(p) for p in pngs] == fresh
    assert all(e.read_bytes().startswith(rf.PNG_SIGNATURE) for e in entries)
