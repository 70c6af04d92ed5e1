"""The report: every reproduced number beside the published one.

Reads ``results/<artefact>.json/.csv/.png`` (written by :func:`hpfebe.suite.results.write_result`)
and ``report/published/*.csv`` (the thesis's numbers; first line a ``#`` comment), and
writes

    report/index.html   self-contained (inline CSS, figures embedded as base64 PNG,
                        re-encoded to at most MAX_FIGURE_WIDTH pixels and 256 colours)
    report/report.md    the same content in Markdown (figures linked from results/)

Top: the counts of artefacts per status, in all and per chapter (with the thesis
claims holding / differing / undecided); a summary (artefact, kind, module, status,
cells within tolerance, thesis claims, the other claims by kind, wall time); a timing
table: one line per workflow job (a module, or one scene of it: ``provenance.run.job``;
the module for older results) with its wall time, numba compile time and JIT time
(written by the command line's :class:`hpfebe.cli.JitTimer`; older results show "-").
Per table artefact with a published file: published | reproduced | difference | status
for every column with a tolerance, joined on the result's ``keys`` (rows on one side
only are marked "not run" / "not published"), and published | reproduced for the
columns both tables have that are not judged (e.g. Table 4.3's Newton iterations).
Per artefact: what differs and what explains it, the figure, the claims by kind with
verdict and evidence, the notes (the opening a module's artefacts share is shown once,
at its first artefact; the others link to it), the reproduced table.  Footer:
provenance.

Status of an artefact (:func:`judge`).  The *off items* are the cells outside their
tolerance and the thesis claims that fail (``holds`` False; a claim with ``holds``
None is undecided, neither holding nor differing).  An ``explanation`` or
``hypothesis`` claim links to off items through ``Claim.explains`` (claim ids, or
``cells:*``, ``cells:<column>``, ``cells:<column>[key=value,...]``); a link counts only
if that claim holds (an explanation that fails, or is undecided, explains nothing).
Each off item's best link is an explanation that holds, else a hypothesis that holds,
else none:

    matches                no off item (and some cell compared within tolerance)
    differs (explained)    every off item's best link is an explanation that holds
    differs (hypothesis)   every off item is linked, some only by a hypothesis
    differs (unexplained)  some off item has no link that holds
    no published numbers   no off item and no table compared (figures: their claims
                           are listed and counted)

``beyond`` claims and failed explanations / hypotheses never make an artefact differ
from the thesis: they are listed (and counted per kind), not compared with it.  An
artefact whose result carries ``meta["reading"]`` (:data:`READING_KEY`: the reading of
the thesis under which the numbers are compared, e.g. Table 4.3's two-pass contact) has
it shown beside its status.  Missing results are "not built"; a published table without
any experiment is "not implemented"; a result whose files do not match what its JSON
records (:func:`hpfebe.suite.results.check_result`) is "damaged" with the mismatches, and none
of its numbers or figures is used.  Results written before claims had kinds count as
``thesis`` claims with no links.

An edge module: no numerics beyond comparing numbers.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import os
import re
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import pandas as pd

from .results import CELLS_PREFIX, CLAIM_KINDS, DamagedResult, artefact_kind, \
    atomic_write, check_result, published_file_for

__all__ = ["build_report", "compare", "collect", "judge", "READING_KEY"]

_ID_RE = re.compile(r"^(table|figure)_(\d+)_(\d+)")
_MODULE_CHAPTER_RE = re.compile(r"^ch(\d+)_")

STATUS_MATCH = "matches"
STATUS_DIFF_EXPL = "differs (explained)"
STATUS_DIFF_HYP = "differs (hypothesis)"
STATUS_DIFF_UNEXPL = "differs (unexplained)"
STATUS_NO_PUB = "no published numbers"
STATUS_NOT_BUILT = "not built"
STATUS_NOT_IMPL = "not implemented"
STATUS_NO_OVERLAP = "no rows in common"
STATUS_PUB_MISSING = "published file missing"
STATUS_UNREADABLE = "unreadable result"
STATUS_DAMAGED = "damaged"

#: the order of the status counts; the first five are always shown
STATUS_ORDER = (STATUS_MATCH, STATUS_DIFF_EXPL, STATUS_DIFF_HYP, STATUS_DIFF_UNEXPL,
                STATUS_NO_PUB, STATUS_NO_OVERLAP, STATUS_PUB_MISSING, STATUS_UNREADABLE,
                STATUS_DAMAGED, STATUS_NOT_BUILT, STATUS_NOT_IMPL)
_ALWAYS_COUNTED = STATUS_ORDER[:5]

#: result meta key: the reading of the thesis under which the artefact is compared
#: (a short phrase, e.g. "two-pass penalty contact (Section 4.4)"), shown with its status
READING_KEY = "reading"

#: link strength of an off item: an explanation that holds, a hypothesis that holds, none
LINK_EXPLANATION, LINK_HYPOTHESIS, LINK_NONE = 2, 1, 0
_LEVEL_STATUS = {LINK_EXPLANATION: STATUS_DIFF_EXPL, LINK_HYPOTHESIS: STATUS_DIFF_HYP,
                 LINK_NONE: STATUS_DIFF_UNEXPL}

#: claim kinds listed apart from the thesis's claims, with their labels
OTHER_KINDS = {"explanation": ("explanation", "explanations"),
               "hypothesis": ("hypothesis", "hypotheses"),
               "beyond": ("beyond the thesis", "beyond the thesis")}

#: a common opening of two artefacts' notes shorter than this is repeated, not shared
SHARED_NOTES_MIN = 200

#: figures are embedded at most this wide (pixels; the page is narrower)
MAX_FIGURE_WIDTH = 1400

#: rows of a reproduced table shown (the rest are in its CSV file)
MAX_TABLE_ROWS = 200


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
    shown: list[str] = field(default_factory=list)  # columns shown side by side, not judged


@dataclass
class OffItem:
    """A cell outside its tolerance or a thesis claim that fails, with its best link."""

    what: str                            # "cell" or "claim"
    column: str = ""                     # cell: its column
    key: dict = field(default_factory=dict)      # cell: its row's key values
    claim: dict | None = None            # claim: the claim
    level: int = LINK_NONE               # best link that holds (LINK_*)
    by: list[str] = field(default_factory=list)  # the claims linking it at ``level``
    dead: list[str] = field(default_factory=list)  # linked by claims that do not hold


def claim_kind(c: dict) -> str:
    """A claim's kind; missing (results written before kinds) or unknown: "thesis"."""
    k = c.get("kind") or "thesis"
    return k if k in CLAIM_KINDS else "thesis"


