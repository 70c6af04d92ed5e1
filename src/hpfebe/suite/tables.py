"""Table building that the experiments repeat: the thesis's published tables as data
frames, observed rates per group of a sweep.

    pub = published_table("table_3_1_penalty_eps.csv")
    df["rate"] = grouped_rates(df, ["C_pen", "p"], "h", "energy_error")
    ratio = published_ratio(table, pub, ["C_eps", "dof"], "err")   # ours / published
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from hpfebe.analysis import observed_rates

__all__ = ["published_table", "grouped_rates", "published_ratio", "PUBLISHED_DIR"]

#: report/published/ of the repository (the package is installed from its src/)
PUBLISHED_DIR = Path(__file__).resolve().parents[3] / "report" / "published"


def published_table(filename: str, directory: Path | str | None = None) -> pd.DataFrame:
    """The published table ``filename`` of ``directory`` (default :data:`PUBLISHED_DIR`)
    as a data frame; its first line, a ``#`` comment (the caption), is skipped."""
    path = Path(PUBLISHED_DIR if directory is None else directory) / filename
    if not path.is_file():
        raise ValueError(f"filename={filename!r}: no published table {path}")
    return pd.read_csv(path, comment="#")


def grouped_rates(df: pd.DataFrame, by, h, e) -> np.ndarray:
    """Observed rates log(e_prev/e) / log(h_prev/h) (:func:`hpfebe.analysis.observed_rates`)
    within every group of rows of ``df`` with equal ``by`` (rows in their order, NaN on
    the first row of a group); ``h`` and ``e`` are column names or arrays of len(df)
    (``1 / df.dof`` for rates in DOF^-1).  Returned in the row order of ``df``."""
    h = np.asarray(df[h] if isinstance(h, str) else h, float)
    e = np.asarray(df[e] if isinstance(e, str) else e, float)
    out = np.full(len(df), np.nan)
    for rows in df.groupby(by, sort=False).indices.values():
        out[rows] = observed_rates(h[rows], e[rows])
    return out


def published_ratio(table: pd.DataFrame, published: pd.DataFrame, keys, col: str,
                    ours: str | None = None) -> pd.Series:
    """reproduced / published of column ``col`` over the rows present in both tables
    (joined on the columns ``keys``); ``ours``: the column of ``table`` to divide (default
    ``col``)."""
    m = table.merge(published, on=list(keys), suffixes=("", "_pub"))
    return m[ours or col] / m[f"{col}_pub"]
