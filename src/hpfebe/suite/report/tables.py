"""What the Markdown and the HTML report both show, as text and rows: the formatting of
numbers, differences and tolerances, the status counts, the summary, the timing, the
differences with their links, the side-by-side comparison, the claims and the
provenance.  The renderers (:mod:`.markdown`, :mod:`.html`) only lay them out.
"""

from __future__ import annotations

import json
import math
import re
from datetime import datetime, timezone
from pathlib import Path

from ..published import Comparison
from .entries import Entry, chapter_label
from .status import (ALWAYS_COUNTED, LINK_EXPLANATION, LINK_HYPOTHESIS, LINK_NONE,
                     STATUS_ORDER, OffItem, claim_explains, claim_kind)

__all__ = ["fmt", "fmt_tol", "summary_rows", "SUMMARY_HEADER", "status_counts",
           "difference_lines", "comparison_groups", "comparison_table", "timing_rows",
           "compile_record", "TIMING_HEADER", "TIMING_INTRO", "provenance_summary", "INTRO",
           "STATUS_COUNTS_INTRO", "claim_line", "CLAIM_SECTIONS", "CODE_RE",
           "MAX_TABLE_ROWS", "OTHER_KINDS"]

#: claim kinds listed apart from the thesis's claims, with their labels
OTHER_KINDS = {"explanation": ("explanation", "explanations"),
               "hypothesis": ("hypothesis", "hypotheses"),
               "beyond": ("beyond the thesis", "beyond the thesis")}

#: rows of a reproduced table shown (the rest are in its CSV file)
MAX_TABLE_ROWS = 200


def fmt(x, digits=6) -> str:
    """A cell as text: "-" for empty or NaN, integers without a point, else ``digits``
    significant digits."""
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    if isinstance(x, bool):
        return str(x)
    if isinstance(x, int) and not isinstance(x, bool):
        return str(x)
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    if math.isnan(v):
        return "-"
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return f"{v:.{digits}g}"


def _diff_title(tol) -> str:
    """What the difference column of a compared column shows: the quantity its
    tolerance bounds."""
    return "ratio" if tol[0] == "factor" else "difference"


def _fmt_diff(cell, tol) -> str:
    """reproduced / published for a factor tolerance ("x1.02"; the difference if the
    published value is 0), reproduced - published for an absolute one."""
    if cell["diff"] is None:
        return ""
    if tol[0] == "factor" and cell["ratio"] is not None and math.isfinite(cell["ratio"]):
        return f"x{cell['ratio']:.3g}"
    return "0" if cell["diff"] == 0 else f"{cell['diff']:+.3g}"


def fmt_tol(tol) -> str:
    return f"ratio within x{tol[1]:g}" if tol[0] == "factor" else f"|diff| <= {tol[1]:g}"


def _thesis_counts(e: Entry) -> tuple[int, int, int]:
    """Thesis claims (holding, differing, undecided)."""
    c = e.claims_of("thesis")
    hold = sum(x.get("holds") is True for x in c)
    diff = sum(x.get("holds") is False for x in c)
    return hold, diff, len(c) - hold - diff


def _claims_counts(e: Entry) -> str:
    if not e.doc:
        return ""
    if not e.claims_of("thesis"):
        return "-"
    hold, diff, und = _thesis_counts(e)
    return f"{hold} / {diff}" + (f" (+{und} undecided)" if und else "")


def _others_counts(e: Entry) -> str:
    """The claims that are not the thesis's, per kind: "2 explanations (1 fails)"."""
    parts = []
    for kind, (one, many) in OTHER_KINDS.items():
        c = e.claims_of(kind)
        if not c:
            continue
        fails = sum(x.get("holds") is False for x in c)
        und = sum(x.get("holds") is None for x in c)
        extra = [f"{fails} fail{'s' if fails == 1 else ''}"] if fails else []
        extra += [f"{und} undecided"] if und else []
        parts.append(f"{len(c)} {one if len(c) == 1 else many}"
                     + (f" ({', '.join(extra)})" if extra else ""))
    return ", ".join(parts) if parts else ("-" if e.doc else "")