def _explains(c: dict) -> tuple[str, ...]:
    x = c.get("explains") or ()
    if isinstance(x, str):
        x = (x,)
    return tuple(str(v) for v in x if v)


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
    off_items: list[OffItem] = field(default_factory=list)
    link_problems: list[str] = field(default_factory=list)
    # notes: the opening shared with other artefacts of the module (shown here if this
    # is its first artefact), the artefact that shows it otherwise, and the rest
    notes_shared: str = ""
    notes_sharers: list[str] = field(default_factory=list)
    notes_home: str | None = None
    notes_own: str = ""

    @property
    def claims(self) -> list[dict]:
        return [c for c in (self.doc or {}).get("claims", []) if isinstance(c, dict)]

    def claims_of(self, *kinds: str) -> list[dict]:
        return [c for c in self.claims if claim_kind(c) in kinds]

    @property
    def run(self) -> dict:
        run = ((self.doc or {}).get("provenance") or {}).get("run")
        return run if isinstance(run, dict) else {}

    @property
    def job(self) -> str | None:
        """The workflow job that made it: ``<module>__<scene>``, or the module."""
        return self.run.get("job") or self.module

    @property
    def reading(self) -> str:
        r = ((self.doc or {}).get("meta") or {}).get(READING_KEY)
        return "" if r is None else str(r).strip()

    @property
    def status_text(self) -> str:
        return self.status + (f" - reading: {self.reading}" if self.reading else "")

    @property
    def chapter(self) -> str:
        return chapter_of(self.name, self.module)

    @property
    def wall_time(self) -> float | None:
        if not self.doc:
            return None
        t = self.run.get("module_wall_time_s")
        if t is None:
            t = (self.doc.get("meta") or {}).get("run_s")
        try:
            return float(t)
        except (TypeError, ValueError):
            return None

    def _run_number(self, key: str, meta_key: str | None = None) -> float | None:
        if not self.doc:
            return None
        t = self.run.get(key)
        if t is None and meta_key:
            t = (self.doc.get("meta") or {}).get(meta_key)
        try:
            return float(t)
        except (TypeError, ValueError):
            return None

    @property
    def compile_time(self) -> float | None:
        """Seconds the job's run spent compiling numba code (None: not recorded)."""
        return self._run_number("jit_compile_s", "jit_s")

    @property
    def jit_time(self) -> float | None:
        """Seconds in numba's JIT in all (compiling and loading from its cache)."""
        return self._run_number("jit_s")

    @property
    def quick(self) -> bool | None:
        if not self.doc:
            return None
        return self.run.get("quick")


def chapter_of(name: str, module: str | None) -> str:
    """The thesis chapter of an artefact: from its id (table_2_1 -> "2"), else from its
    module (ch4_mortar -> "4"), else "other" (e.g. bem_laplace, a demonstration of the
    pipeline that is no artefact of the thesis)."""
    m = _ID_RE.match(name)
    if m:
        return m.group(2)
    m = _MODULE_CHAPTER_RE.match(module or "")
    return m.group(1) if m else "other"


def _chapter_label(ch: str) -> str:
    return f"chapter {ch}" if ch != "other" else "other (no thesis chapter)"


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


def _diff_ratio(p, r) -> tuple[float, float]:
    return r - p, (r / p if p != 0 else (1.0 if r == 0 else math.inf))


