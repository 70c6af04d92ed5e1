"""The report: every reproduced number beside the published one.

Reads ``results/<artefact>.json/.csv/.png`` (written by :func:`hpfebe.results.write_result`)
and ``report/published/*.csv`` (the thesis's numbers; first line a ``#`` comment), and
writes

    report/index.html   self-contained (inline CSS, figures embedded as base64 PNG)
    report/report.md    the same content in Markdown (figures linked from results/)

Top: a summary (artefact, kind, status, cells within tolerance, claims holding /
differing, wall time), then a timing table: one line per module with its wall time,
numba compile time and JIT time (``provenance.run`` of the results, written by the
command line's :class:`hpfebe.cli.JitTimer`; older results show "-").  Per table artefact with a published file: published |
reproduced | difference | status for every column with a tolerance, joined on the
result's ``keys`` (rows on one side only are marked "not run" / "not published").
Per artefact: the figure, the thesis's claims with verdict and evidence, the notes, the
reproduced table.  Footer: provenance.  Missing results are marked "not built"; a
result whose files do not match what its JSON records (JSON not an object, truncated or
changed CSV, empty or changed PNG: :func:`hpfebe.results.check_result`) is marked
"damaged" with the mismatches, and none of its numbers or figures is used.

An edge module: no numerics beyond comparing numbers.
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import re
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import pandas as pd

from .results import DamagedResult, artefact_kind, atomic_write, check_result, \
    published_file_for

__all__ = ["build_report", "compare", "collect"]

_ID_RE = re.compile(r"^(table|figure)_(\d+)_(\d+)")

STATUS_MATCH = "matches"
STATUS_DIFF_EXPL = "differs (explained)"
STATUS_DIFF_UNEXPL = "differs (unexplained)"
STATUS_NO_PUB = "no published numbers"
STATUS_NOT_BUILT = "not built"
STATUS_NOT_IMPL = "not implemented"
STATUS_NO_OVERLAP = "no rows in common"
STATUS_PUB_MISSING = "published file missing"
STATUS_UNREADABLE = "unreadable result"
STATUS_DAMAGED = "damaged"


# --------------------------------------------------------------------------- data
@dataclass
class Comparison:
    keys: list[str]
    columns: list[str]                   # value columns compared
    tolerances: dict[str, tuple[str, float]]
    rows: list[dict] = field(default_factory=list)  # key values, per column cells
    n_ok: int = 0
    n_off: int = 0
    n_not_run: int = 0                   # published rows without a reproduced row
    n_not_published: int = 0             # reproduced rows without a published row


@dataclass
class Entry:
    name: str
    kind: str
    module: str | None
    status: str
    doc: dict | None = None
    table: pd.DataFrame | None = None
    png: Path | None = None
    published_path: Path | None = None
    published_caption: str = ""
    published_table: pd.DataFrame | None = None
    comparison: Comparison | None = None
    error: str = ""

    @property
    def claims(self) -> list[dict]:
        return (self.doc or {}).get("claims", [])

    @property
    def wall_time(self) -> float | None:
        if not self.doc:
            return None
        t = ((self.doc.get("provenance") or {}).get("run") or {}).get("module_wall_time_s")
        if t is None:
            t = (self.doc.get("meta") or {}).get("run_s")
        try:
            return float(t)
        except (TypeError, ValueError):
            return None

    def _run_number(self, key: str, meta_key: str | None = None) -> float | None:
        if not self.doc:
            return None
        t = ((self.doc.get("provenance") or {}).get("run") or {}).get(key)
        if t is None and meta_key:
            t = (self.doc.get("meta") or {}).get(meta_key)
        try:
            return float(t)
        except (TypeError, ValueError):
            return None

    @property
    def compile_time(self) -> float | None:
        """Seconds the module's run spent compiling numba code (None: not recorded)."""
        return self._run_number("jit_compile_s", "jit_s")

    @property
    def jit_time(self) -> float | None:
        """Seconds in numba's JIT in all (compiling and loading from its cache)."""
        return self._run_number("jit_s")

    @property
    def quick(self) -> bool | None:
        if not self.doc:
            return None
        return ((self.doc.get("provenance") or {}).get("run") or {}).get("quick")


