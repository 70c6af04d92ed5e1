"""Shared sweeps of the Chapter 2 experiments (private helper, not an experiment module).

``sweep`` builds the coupled system of each mesh pair once and solves it for every
lambda_Nit requested (only the penalty blocks are rescaled), then measures the FE- and
BE-part errors with :mod:`hpfebe.coupling.errors`.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pandas as pd

from hpfebe.coupling import NitscheFEBE, problem
from hpfebe.coupling.errors import be_domain_errors, be_trace_energy_error, fe_errors
from hpfebe.results import progress

log = logging.getLogger("experiments.ch2")
logging.getLogger("skfem").setLevel(logging.WARNING)  # one INFO line per assembly otherwise

PUBLISHED_COLUMNS = ["series", "h_inv", "p", "l2_error", "l2_rate", "h1_error", "h1_rate"]


def sweep(name: str, series: str, cases, lambdas, alpha: float, h_def: str,
          desc: str = "", companions: bool = False) -> pd.DataFrame:
    """One row per (case, lambda): cases are (fe_h_inv, be_h_inv, p) triples.
    ``companions`` adds the BE columns be_energy (|u - U2|_W, which assembles a richer
    W per solve) and be_h1_interp (the interpolation error of the exact u)."""
    pb = problem(name)
    rows = []
    for fh, bh, p in progress(list(cases), desc=desc or f"{name} {series}"):
        t0 = time.perf_counter()
        model = NitscheFEBE(pb, fh, bh, int(p), alpha=alpha, h_def=h_def)
        t_asm = time.perf_counter() - t0
        for lam in lambdas:
            t1 = time.perf_counter()
            sol = model.solve(float(lam))
            t_solve = time.perf_counter() - t1
            fe = fe_errors(model, sol)
            be = be_domain_errors(model, sol)
            row = dict(problem=name, series=series, lam=float(lam), p=int(p),
                       fe_h_inv=fh, be_h_inv=bh, n_fe=model.n1, n_be=model.n2,
                       dof=model.ndof, fe_l2=fe["l2"], fe_h1=fe["h1"],
                       be_l2=be["l2"], be_h1=be["h1"], assembly_s=t_asm,
                       solve_s=t_solve, wall_time_s=t_asm + t_solve,
                       residual=sol.info["residual"])
            if companions:
                row["be_energy"] = be_trace_energy_error(model, sol)
                row["be_h1_interp"] = be_domain_errors(model, sol,
                                                       interpolate_exact=True)["h1"]
            rows.append(row)
            log.info("%s %s p=%d FE 1/%g BE 1/%g lam=%g dof=%d: FE %.3e %.3e BE %.3e %.3e "
                     "(%.2f s + %.2f s)", name, series, p, fh, bh, lam, model.ndof,
                     fe["l2"], fe["h1"], be["l2"], be["h1"], t_asm, t_solve)
    return pd.DataFrame(rows)


def rates(x, e) -> np.ndarray:
    """log(e_prev/e) / log(x/x_prev) for increasing x (h^-1 or p); NaN first."""
    x, e = np.asarray(x, float), np.asarray(e, float)
    r = np.full(len(e), np.nan)
    r[1:] = np.log(e[:-1] / e[1:]) / np.log(x[1:] / x[:-1])
    return r


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
                "lambda_nit": gg["lam"]})
            if part == "be" and "be_energy" in gg:
                t["h1_interp_exact"] = gg["be_h1_interp"].to_numpy()
                t["trace_energy_error"] = gg["be_energy"].to_numpy()
                t["trace_energy_rate"] = rates(x, gg["be_energy"])
            out.append(t)
    return pd.concat(out, ignore_index=True)


def compare(table: pd.DataFrame, published: pd.DataFrame, col: str) -> pd.Series:
    """reproduced / published for the rows present in both (keys series, h_inv, p)."""
    m = table.merge(published, on=["series", "h_inv", "p"], suffixes=("", "_pub"))
    return m[col] / m[f"{col}_pub"]


def add_slope(ax, x, y0, slope, label, **kw):
    """Reference line y = y0 (x / x[0])^slope over the range of x."""
    x = np.asarray([np.min(x), np.max(x)], float)
    ax.loglog(x, y0 * (x / x[0]) ** slope, "k--", lw=0.8, alpha=0.7, **kw)
    ax.annotate(label, (x[-1], y0 * (x[-1] / x[0]) ** slope), fontsize=7, alpha=0.8)
