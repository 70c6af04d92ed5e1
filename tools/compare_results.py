#!/usr/bin/env python
"""Compare two results folders artefact by artefact.

    python tools/compare_results.py OLD_DIR NEW_DIR [--rtol 1e-9] [--atol 0]
                                    [--only ID ...] [--require-all]
                                    [--rename OLD_COL=NEW_COL ...]

An artefact is ``<id>`` with ``<id>.csv`` and/or ``<id>.json``.  Only artefacts present
in BOTH folders are compared; those present in only one are reported as information
(``--require-all`` makes an artefact missing from NEW_DIR a failure).  ``--only``
restricts the comparison to the given ids.

Tables (``<id>.csv``), for every column present in both:

* numeric columns agree if, entry by entry,

      |a - b| <= rtol * max(|a|, |b|) + 64 * eps * max|column| + atol

  where eps is the float64 machine epsilon and max|column| the largest finite magnitude
  of that column in either table: the floor accepts entries at round-off relative to
  the column (a residual history 1e-2 ... 1e-16 whose last entry becomes 3e-16) without
  loosening the relative test of the others.  A column that is round-off throughout
  (all entries ~1e-15) gets no such slack; ``--atol`` (default 0) adds an absolute one.
  NaN equals NaN, inf equals inf of the same sign;
* other columns (text, booleans, mixed) must be equal as text;
* timing and provenance columns are skipped: names ending in ``_s`` (seconds; the
  suffix is case-sensitive, ``norm_S`` is compared) or containing ``time``, ``wall``
  or ``jit``;
* rows are compared by position; a different number of rows, and columns present on
  one side only, are differences.  ``--rename lam=lambda_nit`` compares OLD's column
  ``lam`` with NEW's ``lambda_nit`` (a deliberate rename; reported as info).

Claims (the ``claims`` list of ``<id>.json``) are matched by their text: a claim whose
``holds`` changed, or that exists on one side only, is a difference (the evidence
strings are not compared; they quote the numbers that the table check covers).

The baseline runs pin NUMBA_NUM_THREADS = OMP_NUM_THREADS = OPENBLAS_NUM_THREADS =
MKL_NUM_THREADS = 1 (as the Snakefile does); a run with more threads changes the rounding
of BLAS and numba reductions, and near-round-off values (solver residuals, errors of
1e-10) then differ by far more than 1e-9 relative.  Run ``hpfebe run`` with the same
variables set; an artefact whose provenance ``threads_env`` differs gets a warning.

One line per artefact (``OK`` / ``DIFF`` / ``INFO``) with the details indented below;
the exit status is 1 if anything differs, 2 on bad arguments, else 0.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["main", "compare_dirs", "compare_tables", "compare_claims", "is_skipped_column",
           "ArtefactReport"]

EPS = float(np.finfo(float).eps)
ABS_FLOOR_EPS = 64.0
MAX_LISTED = 5  # differing rows listed per column


@dataclass
class ArtefactReport:
    """What the comparison of one artefact found."""

    name: str
    differences: list[str] = field(default_factory=list)
    info: list[str] = field(default_factory=list)
    compared: bool = True

    @property
    def ok(self) -> bool:
        return not self.differences

    def verdict(self) -> str:
        if not self.compared:
            return f"INFO {self.name}: " + "; ".join(self.info)
        if self.ok:
            extra = f" ({'; '.join(self.info)})" if self.info else ""
            return f"OK   {self.name}{extra}"
        return f"DIFF {self.name}: {len(self.differences)} difference(s)"


def is_skipped_column(name: str) -> bool:
    """Timing/provenance columns, not compared: names ending in ``_s`` (lower-case s:
    seconds; ``norm_S`` is a value) or containing ``time``, ``wall`` or ``jit`` (any
    case)."""
    n = str(name)
    low = n.lower()
    return n.endswith("_s") or "time" in low or "wall" in low or "jit" in low


def _is_numeric(s: pd.Series) -> bool:
    return pd.api.types.is_numeric_dtype(s) and not pd.api.types.is_bool_dtype(s)


def _compare_numeric(col: str, a: np.ndarray, b: np.ndarray, rtol: float,
                     atol: float = 0.0) -> list[str]:
    finite = np.concatenate([a[np.isfinite(a)], b[np.isfinite(b)]])
    scale = float(np.max(np.abs(finite))) if finite.size else 0.0
    both_nan = np.isnan(a) & np.isnan(b)
    same_inf = np.isinf(a) & np.isinf(b) & (np.sign(a) == np.sign(b))
    with np.errstate(invalid="ignore"):
        close = np.abs(a - b) <= rtol * np.maximum(np.abs(a), np.abs(b)) + \
            ABS_FLOOR_EPS * EPS * scale + atol
    bad = np.flatnonzero(~(close | both_nan | same_inf))
    if not bad.size:
        return []
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(a[bad] - b[bad]) / np.maximum(np.abs(a[bad]), np.abs(b[bad]))
    rel = rel[np.isfinite(rel)]
    rows = ", ".join(f"row {i}: {float(a[i])!r} -> {float(b[i])!r}"
                     for i in bad[:MAX_LISTED])
    more = f" (+{bad.size - MAX_LISTED} more)" if bad.size > MAX_LISTED else ""
    return [f"column {col!r}: {bad.size} value(s) differ, max rel "
            f"{(f'{rel.max():.3g}' if rel.size else 'n/a (NaN/inf)')}: "
            f"{rows}{more}"]


def _compare_text(col: str, a: pd.Series, b: pd.Series) -> list[str]:
    # missing values compare equal (pandas' string dtype keeps NaN through astype(str))
    sa, sb = (s.astype(str).fillna("<NA>").to_numpy(dtype=object) for s in (a, b))
    bad = np.flatnonzero(sa != sb)
    if not bad.size:
        return []
    rows = ", ".join(f"row {i}: {sa[i]!r} -> {sb[i]!r}" for i in bad[:MAX_LISTED])
    more = f" (+{bad.size - MAX_LISTED} more)" if bad.size > MAX_LISTED else ""
    return [f"column {col!r}: {bad.size} value(s) differ: {rows}{more}"]


def compare_tables(old: pd.DataFrame, new: pd.DataFrame, rtol: float = 1e-9,
                   atol: float = 0.0, rename: dict | None = None) -> list[str]:
    """Differences between two result tables (empty list if they agree); see the module
    docstring for the rules.  ``rename`` maps OLD column names to NEW ones."""
    diffs = []
    if rename:
        old = old.rename(columns={k: v for k, v in rename.items() if k in old.columns
                                  and v not in old.columns})
    cols_old = [c for c in old.columns if not is_skipped_column(c)]
    cols_new = [c for c in new.columns if not is_skipped_column(c)]
    only_old = [c for c in cols_old if c not in new.columns]
    only_new = [c for c in cols_new if c not in old.columns]
    if only_old:
        diffs.append(f"columns missing in NEW: {only_old}")
    if only_new:
        diffs.append(f"columns missing in OLD: {only_new}")
    if len(old) != len(new):
        diffs.append(f"row count differs: OLD {len(old)}, NEW {len(new)} "
                     f"(first {min(len(old), len(new))} rows compared)")
    n = min(len(old), len(new))
    for col in (c for c in cols_old if c in new.columns):
        a, b = old[col].iloc[:n], new[col].iloc[:n]
        if _is_numeric(a) and _is_numeric(b):
            diffs += _compare_numeric(str(col), a.to_numpy(float), b.to_numpy(float), rtol,
                                      atol)
        else:
            diffs += _compare_text(str(col), a, b)
    return diffs


def compare_claims(old: list[dict], new: list[dict]) -> list[str]:
    """Differences between two claim lists, matched by text: changed ``holds`` and
    claims present on one side only."""
    diffs = []
    new_by_text = {c.get("text"): c for c in new}
    old_texts = {c.get("text") for c in old}
    for c in old:
        t = c.get("text")
        if t not in new_by_text:
            diffs.append(f"claim missing in NEW: {t!r} (holds={c.get('holds')})")
        elif new_by_text[t].get("holds") != c.get("holds"):
            diffs.append(f"claim holds changed {c.get('holds')} -> "
                         f"{new_by_text[t].get('holds')}: {t!r}")
    for c in new:
        if c.get("text") not in old_texts:
            diffs.append(f"claim missing in OLD: {c.get('text')!r} (holds={c.get('holds')})")
    return diffs


def _artefacts(d: Path) -> set[str]:
    return {p.stem for p in d.iterdir() if p.suffix in (".csv", ".json") and p.is_file()}


def _read_json(path: Path) -> dict:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def _threads_env(doc: dict) -> dict:
    env = (doc.get("provenance") or {}).get("threads_env") or {}
    return {k: v for k, v in env.items() if v is not None}


def compare_artefact(name: str, old_dir: Path, new_dir: Path, rtol: float = 1e-9,
                     atol: float = 0.0, rename: dict | None = None) -> ArtefactReport:
    """Compare ``<name>.csv`` and the claims of ``<name>.json`` in the two folders."""
    rep = ArtefactReport(name)
    for ext in (".csv", ".json"):
        o, n = (old_dir / f"{name}{ext}").is_file(), (new_dir / f"{name}{ext}").is_file()
        if o != n:
            rep.differences.append(f"{name}{ext} missing in {'NEW' if o else 'OLD'}")
    if (old_dir / f"{name}.csv").is_file() and (new_dir / f"{name}.csv").is_file():
        old = pd.read_csv(old_dir / f"{name}.csv")
        renamed = sorted(k for k in (rename or {}) if k in old.columns)
        if renamed:
            rep.info.append("renamed " + ", ".join(f"{k} -> {rename[k]}" for k in renamed))
        rep.differences += compare_tables(old, pd.read_csv(new_dir / f"{name}.csv"), rtol,
                                          atol, rename)
    if (old_dir / f"{name}.json").is_file() and (new_dir / f"{name}.json").is_file():
        jo, jn = _read_json(old_dir / f"{name}.json"), _read_json(new_dir / f"{name}.json")
        rep.differences += compare_claims(jo.get("claims", []), jn.get("claims", []))
        to, tn = _threads_env(jo), _threads_env(jn)
        if to != tn:
            rep.info.append(f"warning: thread settings differ (OLD {to}, NEW {tn}): "
                            "round-off differs; rerun with the same *_NUM_THREADS")
    return rep


def compare_dirs(old_dir, new_dir, rtol: float = 1e-9, only=None,
                 require_all: bool = False, atol: float = 0.0,
                 rename: dict | None = None) -> list[ArtefactReport]:
    """One :class:`ArtefactReport` per artefact of either folder (restricted to ``only``
    if given). Artefacts on one side only are info, except those missing from NEW when
    ``require_all``."""
    old_dir, new_dir = Path(old_dir), Path(new_dir)
    for label, d in (("OLD_DIR", old_dir), ("NEW_DIR", new_dir)):
        if not d.is_dir():
            raise ValueError(f"{label} {str(d)!r} is not a directory")
    for label, tol in (("rtol", rtol), ("atol", atol)):
        if not (isinstance(tol, (int, float)) and tol >= 0):
            raise ValueError(f"{label} must be a number >= 0, got {tol!r}")
    a_old, a_new = _artefacts(old_dir), _artefacts(new_dir)
    names = sorted(a_old | a_new)
    if only:
        unknown = sorted(set(only) - set(names))
        if unknown:
            raise ValueError(f"--only names artefacts in neither folder: {unknown}")
        names = [n for n in names if n in set(only)]
    reports = []
    for name in names:
        if name in a_old and name in a_new:
            reports.append(compare_artefact(name, old_dir, new_dir, rtol, atol, rename))
        elif name in a_old:
            rep = ArtefactReport(name, compared=False, info=["missing in NEW, not compared"])
            if require_all:
                rep.differences.append("missing in NEW")
            reports.append(rep)
        else:
            reports.append(ArtefactReport(name, compared=False,
                                          info=["only in NEW, not compared"]))
    return reports


def _pair(text: str) -> tuple[str, str]:
    old, sep, new = text.partition("=")
    if not (sep and old and new):
        raise ValueError(f"--rename takes OLD=NEW, got {text!r}")
    return old, new


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old_dir", type=Path)
    ap.add_argument("new_dir", type=Path)
    ap.add_argument("--rtol", type=float, default=1e-9,
                    help="relative tolerance for numeric columns (default 1e-9)")
    ap.add_argument("--atol", type=float, default=0.0,
                    help="extra absolute tolerance for numeric columns (default 0)")
    ap.add_argument("--only", nargs="+", metavar="ID", help="compare only these artefacts")
    ap.add_argument("--require-all", action="store_true",
                    help="an artefact of OLD_DIR missing from NEW_DIR is a failure")
    ap.add_argument("--rename", nargs="+", default=[], metavar="OLD=NEW",
                    help="OLD_DIR column OLD is NEW_DIR column NEW (a deliberate rename)")
    ap.add_argument("--quiet-info", action="store_true",
                    help="do not print artefacts that were not compared")
    args = ap.parse_args(argv)
    try:
        rename = dict(_pair(r) for r in args.rename)
        reports = compare_dirs(args.old_dir, args.new_dir, args.rtol, args.only,
                               args.require_all, args.atol, rename)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for rep in reports:
        if rep.compared or rep.differences:
            print(rep.verdict() if rep.compared else f"DIFF {rep.name}: missing in NEW")
            if rep.compared and not rep.ok:
                for i in rep.info:
                    print(f"    {i}")
        elif not args.quiet_info:
            print(rep.verdict())
        for d in rep.differences:
            print(f"    {d}")
    compared = [r for r in reports if r.compared]
    failed = [r for r in reports if not r.ok]
    print(f"{len(compared)} artefact(s) compared, {len(failed)} differ"
          + (f": {', '.join(r.name for r in failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