def _sort_key(name: str):
    m = _ID_RE.match(name)
    if m:
        return (0, int(m.group(2)), 0 if m.group(1) == "table" else 1, int(m.group(3)), name)
    return (1, 0, 0, 0, name)


# --------------------------------------------------------------------------- comparing
def _num(x):
    """float of a cell, or None if empty / not a number."""
    if x is None:
        return None
    if isinstance(x, str):
        x = x.strip()
        if x in ("", "-", "nan", "NaN"):
            return None
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(v) else v


def _key_value(x):
    """Join-key normal form: numbers compared to 12 significant digits, else text."""
    v = _num(x)
    if v is not None:
        return float(f"{v:.12g}")
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return ""
    return str(x).strip()


def _cell_status(pub, rep, tol) -> tuple[str, float | None, float | None]:
    """(status, difference rep - pub, ratio rep/pub) of one compared value."""
    p, r = _num(pub), _num(rep)
    if p is None and r is None:
        return "ok", None, None          # both empty (e.g. first rate, no convergence)
    if p is None or r is None:
        return "off", None, None
    diff = r - p
    ratio = r / p if p != 0 else (1.0 if r == 0 else math.inf)
    kind, value = tol
    slack = 1e-9  # a tolerance met exactly must not fail on the last bit
    if kind == "abs":
        ok = abs(diff) <= value * (1 + slack) + 1e-300
    else:
        ok = (p == 0 and r == 0) or (
            ratio > 0 and 1.0 / (value * (1 + slack)) <= ratio <= value * (1 + slack))
    return ("ok" if ok else "off"), diff, ratio


def compare(published: pd.DataFrame, reproduced: pd.DataFrame, keys, tolerances) -> Comparison:
    """Join ``reproduced`` with ``published`` on ``keys`` (outer join) and judge every
    column in ``tolerances``."""
    keys = list(keys)
    tolerances = {k: (v[0], float(v[1])) for k, v in tolerances.items()}
    cols = [c for c in tolerances]
    for df, side in ((published, "published"), (reproduced, "reproduced")):
        missing = [c for c in keys + cols if c not in df.columns]
        if missing:
            raise ValueError(f"{side} table lacks columns {missing}")
    cmp = Comparison(keys=keys, columns=cols, tolerances=tolerances)

    def index(df):
        out = {}
        for i, row in df.iterrows():
            k = tuple(_key_value(row[c]) for c in keys)
            out.setdefault(k, row)  # duplicates: first row wins
        return out

    pub, rep = index(published), index(reproduced)
    order = list(pub) + [k for k in rep if k not in pub]
    for k in order:
        prow, rrow = pub.get(k), rep.get(k)
        src = prow if prow is not None else rrow
        row = {"key": {c: src[c] for c in keys}, "cells": {}}
        if prow is None:
            row["presence"] = "not published"
            cmp.n_not_published += 1
        elif rrow is None:
            row["presence"] = "not run"
            cmp.n_not_run += 1
        else:
            row["presence"] = "both"
        for c in cols:
            pv = None if prow is None else prow[c]
            rv = None if rrow is None else rrow[c]
            if row["presence"] != "both":
                row["cells"][c] = dict(pub=pv, rep=rv, diff=None, ratio=None,
                                       status=row["presence"])
                continue
            st, diff, ratio = _cell_status(pv, rv, tolerances[c])
            cmp.n_ok += st == "ok"
            cmp.n_off += st == "off"
            row["cells"][c] = dict(pub=pv, rep=rv, diff=diff, ratio=ratio, status=st)
        cmp.rows.append(row)
    return cmp


