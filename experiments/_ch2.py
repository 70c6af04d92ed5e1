"""Shared helpers of the Chapter 2 experiments (private, not an experiment module):
sweep tables, published-format tables, joins with the published tables.  The numerics
are :func:`hpfebe.scenes.interface.lambda_sweep` and :func:`hpfebe.analysis.observed_rates`.
"""

from __future__ import annotations

import logging

import numpy as np
import pandas as pd

from hpfebe.analysis import observed_rates
from hpfebe.scenes import interface
from hpfebe.suite import progress

logging.getLogger("skfem").setLevel(logging.WARNING)  # one INFO line per assembly otherwise

PUBLISHED_COLUMNS = ["series", "h_inv", "p", "l2_error", "l2_rate", "h1_error", "h1_rate"]
KEYS = ("series", "h_inv", "p")


def sweep(name: str, series: str, cases, lambdas, alpha: float, h_def: str,
          desc: str = "", companions: bool = False) -> pd.DataFrame:
    """One row per (case, lambda_Nit) of problem ``name``: cases are (fe_h_inv,
    be_h_inv, p) triples; columns problem, series, then those of ``lambda_sweep``
    (:func:`hpfebe.scenes.interface.sweep_rows`)."""
    return pd.DataFrame(interface.sweep_rows(name, series, cases, lambdas, alpha, h_def,
                                             desc, companions, progress))


def rates(x, e) -> np.ndarray:
    """Observed rates w.r.t. increasing x (h^-1 or p): log(e_prev/e) / log(x/x_prev),
    NaN first."""
    return observed_rates(1.0 / np.asarray(x, float), np.asarray(e, float))


def part_table(df: pd.DataFrame, part: str, h_col: str) -> pd.DataFrame:
    """Published-format table of one part ("fe" or "be"): series, h_inv, p, errors and
    rates (w.r.t. h^-1 for series h, w.r.t. p for series p), then dof and timings; the BE
    part adds the H1 error of the same interpolant of the exact u, and the trace energy
    error |u - U2|_W on Gamma2 with its rate."""
    out = []
    for series, g in df.groupby("series", sort=False):
        keys = ["p"] if series == "h" else [h_col]
        for _, gg in g.groupby(keys, sort=False):
            gg = gg.sort_values(h_col if series == "h" else "p")
            x = gg[h_col] if series == "h" else gg["p"]
            t = pd.DataFrame({
                "series": series, "h_inv": gg[h_col].astype(int), "p": gg["p"],
                "l2_error": gg[f"{part}_l2"], "l2_rate": rates(x, gg[f"{part}_l2"]),
                "h1_error": gg[f"{part}_h1"], "h1_rate": rates(x, gg[f"{part}_h1"]),
                "dof": gg["dof"], "wall_time_s": gg["wall_time_s"],
                "fe_h_inv": gg["fe_h_inv"], "be_h_inv": gg["be_h_inv"],
                "lambda_nit": gg["lambda_nit"]})
            if part == "be" and "be_energy" in gg:
                t["h1_interp_exact"] = gg["be_h1_interp"].to_numpy()
                t["trace_energy_error"] = gg["be_energy"].to_numpy()
                t["trace_energy_rate"] = rates(x, gg["be_energy"])
            out.append(t)
    return pd.concat(out, ignore_index=True)


def last(table: pd.DataFrame, series: str, p, col: str) -> float:
    """Last entry of ``col`` in a part table: series h at degree p, or series p."""
    g = table[(table.series == series) & (table.p == p)] if series == "h" else \
        table[table.series == series]
    return float(g[col].iloc[-1])


def compare(table: pd.DataFrame, published: pd.DataFrame, col: str) -> pd.Series:
    """reproduced / published for the rows present in both (keys series, h_inv, p)."""
    m = table.merge(published, on=list(KEYS), suffixes=("", "_pub"))
    return m[col] / m[f"{col}_pub"]