def _cells_counts(e: Entry) -> str:
    cmp = e.comparison
    if cmp is None:
        return "-" if e.doc else ""
    s = f"{cmp.n_ok} ok / {cmp.n_off} off"
    extra = []
    if cmp.n_not_run:
        extra.append(f"{cmp.n_not_run} rows not run")
    if cmp.n_not_published:
        extra.append(f"{cmp.n_not_published} not published")
    return s + (f" ({', '.join(extra)})" if extra else "")


def _verdict(holds) -> str:
    return {True: "holds", False: "differs", None: "undecided"}.get(holds, str(holds))


def summary_rows(entries):
    rows = []
    for e in entries:
        t = e.wall_time
        rows.append([e.name, e.kind, e.module or "-", e.status_text, _cells_counts(e),
                     _claims_counts(e), _others_counts(e), "" if t is None else f"{t:.1f}"])
    return rows


SUMMARY_HEADER = ["artefact", "kind", "module", "status", "cells (tolerance)",
                  "thesis claims hold / differ", "other claims (not counted)",
                  "job wall time [s]"]


def status_counts(entries) -> tuple[list[str], list[list[str]]]:
    """Artefacts per status, per chapter and in all, with the thesis claims holding /
    differing / undecided."""
    chapters: dict[str, list[Entry]] = {}
    for e in entries:
        chapters.setdefault(e.chapter, []).append(e)
    order = sorted(chapters, key=lambda c: (c == "other", int(c) if c.isdigit() else 0, c))
    statuses = [s for s in STATUS_ORDER
                if s in ALWAYS_COUNTED or any(e.status == s for e in entries)]
    header = ["chapter", "artefacts", *statuses, "thesis claims hold / differ / undecided"]

    def row(label, es):
        tc = [sum(t) for t in zip(*(_thesis_counts(e) for e in es))] or [0, 0, 0]
        return ([label, str(len(es))] + [str(sum(e.status == s for e in es))
                                         for s in statuses] + [" / ".join(map(str, tc))])
    rows = [row(chapter_label(c), chapters[c]) for c in order]
    rows.append(row("all", list(entries)))
    return header, rows


def _key_label(key: dict) -> str:
    return ", ".join(f"{k}={fmt(v)}" for k, v in key.items())


def _link_text(level: int, by: list[str], dead: list[str]) -> str:
    if level == LINK_EXPLANATION:
        s = "explained by " + ", ".join(by)
    elif level == LINK_HYPOTHESIS:
        s = "hypothesis only: " + ", ".join(by)
    else:
        s = "unexplained"
    if dead:
        s += (" (also " if level else " (") + "linked to " + ", ".join(dead) + \
             ", which do" + ("es" if len(dead) == 1 else "") + " not hold)"
    return s


def difference_lines(e: Entry, max_keys: int = 6) -> list[tuple[str, str, int]]:
    """What differs and its best link, one line per group: (what, link, link level)."""
    groups: dict[tuple, list[OffItem]] = {}
    for it in e.off_items:
        if it.what == "cell":
            g = ("cell", it.column, it.level, tuple(it.by), tuple(it.dead))
        else:
            g = ("claim", id(it), it.level, tuple(it.by), tuple(it.dead))
        groups.setdefault(g, []).append(it)
    lines = []
    for (what, col, level, by, dead), its in groups.items():
        link = _link_text(level, list(by), list(dead))
        if what == "cell":
            keys = "; ".join(_key_label(it.key) for it in its[:max_keys])
            more = f"; and {len(its) - max_keys} more" if len(its) > max_keys else ""
            n = len(its)
            lines.append((f"{n} off cell{'s' if n > 1 else ''} in column {col} "
                          f"({keys}{more})", link, level))
        else:
            c = its[0].claim
            cid = f" [{c['id']}]" if c.get("id") else " (no id: nothing can link it)"
            lines.append((f"thesis claim{cid} differs: {c.get('text', '')}", link, level))
    lines += [("link problem", p, LINK_NONE) for p in e.link_problems]
    return lines


