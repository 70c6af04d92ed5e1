"""The report's entries: one per artefact, with its result, published table, comparison
and status (:func:`collect`), and the notes that the artefacts of one module share.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from ..published import Comparison, compare, published_file_for, read_published
from ..results import DamagedResult, artefact_kind, check_result
from .status import (READING_KEY, STATUS_DAMAGED, STATUS_NOT_BUILT, STATUS_NOT_IMPL,
                     STATUS_PUB_MISSING, OffItem, claim_kind, judge)

__all__ = ["Entry", "collect", "chapter_of", "chapter_label"]


_ID_RE = re.compile(r"^(table|figure)_(\d+)_(\d+)")
_MODULE_CHAPTER_RE = re.compile(r"^ch(\d+)_")

#: a common opening of two artefacts' notes shorter than this is repeated, not shared
SHARED_NOTES_MIN = 200


@dataclass
class Entry:
    """One artefact in the report: its result (JSON document, table, figure), the
    published table and the comparison with it, its status and what is off."""

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


def chapter_label(ch: str) -> str:
    return f"chapter {ch}" if ch != "other" else "other (no thesis chapter)"


def _sort_key(name: str):
    m = _ID_RE.match(name)
    if m:
        return (0, int(m.group(2)), 0 if m.group(1) == "table" else 1, int(m.group(3)), name)
    return (1, 0, 0, 0, name)


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
                    e.published_table, e.published_caption = read_published(
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
                pub, e.published_caption = read_published(e.published_path)
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