def _cell_status(pub, rep, tol) -> tuple[str, float | None, float | None]:
    """(status, difference rep - pub, ratio rep/pub) of one compared value."""
    p, r = _num(pub), _num(rep)
    if p is None and r is None:
        return "ok", None, None          # both empty (e.g. first rate, no convergence)
    if p is None or r is None:
        return "off", None, None
    diff, ratio = _diff_ratio(p, r)
    kind, value = tol
    slack = 1e-9  # a tolerance met exactly must not fail on the last bit
    if kind == "abs":
        ok = abs(diff) <= value * (1 + slack) + 1e-300
    else:
        ok = (p == 0 and r == 0) or (
            ratio > 0 and 1.0 / (value * (1 + slack)) <= ratio <= value * (1 + slack))
    return ("ok" if ok else "off"), diff, ratio


def compare(published: pd.DataFrame, reproduced: pd.DataFrame, keys, tolerances,
            shown=()) -> Comparison:
    """Join ``reproduced`` with ``published`` on ``keys`` (outer join) and judge every
    column in ``tolerances``; the ``shown`` columns (in both tables) are put side by
    side without a verdict."""
    keys = list(keys)
    tolerances = {k: (v[0], float(v[1])) for k, v in tolerances.items()}
    cols = [c for c in tolerances]
    shown = [c for c in shown if c not in cols and c not in keys]
    for df, side in ((published, "published"), (reproduced, "reproduced")):
        missing = [c for c in keys + cols + shown if c not in df.columns]
        if missing:
            raise ValueError(f"{side} table lacks columns {missing}")
    cmp = Comparison(keys=keys, columns=cols, tolerances=tolerances, shown=shown)

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
        row = {"key": {c: src[c] for c in keys}, "cells": {}, "shown": {}}
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
        for c in shown:
            pv = None if prow is None else prow[c]
            rv = None if rrow is None else rrow[c]
            p, r = _num(pv), _num(rv)
            diff, ratio = _diff_ratio(p, r) if p is not None and r is not None else (
                None, None)
            row["shown"][c] = dict(pub=pv, rep=rv, diff=diff, ratio=ratio,
                                   status="not judged")
        cmp.rows.append(row)
    return cmp


def _read_published(path: Path) -> tuple[pd.DataFrame, str]:
    caption = ""
    with open(path, encoding="utf-8") as f:
        first = f.readline()
    if first.startswith("#"):
        caption = first.lstrip("#").strip()
    return pd.read_csv(path, comment="#"), caption


# --------------------------------------------------------------------------- judging
_CELLS_RE = re.compile(r"^([^\[\]]+?)\s*(?:\[([^\[\]]*)\])?$")


def _parse_cells(spec: str) -> tuple[str, dict[str, str]] | None:
    """``cells:<column>[key=value,...]`` -> (column, {key: value}); None if malformed."""
    m = _CELLS_RE.match(spec[len(CELLS_PREFIX):].strip())
    if not m:
        return None
    cond = {}
    for part in (m.group(2) or "").split(","):
        if not part.strip():
            continue
        k, sep, v = part.partition("=")
        if not sep or not k.strip():
            return None
        cond[k.strip()] = v.strip()
    return m.group(1).strip(), cond


def _claim_label(c: dict) -> str:
    if c.get("id"):
        return str(c["id"])
    t = str(c.get("text", ""))
    return f"'{t[:60]}...'" if len(t) > 60 else f"'{t}'"


def _link_level(c: dict) -> int:
    """What a link from claim ``c`` is worth: nothing unless ``c`` holds."""
    if c.get("holds") is not True:
        return LINK_NONE
    return {"explanation": LINK_EXPLANATION, "hypothesis": LINK_HYPOTHESIS}.get(
        claim_kind(c), LINK_NONE)


def _targets(spec: str, items: list[OffItem], cmp: Comparison | None, ids: set[str]
             ) -> tuple[list[OffItem], str]:
    """The off items an ``explains`` entry names, and what is wrong with it ("" if
    nothing: naming an item that is not off is fine)."""
    if spec.startswith(CELLS_PREFIX):
        parsed = _parse_cells(spec)
        if parsed is None:
            return [], f"cannot read {spec!r} (cells:<column>[key=value,...])"
        if cmp is None:
            return [], f"{spec!r} names cells, but no table is compared"
        col, cond = parsed
        if col != "*" and col not in cmp.columns:
            return [], f"{spec!r}: {col!r} is not a judged column {cmp.columns}"
        unknown = sorted(set(cond) - set(cmp.keys))
        if unknown:
            return [], f"{spec!r}: {unknown} are not key columns {cmp.keys}"
        want = {k: _key_value(v) for k, v in cond.items()}
        return [it for it in items if it.what == "cell" and col in ("*", it.column)
                and all(_key_value(it.key.get(k)) == v for k, v in want.items())], ""
    if spec not in ids:
        return [], f"{spec!r} is no claim id of this artefact"
    return [it for it in items if it.what == "claim" and it.claim.get("id") == spec], ""