def comparison_groups(cmp: Comparison) -> list[tuple[str, list[str]]]:
    """Column groups of the side-by-side table: (group title, sub-column titles)."""
    groups = [(c, ["published", "reproduced", _diff_title(cmp.tolerances[c]), "status"])
              for c in cmp.columns]
    groups += [(f"{c} (not judged)", ["published", "reproduced", "ratio"])
               for c in cmp.shown]
    return groups


def comparison_table(cmp: Comparison):
    """Flat header ("<column> published", ...), rows and per-cell classes."""
    header = list(cmp.keys)
    for title, subs in comparison_groups(cmp):
        header += [f"{title.replace(' (not judged)', '')} {s}" for s in subs]
    rows, classes = [], []
    for r in cmp.rows:
        row = [fmt(r["key"][k]) for k in cmp.keys]
        cl = [None] * len(cmp.keys)
        for c in cmp.columns:
            cell = r["cells"][c]
            row += [fmt(cell["pub"]), fmt(cell["rep"]), _fmt_diff(cell, cmp.tolerances[c]),
                    cell["status"]]
            cl += [None, None, None, _cell_class(cell["status"])]
        for c in cmp.shown:
            cell = r["shown"][c]
            row += [fmt(cell["pub"]), fmt(cell["rep"]), _fmt_diff(cell, ("factor", 0))]
            cl += ["na", "na", "na"]
        rows.append(row)
        classes.append(cl)
    return header, rows, classes


TIMING_HEADER = ["job", "artefacts", "run time [s]", "numba compile [s]",
                 "numba JIT incl. cache loads [s]"]


def _fmt_s(t) -> str:
    return "-" if t is None else f"{t:.1f}"


def compile_record(results_dir: Path) -> dict | None:
    """The workflow's `hpfebe compile` record (results/logs/numba_cache.json), if any."""
    try:
        rec = json.loads((Path(results_dir) / "logs" / "numba_cache.json").read_text())
        return {k: float(rec[k]) for k in ("wall_s", "jit_compile_s", "jit_s")}
    except (OSError, ValueError, KeyError, TypeError):
        return None


def timing_rows(entries, compiled: dict | None = None):
    """One row per workflow job (``provenance.run.job``: a module, or one scene of a
    module; the module for results written before scenes): its artefacts, the job's
    wall time (one run makes all its artefacts), the time numba spent compiling and in
    its JIT in all (cold numba cache: compile ~ JIT; warm: compile 0, JIT = cache
    loading).  ``compiled``: the workflow's `hpfebe compile` job
    (:func:`compile_record`), a row of its own.  Totals last."""
    jobs: dict[str, list] = {}
    for e in entries:
        if e.doc is not None and e.job:
            jobs.setdefault(e.job, []).append(e)
    rows, tot = [], [0.0, 0.0, 0.0]
    if compiled and jobs:
        vals = [compiled["wall_s"], compiled["jit_compile_s"], compiled["jit_s"]]
        rows.append(["numba kernels (hpfebe compile, its last run)", "-"]
                    + [_fmt_s(v) for v in vals])
        tot = vals
    for job in sorted(jobs):
        es = jobs[job]
        vals = [max((x for x in (f(e) for e in es) if x is not None), default=None)
                for f in (lambda e: e.wall_time, lambda e: e.compile_time,
                          lambda e: e.jit_time)]
        rows.append([job, ", ".join(e.name for e in es)] + [_fmt_s(v) for v in vals])
        tot = [t + (v or 0.0) for t, v in zip(tot, vals)]
    if rows:
        rows.append(["all jobs (sum)", f"{len(jobs)} jobs"] + [f"{t:.1f}" for t in tot])
    return rows