def _read_published(path: Path) -> tuple[pd.DataFrame, str]:
    caption = ""
    with open(path, encoding="utf-8") as f:
        first = f.readline()
    if first.startswith("#"):
        caption = first.lstrip("#").strip()
    return pd.read_csv(path, comment="#"), caption


# --------------------------------------------------------------------------- collecting
def _judge(entry: Entry) -> str:
    doc = entry.doc or {}
    claims = entry.claims
    failed = [c for c in claims if c.get("holds") is False]
    notes = (doc.get("notes") or "").strip()
    cmp = entry.comparison
    off = cmp.n_off if cmp else 0
    explained = all((c.get("evidence") or "").strip() for c in failed) and (off == 0 or notes)
    if off or failed:
        return STATUS_DIFF_EXPL if explained else STATUS_DIFF_UNEXPL
    if cmp is not None:
        if cmp.n_ok == 0:
            return STATUS_NO_OVERLAP
        return STATUS_MATCH
    return STATUS_NO_PUB


def collect(results_dir: Path, published_dir: Path,
            expected: dict[str, str] | None = None) -> list[Entry]:
    """One entry per artefact: expected (from the registry), found in ``results_dir``,
    or implied by a published file."""
    results_dir, published_dir = Path(results_dir), Path(published_dir)
    expected = dict(expected or {})
    names = set(expected)
    if results_dir.is_dir():
        names |= {p.stem for p in results_dir.glob("*.json")}
    pub_only = set()
    if published_dir.is_dir():
        for p in published_dir.glob("*.csv"):
            m = _ID_RE.match(p.stem)
            if m and m.group(0) not in names:
                pub_only.add(m.group(0))
    names |= pub_only

    entries = []
    for name in sorted(names, key=_sort_key):
        kind = artefact_kind(name)
        module = expected.get(name)
        js, csv = (results_dir / f"{name}.{e}" for e in ("json", "csv"))
        checked, damage = None, ""
        if js.is_file():
            try:
                checked = check_result(results_dir, name)
            except DamagedResult as exc:
                damage = "; ".join(exc.problems)
            except Exception as exc:  # noqa: BLE001 - shown in the report
                damage = f"cannot be read: {exc}"
        if checked is None:
            if damage:
                status = STATUS_DAMAGED
            else:
                status = STATUS_NOT_BUILT if (module or js.exists() or csv.exists()) else (
                    STATUS_NOT_IMPL if name in pub_only else STATUS_NOT_BUILT)
            e = Entry(name, kind, module, status,
                      error=f"damaged result, not used: {damage}. Rerun its module "
                            "(snakemake reruns it once the damaged files are deleted)"
                      if damage else "")
            e.published_path = published_file_for(name, published_dir)
            if e.published_path:
                try:
                    e.published_table, e.published_caption = _read_published(
                        e.published_path)
                except Exception:  # noqa: BLE001 - a caption is not worth failing for
                    pass
            entries.append(e)
            continue
        doc, table, png = checked
        run = doc.get("provenance") if isinstance(doc.get("provenance"), dict) else {}
        module = module or (run.get("run") or {}).get("module")
        e = Entry(name, kind, module, "", doc=doc, table=table, png=png)
        pub_name = doc.get("published")
        if pub_name:
            e.published_path = published_dir / pub_name
            if not e.published_path.is_file():
                e.status = STATUS_PUB_MISSING
                e.error = f"{pub_name} not found in {published_dir}"
                entries.append(e)
                continue
            try:
                pub, e.published_caption = _read_published(e.published_path)
                if doc.get("tolerances"):
                    e.comparison = compare(pub, table, doc.get("keys") or [],
                                           doc["tolerances"])
            except Exception as exc:  # noqa: BLE001 - shown in the report
                e.error = f"comparison failed: {exc}"
        e.status = _judge(e)
        if e.error and e.status == STATUS_MATCH:
            e.status = STATUS_DIFF_UNEXPL
        entries.append(e)
    return entries


# --------------------------------------------------------------------------- formatting
def _fmt(x, digits=6) -> str:
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