def judge(entry: Entry) -> str:
    """The status of a built, readable result (the rules in the module docstring);
    sets ``entry.off_items`` (each with its best link) and ``entry.link_problems``."""
    cmp, claims = entry.comparison, entry.claims
    items = []
    if cmp is not None:
        items = [OffItem("cell", column=c, key=r["key"]) for r in cmp.rows
                 if r["presence"] == "both" for c in cmp.columns
                 if r["cells"][c]["status"] == "off"]
    items += [OffItem("claim", claim=c) for c in entry.claims_of("thesis")
              if c.get("holds") is False]
    ids = {str(c["id"]) for c in claims if c.get("id")}
    problems = []
    for c in entry.claims_of("explanation", "hypothesis"):
        level, label = _link_level(c), _claim_label(c)
        for spec in _explains(c):
            targets, problem = _targets(spec, items, cmp, ids)
            if problem:
                problems.append(f"{label}: {problem}")
            for it in targets:
                if level == LINK_NONE:
                    if label not in it.dead:
                        it.dead.append(label)
                elif level > it.level:
                    it.level, it.by = level, [label]
                elif level == it.level and label not in it.by:
                    it.by.append(label)
    entry.off_items, entry.link_problems = items, problems
    if items:
        return _LEVEL_STATUS[min(it.level for it in items)]
    if entry.error:
        return STATUS_DIFF_UNEXPL        # the comparison failed: nothing is known to match
    if cmp is not None:
        return STATUS_MATCH if cmp.n_ok else STATUS_NO_OVERLAP
    return STATUS_NO_PUB


# --------------------------------------------------------------------------- collecting
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
        e = Entry(name, kind, module, "", doc=doc, table=table, png=png)
        e.module = module or e.run.get("module")
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
                    keys = doc.get("keys") or []
                    shown = [c for c in pub.columns if c in table.columns
                             and c not in keys and c not in doc["tolerances"]]
                    e.comparison = compare(pub, table, keys, doc["tolerances"], shown)
            except Exception as exc:  # noqa: BLE001 - shown in the report
                e.error = f"comparison failed: {exc}"
        e.status = judge(e)
        entries.append(e)
    _share_notes(entries)
    return entries


def _common_opening(a: str, b: str) -> int:
    """Length of the common opening of two notes, ending at a sentence end (or where
    the shorter one ends)."""
    p = os.path.commonprefix([a, b])
    if len(p) in (len(a), len(b)):
        return len(p)
    i = p.rfind(". ")
    return i + 1 if i >= 0 else 0


def _share_notes(entries: list[Entry]) -> None:
    """Show the notes' opening that artefacts of one module share once: at the first of
    them (in report order); the others refer to it and show only the rest."""
    by_module: dict[str, list[Entry]] = {}
    for e in entries:
        e.notes_own = ((e.doc or {}).get("notes") or "").strip()
        if e.doc is not None and e.module and e.notes_own:
            by_module.setdefault(e.module, []).append(e)
    for es in by_module.values():
        for e in es:
            if e.notes_home or e.notes_shared:
                continue                 # already in a group
            full = e.notes_own
            group = [(f, _common_opening(full, f.notes_own)) for f in es
                     if f is not e and not (f.notes_home or f.notes_shared)]
            group = [(f, n) for f, n in group if n >= SHARED_NOTES_MIN]
            if not group:
                continue
            n = min(n for _, n in group)  # every member shares full[:n]
            e.notes_shared, e.notes_sharers = full[:n].strip(), [f.name for f, _ in group]
            for f in [e] + [f for f, _ in group]:
                f.notes_own = f.notes_own[n:].strip()
            for f, _ in group:
                f.notes_home = e.name


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


def _fmt_tol(tol) -> str:
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


def _summary_rows(entries):
    rows = []
    for e in entries:
        t = e.wall_time
        rows.append([e.name, e.kind, e.module or "-", e.status_text, _cells_counts(e),
                     _claims_counts(e), _others_counts(e), "" if t is None else f"{t:.1f}"])
    return rows


SUMMARY_HEADER = ["artefact", "kind", "module", "status", "cells (tolerance)",
                  "thesis claims hold / differ", "other claims (not counted)",
                  "job wall time [s]"]


def _status_counts(entries) -> tuple[list[str], list[list[str]]]:
    """Artefacts per status, per chapter and in all, with the thesis claims holding /
    differing / undecided."""
    chapters: dict[str, list[Entry]] = {}
    for e in entries:
        chapters.setdefault(e.chapter, []).append(e)
    order = sorted(chapters, key=lambda c: (c == "other", int(c) if c.isdigit() else 0, c))
    statuses = [s for s in STATUS_ORDER
                if s in _ALWAYS_COUNTED or any(e.status == s for e in entries)]
    header = ["chapter", "artefacts", *statuses, "thesis claims hold / differ / undecided"]

    def row(label, es):
        tc = [sum(t) for t in zip(*(_thesis_counts(e) for e in es))] or [0, 0, 0]
        return ([label, str(len(es))] + [str(sum(e.status == s for e in es))
                                         for s in statuses] + [" / ".join(map(str, tc))])
    rows = [row(_chapter_label(c), chapters[c]) for c in order]
    rows.append(row("all", list(entries)))
    return header, rows