TIMING_INTRO = ("Per workflow job (a module, or one scene of a module: <module>__<scene>; "
                "one run makes all the job's artefacts): wall time of the run, the part "
                "numba spent compiling (new machine code: cold cache), and the time in "
                "numba's JIT in all (compiling plus loading compiled code from the "
                "on-disk cache). The sum is serial time; snakemake -j2 runs two jobs at "
                "once.")


def provenance_summary(entries) -> dict:
    docs = [e.doc for e in entries if e.doc]
    provs = [d.get("provenance") or {} for d in docs]
    commits = sorted({p.get("git_commit", "unknown") for p in provs})
    dirty = any(p.get("git_dirty") for p in provs)
    packages = {}
    for p in provs:
        for k, v in (p.get("packages") or {}).items():
            packages.setdefault(k, set()).add(v)
    dates = sorted(p.get("date_utc") for p in provs if p.get("date_utc"))
    commit_text = (", ".join(commits) + (" (uncommitted changes)" if dirty else "")
                   if commits else "-")
    return {
        "git commit(s) of the results": commit_text,
        "packages": ", ".join(f"{k} {'/'.join(sorted(v))}" for k, v in sorted(packages.items()))
        or "-",
        "python": ", ".join(sorted({p.get("python", "?") for p in provs})) or "-",
        "host cpu count": ", ".join(sorted({str(p.get("host_cpu_count")) for p in provs})) or "-",
        "results computed (UTC)": f"{dates[0]} ... {dates[-1]}" if dates else "-",
        "quick configuration": ", ".join(sorted({str(((p.get("run") or {}).get("quick")))
                                                 for p in provs})) or "-",
        "report built (UTC)": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }


INTRO = ("Every thesis artefact reproduced by this suite, beside the numbers the thesis "
         "prints (report/published/). Cells are judged by the tolerance each experiment "
         "declares; thesis claims are the thesis's statements, checked against the "
         "measured numbers. A cell outside its tolerance or a thesis claim that differs "
         "is explained only by an explanation claim linked to it that holds (our own "
         "computed test of a cause): 'differs (explained)' means every difference has "
         "one, 'differs (hypothesis)' that some have only a hypothesis (a reading or a "
         "numerical coincidence, not derived), 'differs (unexplained)' that some have "
         "neither. Explanations, hypotheses and results beyond the thesis are listed "
         "per artefact and not counted with the thesis's claims (one that fails is "
         "shown, but is no difference with the thesis, and explains nothing); a claim "
         "that could not be decided (e.g. over zero converged runs) is 'undecided'. A "
         "status reached under a particular reading of the thesis names it.")

STATUS_COUNTS_INTRO = ("Artefacts per status, per thesis chapter (from the artefact id, "
                       "or its module's for artefacts beyond the thesis) and in all; the "
                       "last column counts the thesis's claims only.")


# --------------------------------------------------------------------------- markup
#: inline code in notes and claims: ``x`` (RST), `x` (Markdown), :role:`x` (Sphinx)
CODE_RE = re.compile(r"(?::[A-Za-z][\w.-]*:)?(``|`)(?=\S)(.+?)(?<=\S)\1")


def claim_line(c: dict) -> tuple[str, str, str, str]:
    """(verdict, "[id] text", what it explains, evidence) of a claim (what it explains:
    for explanations and hypotheses, else "")."""
    head = f"[{c['id']}] " if c.get("id") else ""
    links = ""
    if claim_kind(c) in ("explanation", "hypothesis"):
        ex = claim_explains(c)
        links = f"explains: {', '.join(ex)}" if ex else "explains nothing named"
        if ex and c.get("holds") is not True:
            links += "; it does not hold, so it explains nothing"
    return (_verdict(c.get("holds")), head + str(c.get("text", "")), links,
            str(c.get("evidence") or ""))


CLAIM_SECTIONS = (("Thesis claims", ("thesis",)),
                   ("Explanations and hypotheses", ("explanation", "hypothesis")),
                   ("Beyond the thesis", ("beyond",)))


def _cell_class(status: str) -> str:
    return {"ok": "ok", "off": "off"}.get(status, "na")