def _fmt_diff(cell, tol) -> str:
    if cell["diff"] is None:
        return ""
    s = "0" if cell["diff"] == 0 else f"{cell['diff']:+.3g}"
    if tol[0] == "factor" and cell["ratio"] is not None and math.isfinite(cell["ratio"]):
        s += f" (x{cell['ratio']:.3g})"
    return s


def _fmt_tol(tol) -> str:
    return f"ratio within x{tol[1]:g}" if tol[0] == "factor" else f"|diff| <= {tol[1]:g}"


def _claims_counts(e: Entry) -> str:
    if not e.doc:
        return ""
    c = e.claims
    if not c:
        return "-"
    hold = sum(x.get("holds") is True for x in c)
    diff = sum(x.get("holds") is False for x in c)
    und = len(c) - hold - diff
    return f"{hold} / {diff}" + (f" (+{und} undecided)" if und else "")


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
    return {True: "holds", False: "differs", None: "not decidable"}.get(holds, str(holds))


def _summary_rows(entries):
    rows = []
    for e in entries:
        t = e.wall_time
        rows.append([e.name, e.kind, e.module or "-", e.status, _cells_counts(e),
                     _claims_counts(e), "" if t is None else f"{t:.1f}"])
    return rows


SUMMARY_HEADER = ["artefact", "kind", "module", "status", "cells (tolerance)",
                  "claims hold / differ", "module wall time [s]"]


def _comparison_table(cmp: Comparison):
    header = list(cmp.keys)
    for c in cmp.columns:
        header += [f"{c} published", f"{c} reproduced", f"{c} difference", f"{c} status"]
    rows = []
    for r in cmp.rows:
        row = [_fmt(r["key"][k]) for k in cmp.keys]
        for c in cmp.columns:
            cell = r["cells"][c]
            row += [_fmt(cell["pub"]), _fmt(cell["rep"]), _fmt_diff(cell, cmp.tolerances[c]),
                    cell["status"]]
        rows.append(row)
    return header, rows


TIMING_HEADER = ["module", "artefacts", "run time [s]", "numba compile [s]",
                 "numba JIT incl. cache loads [s]"]


def _fmt_s(t) -> str:
    return "-" if t is None else f"{t:.1f}"


def _compile_record(results_dir: Path) -> dict | None:
    """The workflow's `hpfebe compile` record (results/logs/numba_cache.json), if any."""
    try:
        rec = json.loads((Path(results_dir) / "logs" / "numba_cache.json").read_text())
        return {k: float(rec[k]) for k in ("wall_s", "jit_compile_s", "jit_s")}
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _timing_rows(entries, compiled: dict | None = None):
    """One row per module: its artefacts, the module's wall time (one run makes all its
    artefacts), the time numba spent compiling and in its JIT in all (cold numba cache:
    compile ~ JIT; warm: compile 0, JIT = cache loading).  ``compiled``: the workflow's
    `hpfebe compile` job (:func:`_compile_record`), a row of its own.  Totals last."""
    mods: dict[str, list] = {}
    for e in entries:
        if e.doc is not None and e.module:
            mods.setdefault(e.module, []).append(e)
    rows, tot = [], [0.0, 0.0, 0.0]
    if compiled and mods:
        vals = [compiled["wall_s"], compiled["jit_compile_s"], compiled["jit_s"]]
        rows.append(["numba kernels (`hpfebe compile`, its last run)", "-"]
                    + [_fmt_s(v) for v in vals])
        tot = vals
    for mod in sorted(mods):
        es = mods[mod]
        vals = [max((x for x in (f(e) for e in es) if x is not None), default=None)
                for f in (lambda e: e.wall_time, lambda e: e.compile_time,
                          lambda e: e.jit_time)]
        rows.append([mod, ", ".join(e.name for e in es)] + [_fmt_s(v) for v in vals])
        tot = [t + (v or 0.0) for t, v in zip(tot, vals)]
    if rows:
        rows.append(["all modules (sum)", f"{len(mods)} modules"] + [f"{t:.1f}" for t in tot])
    return rows