def _key_label(key: dict) -> str:
    return ", ".join(f"{k}={_fmt(v)}" for k, v in key.items())


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


def _difference_lines(e: Entry, max_keys: int = 6) -> list[tuple[str, str, int]]:
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


def _comparison_groups(cmp: Comparison) -> list[tuple[str, list[str]]]:
    """Column groups of the side-by-side table: (group title, sub-column titles)."""
    groups = [(c, ["published", "reproduced", _diff_title(cmp.tolerances[c]), "status"])
              for c in cmp.columns]
    groups += [(f"{c} (not judged)", ["published", "reproduced", "ratio"])
               for c in cmp.shown]
    return groups


def _comparison_table(cmp: Comparison):
    """Flat header ("<column> published", ...), rows and per-cell classes."""
    header = list(cmp.keys)
    for title, subs in _comparison_groups(cmp):
        header += [f"{title.replace(' (not judged)', '')} {s}" for s in subs]
    rows, classes = [], []
    for r in cmp.rows:
        row = [_fmt(r["key"][k]) for k in cmp.keys]
        cl = [None] * len(cmp.keys)
        for c in cmp.columns:
            cell = r["cells"][c]
            row += [_fmt(cell["pub"]), _fmt(cell["rep"]), _fmt_diff(cell, cmp.tolerances[c]),
                    cell["status"]]
            cl += [None, None, None, _cell_class(cell["status"])]
        for c in cmp.shown:
            cell = r["shown"][c]
            row += [_fmt(cell["pub"]), _fmt(cell["rep"]), _fmt_diff(cell, ("factor", 0))]
            cl += ["na", "na", "na"]
        rows.append(row)
        classes.append(cl)
    return header, rows, classes


