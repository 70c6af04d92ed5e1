"""The thesis's published numbers: finding and reading ``report/published/*.csv``
(first line a ``#`` comment: the caption) and comparing a reproduced table with one.

:func:`compare` joins the reproduced with the published table on the result's ``keys``
(outer join: rows on one side only are "not run" / "not published") and judges every
column with a tolerance (``("factor", f)``: reproduced/published within [1/f, f];
``("abs", a)``: |reproduced - published| <= a); the columns both tables have that are
not judged are put side by side.

Light on import (no pandas at module level): the command line's ``hpfebe list`` uses
:func:`published_file_for`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["published_file_for", "read_published", "compare", "Comparison", "key_value"]


def published_file_for(name: str, published_dir: Path) -> Path | None:
    """report/published/<name>.csv or <name>_*.csv, if there is one."""
    if not published_dir.is_dir():
        return None
    exact = published_dir / f"{name}.csv"
    if exact.is_file():
        return exact
    hits = sorted(published_dir.glob(f"{name}_*.csv"))
    return hits[0] if hits else None


@dataclass
class Comparison:
    """The join of a reproduced with a published table (:func:`compare`): per row its key
    values, presence ("both", "not run", "not published") and cells, and the counts."""

    keys: list[str]
    columns: list[str]                   # value columns compared
    tolerances: dict[str, tuple[str, float]]
    rows: list[dict] = field(default_factory=list)  # key values, per column cells
    n_ok: int = 0
    n_off: int = 0
    n_not_run: int = 0                   # published rows without a reproduced row
    n_not_published: int = 0             # reproduced rows without a published row
    shown: list[str] = field(default_factory=list)  # columns shown side by side, not judged


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


def key_value(x):
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
            k = tuple(key_value(row[c]) for c in keys)
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


def read_published(path: Path) -> tuple[pd.DataFrame, str]:
    import pandas as pd

    caption = ""
    with open(path, encoding="utf-8") as f:
        first = f.readline()
    if first.startswith("#"):
        caption = first.lstrip("#").strip()
    return pd.read_csv(path, comment="#"), caption