TIMING_INTRO = ("Per module (one run makes all its artefacts): wall time of the run, the "
                "part numba spent compiling (new machine code: cold cache), and the time "
                "in numba's JIT in all (compiling plus loading compiled code from the "
                "on-disk cache). The sum is serial time; snakemake -j2 runs two modules "
                "at once.")


def _provenance_summary(entries) -> dict:
    docs = [e.doc for e in entries if e.doc]
    provs = [d.get("provenance") or {} for d in docs]
    commits = sorted({p.get("git_commit", "unknown") for p in provs})
    dirty = any(p.get("git_dirty") for p in provs)
    packages = {}
    for p in provs:
        for k, v in (p.get("packages") or {}).items():
            packages.setdefault(k, set()).add(v)
    dates = sorted(p.get("date_utc") for p in provs if p.get("date_utc"))
    return {
        "git commit(s) of the results": ", ".join(commits) + (" (uncommitted changes)"
                                                                  if dirty else "") if commits else "-",
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
         "declares; claims are the thesis's statements, checked against the measured "
         "numbers. 'differs (explained)' means the differences are explained in the "
         "artefact's notes and the claims' evidence.")


# --------------------------------------------------------------------------- Markdown
def _md_escape(s) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def _md_table(header, rows) -> str:
    out = ["| " + " | ".join(_md_escape(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_md_escape(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def _md_df(df: pd.DataFrame, max_rows=200) -> str:
    rows = [[_fmt(v) for v in r] for r in df.head(max_rows).itertuples(index=False)]
    s = _md_table([str(c) for c in df.columns], rows)
    if len(df) > max_rows:
        s += f"\n\n({len(df) - max_rows} more rows in the CSV file)"
    return s


def render_markdown(entries, out_dir: Path, results_dir: Path) -> str:
    L = ["# hpfebe: reproduction report", "", INTRO, ""]
    if any(e.quick for e in entries):
        L += ["> **Quick configuration**: sweeps are reduced (config/quick.yaml); rows "
              "marked 'not run' are expected.", ""]
    L += ["## Summary", "", _md_table(SUMMARY_HEADER, _summary_rows(entries)), ""]
    timing = _timing_rows(entries, _compile_record(results_dir))
    if timing:
        L += ["## Timing", "", TIMING_INTRO, "", _md_table(TIMING_HEADER, timing), ""]
    for e in entries:
        L += [f"## {e.name}", "", f"*{e.kind}* - module `{e.module or '-'}` - "
              f"status: **{e.status}**", ""]
        if e.published_caption:
            L += [f"Published: `{e.published_path.name}` - {e.published_caption}", ""]
        if e.error:
            L += [f"**Problem:** {e.error}", ""]
        if e.doc is None:
            if e.published_table is not None:
                L += ["Published numbers (nothing reproduced yet):", "",
                      _md_df(e.published_table), ""]
            continue
        if e.comparison is not None:
            cmp = e.comparison
            tols = "; ".join(f"{c}: {_fmt_tol(cmp.tolerances[c])}" for c in cmp.columns)
            L += ["### Published vs reproduced", "", f"Tolerances: {tols}.", "",
                  _md_table(*_comparison_table(cmp)), ""]
        if e.png is not None:
            rel = os.path.relpath(e.png, out_dir)
            L += [f"![{e.name}]({Path(rel).as_posix()})", ""]
        if e.claims:
            L += ["### Claims", ""]
            for c in e.claims:
                L += [f"- **{_verdict(c.get('holds'))}**: {c.get('text', '')}"
                      + (f" - {c['evidence']}" if c.get("evidence") else "")]
            L += [""]
        notes = (e.doc.get("notes") or "").strip()
        if notes:
            L += ["### Notes", "", notes, ""]
        if e.table is not None:
            L += ["### Reproduced table", "", _md_df(e.table), ""]
    L += ["## Provenance", ""]
    L += [f"- {k}: {v}" for k, v in _provenance_summary(entries).items()]
    return "\n".join(L) + "\n"


# --------------------------------------------------------------------------- HTML
CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;
max-width:1200px;padding:0 1em;color:#222;line-height:1.45}
h1{border-bottom:2px solid #444}h2{border-bottom:1px solid #bbb;margin-top:2em}
table{border-collapse:collapse;margin:.6em 0;font-size:.85em}
th,td{border:1px solid #ccc;padding:.25em .5em;text-align:right;vertical-align:top}
th{background:#f0f0f0}td.l,th.l{text-align:left}
.ok{background:#e3f5e1}.off{background:#fbe0de}.na{background:#f2f2f2;color:#777}
.st-match{color:#1b6e20;font-weight:600}.st-diff{color:#a0361f;font-weight:600}
.st-none{color:#666}.banner{background:#fff6d5;border:1px solid #e0c050;padding:.5em 1em}
img{max-width:100%;border:1px solid #ddd}details{margin:.5em 0}
.claim-holds{color:#1b6e20}.claim-differs{color:#a0361f}.claim-undecided{color:#666}
footer{margin-top:3em;font-size:.85em;color:#444;border-top:1px solid #bbb}
.scroll{overflow-x:auto}
"""


def _e(s) -> str:
    return html.escape(str(s), quote=True)


def _status_class(status: str) -> str:
    if status == STATUS_MATCH:
        return "st-match"
    if status.startswith("differs") or status in (STATUS_PUB_MISSING, STATUS_UNREADABLE,
                                                  STATUS_DAMAGED):
        return "st-diff"
    return "st-none"


def _cell_class(status: str) -> str:
    return {"ok": "ok", "off": "off"}.get(status, "na")


def _html_table(header, rows, classes=None, left=0) -> str:
    out = ['<div class="scroll"><table><thead><tr>']
    out += [f'<th class="{"l" if i < left else ""}">{_e(h)}</th>' for i, h in enumerate(header)]
    out.append("</tr></thead><tbody>")
    for r_i, r in enumerate(rows):
        out.append("<tr>")
        for i, c in enumerate(r):
            cls = []
            if i < left:
                cls.append("l")
            if classes and classes[r_i] and classes[r_i][i]:
                cls.append(classes[r_i][i])
            out.append(f'<td class="{" ".join(cls)}">{_e(c)}</td>')
        out.append("</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def render_html(entries, results_dir: Path | None = None) -> str:
    H = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
         "<meta name='viewport' content='width=device-width,initial-scale=1'>",
         "<title>hpfebe: reproduction report</title>", f"<style>{CSS}</style></head><body>",
         "<h1>hpfebe: reproduction report</h1>", f"<p>{_e(INTRO)}</p>"]
    if any(e.quick for e in entries):
        H.append("<p class='banner'><b>Quick configuration</b>: sweeps are reduced "
                 "(config/quick.yaml); rows marked 'not run' are expected.</p>")
    H.append("<h2>Summary</h2>")
    rows = _summary_rows(entries)
    classes = [[None, None, None, _status_class(r[3]), None, None, None] for r in rows]
    # artefact names link to their sections
    tbl = _html_table(SUMMARY_HEADER, rows, classes, left=4)
    for e in entries:
        tbl = tbl.replace(f'<td class="l">{_e(e.name)}</td>',
                          f'<td class="l"><a href="#{_e(e.name)}">{_e(e.name)}</a></td>', 1)
    H.append(tbl)
    timing = _timing_rows(entries, results_dir and _compile_record(results_dir))
    if timing:
        H += ["<h2 id='timing'>Timing</h2>", f"<p>{_e(TIMING_INTRO)}</p>",
              _html_table(TIMING_HEADER, timing, left=2)]

    for e in entries:
        H.append(f"<h2 id='{_e(e.name)}'>{_e(e.name)}</h2>")
        H.append(f"<p><i>{_e(e.kind)}</i> - module <code>{_e(e.module or '-')}</code> - "
                 f"status: <span class='{_status_class(e.status)}'>{_e(e.status)}</span></p>")
        if e.published_caption:
            H.append(f"<p>Published: <code>{_e(e.published_path.name)}</code> - "
                     f"{_e(e.published_caption)}</p>")
        if e.error:
            H.append(f"<p class='st-diff'>Problem: {_e(e.error)}</p>")
        if e.doc is None:
            if e.published_table is not None:
                df = e.published_table
                rows = [[_fmt(v) for v in r] for r in df.itertuples(index=False)]
                H.append(f"<details><summary>Published numbers ({len(df)} rows, nothing "
                         "reproduced yet)</summary>"
                         + _html_table([str(c) for c in df.columns], rows) + "</details>")
            continue
        if e.comparison is not None:
            cmp = e.comparison
            tols = "; ".join(f"{c}: {_fmt_tol(cmp.tolerances[c])}" for c in cmp.columns)
            header, rows = _comparison_table(cmp)
            nk = len(cmp.keys)
            classes = []
            for r in cmp.rows:
                cl = [None] * nk
                for c in cmp.columns:
                    k = _cell_class(r["cells"][c]["status"])
                    cl += [None, None, None, k]
                classes.append(cl)
            H.append(f"<h3>Published vs reproduced</h3><p>Tolerances: {_e(tols)}.</p>")
            H.append(_html_table(header, rows, classes, left=nk))
        if e.png is not None:
            data = base64.b64encode(e.png.read_bytes()).decode("ascii")
            H.append(f"<p><img alt='{_e(e.name)}' src='data:image/png;base64,{data}'></p>")
        if e.claims:
            H.append("<h3>Claims</h3><ul>")
            for c in e.claims:
                v = _verdict(c.get("holds"))
                cls = {"holds": "claim-holds", "differs": "claim-differs"}.get(
                    v, "claim-undecided")
                ev = f" - {_e(c['evidence'])}" if c.get("evidence") else ""
                H.append(f"<li><b class='{cls}'>{_e(v)}</b>: {_e(c.get('text', ''))}{ev}</li>")
            H.append("</ul>")
        notes = (e.doc.get("notes") or "").strip()
        if notes:
            H.append("<h3>Notes</h3>" + "".join(f"<p>{_e(p)}</p>" for p in notes.split("\n\n")))
        if e.table is not None:
            df = e.table
            rows = [[_fmt(v) for v in r] for r in df.itertuples(index=False)]
            H.append(f"<details><summary>Reproduced table ({len(df)} rows)</summary>"
                     + _html_table([str(c) for c in df.columns], rows) + "</details>")
        meta = e.doc.get("meta") or {}
        if meta:
            H.append("<details><summary>meta</summary><pre>"
                     + _e(json.dumps(meta, indent=1)) + "</pre></details>")
    H.append("<footer><h2>Provenance</h2><ul>")
    H += [f"<li>{_e(k)}: {_e(v)}</li>" for k, v in _provenance_summary(entries).items()]
    H.append("</ul></footer></body></html>")
    return "\n".join(H) + "\n"


# --------------------------------------------------------------------------- entry point
def build_report(results_dir: Path | str, out_dir: Path | str,
                 published_dir: Path | str, expected: dict[str, str] | None = None
                 ) -> list[Path]:
    """Write ``out_dir/index.html`` and ``out_dir/report.md``; ``expected`` maps the
    artefacts that should exist to their modules (missing ones are "not built")."""
    results_dir, out_dir, published_dir = Path(results_dir), Path(out_dir), Path(published_dir)
    entries = collect(results_dir, published_dir, expected)
    md = render_markdown(entries, out_dir, results_dir)
    page = render_html(entries, results_dir)
    return [atomic_write(out_dir / "index.html", lambda f: f.write(page)),
            atomic_write(out_dir / "report.md", lambda f: f.write(md))]