TIMING_HEADER = ["job", "artefacts", "run time [s]", "numba compile [s]",
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
    """One row per workflow job (``provenance.run.job``: a module, or one scene of a
    module; the module for results written before scenes): its artefacts, the job's
    wall time (one run makes all its artefacts), the time numba spent compiling and in
    its JIT in all (cold numba cache: compile ~ JIT; warm: compile 0, JIT = cache
    loading).  ``compiled``: the workflow's `hpfebe compile` job
    (:func:`_compile_record`), a row of its own.  Totals last."""
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
_CODE_RE = re.compile(r"(?::[A-Za-z][\w.-]*:)?(``|`)(?=\S)(.+?)(?<=\S)\1")


def _rich(s) -> str:
    """HTML of a text: escaped, inline code marked up as <code>, no stray backtick."""
    s, out, pos = str(s), [], 0
    for m in _CODE_RE.finditer(s):
        out += [_e(s[pos:m.start()]), f"<code>{_e(m.group(2))}</code>"]
        pos = m.end()
    out.append(_e(s[pos:]))
    return "".join(out).replace("`", "'")


def _md_text(s) -> str:
    """Markdown of a text: inline code as `x` (RST double backticks, roles dropped)."""
    return _CODE_RE.sub(lambda m: f"`{m.group(2)}`", str(s))


# --------------------------------------------------------------------------- Markdown
def _md_escape(s) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def _md_table(header, rows) -> str:
    out = ["| " + " | ".join(_md_escape(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_md_escape(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def _md_df(df: pd.DataFrame, max_rows=None) -> str:
    max_rows = MAX_TABLE_ROWS if max_rows is None else max_rows
    rows = [[_fmt(v) for v in r] for r in df.head(max_rows).itertuples(index=False)]
    s = _md_table([str(c) for c in df.columns], rows)
    if len(df) > max_rows:
        s += f"\n\n({len(df) - max_rows} more rows in the CSV file)"
    return s


def _claim_line(c: dict) -> tuple[str, str, str, str]:
    """(verdict, "[id] text", what it explains, evidence) of a claim (what it explains:
    for explanations and hypotheses, else "")."""
    head = f"[{c['id']}] " if c.get("id") else ""
    links = ""
    if claim_kind(c) in ("explanation", "hypothesis"):
        ex = _explains(c)
        links = f"explains: {', '.join(ex)}" if ex else "explains nothing named"
        if ex and c.get("holds") is not True:
            links += "; it does not hold, so it explains nothing"
    return (_verdict(c.get("holds")), head + str(c.get("text", "")), links,
            str(c.get("evidence") or ""))


_CLAIM_SECTIONS = (("Thesis claims", ("thesis",)),
                   ("Explanations and hypotheses", ("explanation", "hypothesis")),
                   ("Beyond the thesis", ("beyond",)))


def render_markdown(entries, out_dir: Path, results_dir: Path) -> str:
    L = ["# hpfebe: reproduction report", "", INTRO, ""]
    if any(e.quick for e in entries):
        L += ["> **Quick configuration**: sweeps are reduced (config/quick.yaml); rows "
              "marked 'not run' are expected.", ""]
    L += ["## Status counts", "", STATUS_COUNTS_INTRO, "",
          _md_table(*_status_counts(entries)), ""]
    L += ["## Summary", "", _md_table(SUMMARY_HEADER, _summary_rows(entries)), ""]
    timing = _timing_rows(entries, _compile_record(results_dir))
    if timing:
        L += ["## Timing", "", TIMING_INTRO, "", _md_table(TIMING_HEADER, timing), ""]
    for e in entries:
        job = f" - job `{e.job}`" if e.doc and e.job and e.job != e.module else ""
        L += [f"## {e.name}", "", f"*{e.kind}* - module `{e.module or '-'}`{job} - "
              f"status: **{e.status}**"
              + (f" - reading: *{_md_text(e.reading)}*" if e.reading else ""), ""]
        if e.published_caption:
            L += [f"Published: `{e.published_path.name}` - {e.published_caption}", ""]
        if e.error:
            L += [f"**Problem:** {_md_text(e.error)}", ""]
        if e.doc is None:
            if e.published_table is not None:
                L += ["Published numbers (nothing reproduced yet):", "",
                      _md_df(e.published_table), ""]
            continue
        diffs = _difference_lines(e)
        if diffs:
            L += ["### Differences and what explains them", ""]
            L += [f"- {_md_text(t)}: {_md_text(link)}" for t, link, _ in diffs] + [""]
        if e.comparison is not None:
            cmp = e.comparison
            tols = "; ".join(f"{c}: {_fmt_tol(cmp.tolerances[c])}" for c in cmp.columns)
            shown = (f" Not judged: {', '.join(cmp.shown)}." if cmp.shown else "")
            header, rows, _ = _comparison_table(cmp)
            L += ["### Published vs reproduced", "", f"Tolerances: {tols}.{shown}", "",
                  _md_table(header, rows), ""]
        if e.png is not None:
            rel = os.path.relpath(e.png, out_dir)
            L += [f"![{e.name}]({Path(rel).as_posix()})", ""]
        for title, kinds in _CLAIM_SECTIONS:
            cs = e.claims_of(*kinds)
            if not cs:
                continue
            L += [f"### {title}", ""]
            for c in cs:
                v, text, links, ev = _claim_line(c)
                label = f"{claim_kind(c)}, " if len(kinds) > 1 else ""
                L += [f"- **{label}{v}**: {_md_text(text)}"
                      + (f" ({_md_text(links)})" if links else "")
                      + (f" - {_md_text(ev)}" if ev else "")]
            L += [""]
        if e.notes_shared or e.notes_home or e.notes_own:
            L += ["### Notes", ""]
            if e.notes_shared:
                L += [f"*Shared with {', '.join(e.notes_sharers)} (module "
                      f"`{e.module}`):* {_md_text(e.notes_shared)}", ""]
            if e.notes_home:
                L += [f"*The notes this artefact shares with module `{e.module}`: see "
                      f"[{e.notes_home}](#{e.notes_home}).*", ""]
            if e.notes_own:
                L += [_md_text(e.notes_own), ""]
        if e.table is not None:
            L += ["### Reproduced table", "", _md_df(e.table), ""]
    L += ["## Provenance", ""]
    L += [f"- {k}: {v}" for k, v in _provenance_summary(entries).items()]
    return "\n".join(L) + "\n"


# --------------------------------------------------------------------------- HTML
CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;
max-width:1600px;padding:0 1em;color:#222;line-height:1.45}
h1{border-bottom:2px solid #444}h2{border-bottom:1px solid #bbb;margin-top:2em}
table{border-collapse:collapse;margin:.6em 0;font-size:.82em}
th,td{border:1px solid #ccc;padding:.2em .35em;text-align:right;vertical-align:top}
th{background:#f0f0f0}td.l,th.l{text-align:left}th.g{text-align:center}
td.w{text-align:left;min-width:10em}
.ok{background:#e3f5e1}.off{background:#fbe0de}.na{background:#f2f2f2;color:#555}
.st-match{color:#1b6e20;font-weight:600}.st-expl{color:#6b5a00;font-weight:600}
.st-hyp{color:#b35900;font-weight:600}.st-diff{color:#a0361f;font-weight:600}
.st-none{color:#666}.banner{background:#fff6d5;border:1px solid #e0c050;padding:.5em 1em}
img{max-width:100%;height:auto;border:1px solid #ddd}details{margin:.5em 0}
.claim-holds{color:#1b6e20}.claim-differs{color:#a0361f}.claim-undecided{color:#666}
.kind{font-size:.8em;border:1px solid #999;border-radius:3px;padding:0 .3em;color:#444}
footer{margin-top:3em;font-size:.85em;color:#444;border-top:1px solid #bbb}
.scroll{overflow-x:auto;max-width:100%}code{background:#f4f4f4;padding:0 .2em}
pre{white-space:pre-wrap;word-break:break-word}
.ev{color:#444;font-size:.9em;margin:.1em 0 .4em}.links{color:#6b5a00;font-style:italic}
"""


def _e(s) -> str:
    return html.escape(str(s), quote=True)


def _status_class(status: str) -> str:
    if status.startswith(STATUS_MATCH):
        return "st-match"
    if status.startswith(STATUS_DIFF_EXPL):
        return "st-expl"
    if status.startswith(STATUS_DIFF_HYP):
        return "st-hyp"
    if status.startswith("differs") or status in (STATUS_PUB_MISSING, STATUS_UNREADABLE,
                                                  STATUS_DAMAGED):
        return "st-diff"
    return "st-none"


_LEVEL_CLASS = {LINK_EXPLANATION: "st-expl", LINK_HYPOTHESIS: "st-hyp",
                LINK_NONE: "st-diff"}


def _cell_class(status: str) -> str:
    return {"ok": "ok", "off": "off"}.get(status, "na")


def _html_table(header, rows, classes=None, left=0, groups=None, cells=None) -> str:
    """A table in a horizontal scroll container.  ``groups``: a two-row header, the
    first ``left`` columns spanning both rows and (title, sub-titles) groups after
    them; ``cells``: HTML of cells (already escaped) instead of ``rows``' text."""
    out = ['<div class="scroll"><table><thead>']
    if groups:
        out.append("<tr>" + "".join(f'<th class="l" rowspan="2">{_e(h)}</th>'
                                    for h in header[:left]))
        out += [f'<th class="g" colspan="{len(subs)}">{_e(t)}</th>' for t, subs in groups]
        out.append("</tr><tr>" + "".join(f"<th>{_e(s)}</th>" for _, subs in groups
                                         for s in subs) + "</tr>")
    else:
        out.append("<tr>" + "".join(f'<th class="{"l" if i < left else ""}">{_e(h)}</th>'
                                    for i, h in enumerate(header)) + "</tr>")
    out.append("</thead><tbody>")
    for r_i, r in enumerate(rows):
        out.append("<tr>")
        for i, c in enumerate(r):
            cls = []
            if i < left:
                cls.append("l")
            if classes and classes[r_i] and classes[r_i][i]:
                cls.append(classes[r_i][i])
            text = cells[r_i][i] if cells and cells[r_i][i] is not None else _e(c)
            out.append(f'<td class="{" ".join(cls)}">{text}</td>')
        out.append("</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def _png_for_html(path: Path) -> bytes:
    """The figure's PNG for embedding: at most :data:`MAX_FIGURE_WIDTH` pixels wide and
    re-encoded with 256 colours (matplotlib's plots have few; ~half the bytes) when
    that is smaller; the file's bytes if Pillow cannot read it."""
    data = path.read_bytes()
    try:
        from PIL import Image

        with Image.open(io.BytesIO(data)) as im:
            im.load()
            rgba = im.convert("RGBA")
        img = Image.alpha_composite(Image.new("RGBA", rgba.size, "white"), rgba)
        img = img.convert("RGB")
        if img.width > MAX_FIGURE_WIDTH:
            img = img.resize((MAX_FIGURE_WIDTH,
                              max(1, round(img.height * MAX_FIGURE_WIDTH / img.width))),
                             Image.LANCZOS)
        buf = io.BytesIO()
        img.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
                     ).save(buf, "PNG", optimize=True)
    except Exception:  # noqa: BLE001 - the original is always a valid PNG to embed
        return data
    return buf.getvalue() if len(buf.getvalue()) < len(data) else data


def render_html(entries, results_dir: Path | None = None) -> str:
    H = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
         "<meta name='viewport' content='width=device-width,initial-scale=1'>",
         "<title>hpfebe: reproduction report</title>", f"<style>{CSS}</style></head><body>",
         "<h1>hpfebe: reproduction report</h1>", f"<p>{_e(INTRO)}</p>"]
    if any(e.quick for e in entries):
        H.append("<p class='banner'><b>Quick configuration</b>: sweeps are reduced "
                 "(config/quick.yaml); rows marked 'not run' are expected.</p>")
    header, rows = _status_counts(entries)
    H += ["<h2 id='status-counts'>Status counts</h2>", f"<p>{_e(STATUS_COUNTS_INTRO)}</p>",
          _html_table(header, rows, left=1)]
    H.append("<h2 id='summary'>Summary</h2>")
    rows = _summary_rows(entries)
    classes = [[None, None, None, _status_class(r[3]) + " w", None, None, "w", None]
               for r in rows]
    cells = [[f'<a href="#{_e(r[0])}">{_e(r[0])}</a>'] + [None] * (len(r) - 1)
             for r in rows]
    H.append(_html_table(SUMMARY_HEADER, rows, classes, left=4, cells=cells))
    timing = _timing_rows(entries, results_dir and _compile_record(results_dir))
    if timing:
        H += ["<h2 id='timing'>Timing</h2>", f"<p>{_e(TIMING_INTRO)}</p>",
              _html_table(TIMING_HEADER, timing, left=2)]

    for e in entries:
        H.append(f"<h2 id='{_e(e.name)}'>{_e(e.name)}</h2>")
        job = (f" - job <code>{_e(e.job)}</code>" if e.doc and e.job and e.job != e.module
               else "")
        reading = (f" - reading: <i>{_rich(e.reading)}</i>" if e.reading else "")
        H.append(f"<p><i>{_e(e.kind)}</i> - module <code>{_e(e.module or '-')}</code>{job}"
                 f" - status: <span class='{_status_class(e.status)}'>{_e(e.status)}"
                 f"</span>{reading}</p>")
        if e.published_caption:
            H.append(f"<p>Published: <code>{_e(e.published_path.name)}</code> - "
                     f"{_rich(e.published_caption)}</p>")
        if e.error:
            H.append(f"<p class='st-diff'>Problem: {_rich(e.error)}</p>")
        if e.doc is None:
            if e.published_table is not None:
                df = e.published_table
                rows = [[_fmt(v) for v in r] for r in df.itertuples(index=False)]
                H.append(f"<details><summary>Published numbers ({len(df)} rows, nothing "
                         "reproduced yet)</summary>"
                         + _html_table([str(c) for c in df.columns], rows) + "</details>")
            continue
        diffs = _difference_lines(e)
        if diffs:
            H.append("<h3>Differences and what explains them</h3><ul>")
            H += [f"<li>{_rich(t)}: <span class='{_LEVEL_CLASS[lv]}'>{_rich(link)}</span></li>"
                  for t, link, lv in diffs]
            H.append("</ul>")
        if e.comparison is not None:
            cmp = e.comparison
            tols = "; ".join(f"{c}: {_fmt_tol(cmp.tolerances[c])}" for c in cmp.columns)
            shown = (f" Shown beside, not judged: {', '.join(cmp.shown)}."
                     if cmp.shown else "")
            header, rows, classes = _comparison_table(cmp)
            H.append(f"<h3>Published vs reproduced</h3><p>Tolerances: {_e(tols)}."
                     f"{_e(shown)}</p>")
            H.append(_html_table(header, rows, classes, left=len(cmp.keys),
                                 groups=_comparison_groups(cmp)))
        if e.png is not None:
            data = base64.b64encode(_png_for_html(e.png)).decode("ascii")
            H.append(f"<p><img alt='{_e(e.name)}' src='data:image/png;base64,{data}'></p>")
        for title, kinds in _CLAIM_SECTIONS:
            cs = e.claims_of(*kinds)
            if not cs:
                continue
            H.append(f"<h3>{_e(title)}</h3><ul>")
            for c in cs:
                v, text, links, ev = _claim_line(c)
                cls = {"holds": "claim-holds", "differs": "claim-differs"}.get(
                    v, "claim-undecided")
                label = (f"<span class='kind'>{_e(claim_kind(c))}</span> "
                         if len(kinds) > 1 else "")
                H.append(f"<li>{label}<b class='{cls}'>{_e(v)}</b>: {_rich(text)}"
                         + (f" <span class='links'>({_rich(links)})</span>" if links else "")
                         + (f"<div class='ev'>{_rich(ev)}</div>" if ev else "") + "</li>")
            H.append("</ul>")
        if e.notes_shared or e.notes_home or e.notes_own:
            H.append("<h3>Notes</h3>")
            if e.notes_shared:
                links = ", ".join(f"<a href='#{_e(n)}'>{_e(n)}</a>" for n in e.notes_sharers)
                H.append(f"<p><i>Shared with {links} (module <code>{_e(e.module)}</code>):"
                         "</i></p>" + "".join(f"<p>{_rich(p)}</p>"
                                              for p in e.notes_shared.split("\n\n")))
            if e.notes_home:
                H.append(f"<p><i>The notes this artefact shares with module "
                         f"<code>{_e(e.module)}</code>: see <a href='#{_e(e.notes_home)}'>"
                         f"{_e(e.notes_home)}</a>.</i></p>")
            if e.notes_own:
                if e.notes_shared or e.notes_home:
                    H.append("<p><i>This artefact:</i></p>")
                H += [f"<p>{_rich(p)}</p>" for p in e.notes_own.split("\n\n")]
        if e.table is not None:
            df = e.table
            rows = [[_fmt(v) for v in r] for r in df.head(MAX_TABLE_ROWS).itertuples(
                index=False)]
            more = (f"<p>({len(df) - MAX_TABLE_ROWS} more rows in {_e(e.name)}.csv)</p>"
                    if len(df) > MAX_TABLE_ROWS else "")
            H.append(f"<details><summary>Reproduced table ({len(df)} rows)</summary>"
                     + _html_table([str(c) for c in df.columns], rows) + more
                     + "</details>")
        meta = e.doc.get("meta") or {}
        if meta:
            H.append("<details><summary>meta</summary><pre>"
                     + _e(json.dumps(meta, indent=1)).replace("`", "'")
                     + "</pre></details>")
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
