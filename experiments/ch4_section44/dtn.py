"""Table 4.2 (Section 4.4): the Dirichlet-to-Neumann algorithm (Algorithm 4.3 with the
elastoplastic Neumann problem (4.88) of Remark 4.3.5, the stamp's frictional contact
problem by Uzawa, Algorithm 4.4) on the grid of damping pairs (omega_D, omega_N): DtN
iterations and the Uzawa iterations of the first DtN iteration, non-convergence detected;
the readings of the stopping rule (step 7), the lower bound that step 6 puts on it, the
tolerance that fits the thesis's counts, and (beyond the thesis) the monolithic
semismooth Newton for the same discrete problem."""

from __future__ import annotations

import pandas as pd

from hpfebe.scenes import section44 as s44
from hpfebe.scenes import section44_fields as f44
from hpfebe.scenes import section44_readings as rd44
from hpfebe.scenes import section44_runs as runs44
from hpfebe.suite import ArtefactResult, Claim, progress, published_table

S44 = s44.Section44Scene
PUBLISHED_42 = "table_4_2_dtn_elastoplastic.csv"


def mortar_sweep(prm: S44, pr):
    """Table 4.2: every damping pair; returns (table, {pair: solution})."""
    rows, sols = [], {}
    for wD in progress(prm.omegas_D, desc="table_4_2"):
        for wN in prm.omegas_N:
            row, sols[(float(wD), float(wN))] = runs44.dtn_row(prm, pr, wD, wN)
            rows.append(row)
    return pd.DataFrame(rows), sols


def mortar_claims(prm: S44, tab: pd.DataFrame, pub: pd.DataFrame) -> list[Claim]:
    """Table 4.2's statements: the counts, the '-' cells, the Uzawa counts of the first
    and the later DtN iterations, the optimal dampings."""
    r, f = rd44.counts_readings(prm, tab, pub), prm.iteration_factor
    out = [Claim(f"DtN iteration counts within {f - 1:.0%} of Table 4.2 where both converge",
                 *r["counts"], id="counts"),
           Claim(f"(other reading) the same runs stopped at TOL_DtN = {prm.alt_tol_dtn:g} "
                 f"(e.g. the thesis's DtN accuracy limited by its Newton TOL_N = 1e-4): "
                 f"counts within {f - 1:.0%} of Table 4.2", *r["alt_tol"], kind="hypothesis",
                 id="alt_tol", explains=("counts", "cells:dtn_iterations")),
           Claim("no convergence for large damping parameters: the same '-' cells as "
                 "Table 4.2", *r["no_convergence"], id="no_convergence"),
           Claim("Uzawa iterations in the first DtN iteration fall with omega_D (the "
                 "thesis: 34, 17, 12-13, 9 for omega_D = 0.3, 0.5, 0.7, 0.9)",
                 *r["uzawa_first"], id="uzawa_first"),
           Claim("after the first DtN iteration the Uzawa algorithm needs only 2 "
                 "iterations (the sliding direction is recognised)", *r["uzawa_later"],
                 id="uzawa_later")]
    if "optimum" in r:
        out += [Claim("the optimal damping parameters lie between 0.5 and 0.7",
                      *r["optimum"], id="optimum"),
                Claim("the thesis's own Table 4.2 has its fewest DtN iterations outside "
                      "0.5-0.7: the statement on the optimal damping parameters does not "
                      "describe the thesis's table", *r["optimum_table"],
                      kind="explanation", id="optimum_table", explains=("optimum",))]
    return out


def readings_claim(prm: S44, tab: pd.DataFrame, pub: pd.DataFrame) -> Claim:
    """(analysis) whether any reading of the stopping rule explains the counts (the
    lower bound that step 6 puts on them: :func:`tangential_bound_claim`)."""
    return Claim("(analysis) no reading of the DtN stopping rule (quantity P, its normal "
                 "part or U2; l2, max, L2(Gamma_C) or energy norm; relative to the previous, "
                 f"new or first iterate) brings the counts at TOL_DtN = {prm.tol_dtn:g} "
                 f"within {prm.iteration_factor - 1:.0%} of Table 4.2 in most cells; the "
                 "printed rule (P, relative to P^k-1) gives the table's counts",
                 *rd44.readings_verdict(prm, tab, pub), kind="beyond", id="readings")


def tangential_bound_claim(prm: S44, tab: pd.DataFrame, pub: pd.DataFrame, sols: dict,
                           shares: dict | None = None) -> Claim:
    """(analysis) the lower bound that step 6 puts on the printed rule
    (:func:`hpfebe.scenes.section44_readings.step6_bound`)."""
    r = rd44.step6_bound(prm, tab, pub, sols, shares)
    if r is None:
        return Claim("(analysis) Table 4.2's counts against the tangential lower bound of "
                     "the printed stopping rule", None, "no common converged cell",
                     kind="explanation", id="step6_bound")
    holds, ev, below, n = r
    return Claim(
        f"(analysis) step 6 bounds the printed rule from below: the tangential increments "
        f"contract by exactly 1 - omega_N, our counts respect the bound, and the thesis's "
        f"counts lie below it in {len(below)} of {n} cells (the same cells on every "
        f"sensitivity variant's meshes)", holds, ev, kind="explanation", id="step6_bound",
        explains=tuple(f"cells:dtn_iterations[omega_D={a:g},omega_N={b:g}]" for a, b in below))


def tolerance_fit_claim(prm: S44, tab: pd.DataFrame, pub: pd.DataFrame,
                        sols: dict) -> Claim:
    """(analysis) The relative stopping tolerance whose counts fit Table 4.2 best
    (:func:`hpfebe.scenes.section44_readings.tolerance_fit`)."""
    link = dict(kind="hypothesis", id="tol_fit", explains=("counts", "cells:dtn_iterations"))
    r = rd44.tolerance_fit(prm, tab, pub, sols)
    if r is None:
        return Claim("(analysis) the relative tolerance that fits Table 4.2", None,
                     "no common converged cell", **link)
    tol, k, n, holds, ev = r
    return Claim(f"(analysis) the thesis's counts are those of a relative stop at about "
                 f"{tol:g}, not {prm.tol_dtn:g}: {k} of {n} cells within "
                 f"{prm.iteration_factor - 1:.0%} there (scan of the same runs' relative "
                 f"increments)", holds, ev, **link)


# --------------------------------------------------------------------------- artefact
def table_4_2(prm: S44, pr, tab: pd.DataFrame, sols: dict, setup_s: float):
    pub = published_table(PUBLISHED_42)
    claims = mortar_claims(prm, tab, pub) + [
        readings_claim(prm, tab, pub),
        tangential_bound_claim(prm, tab, pub, sols, runs44.tangential_shares(prm, pr)),
        tolerance_fit_claim(prm, tab, pub, sols)]
    meta = dict(setup_s=setup_s, run_s=float(tab.wall_time_s.sum() + setup_s),
                dof_stamp_nodes=int(pr.stamp.mesh.p.shape[1]),
                dof_work_nodes=int(pr.work.mesh.p.shape[1]),
                dof_stamp=int(pr.stamp.ndofs), dof_work=int(pr.work.ndofs),
                stamp_cells=list(prm.stamp_cells), work_cells=list(prm.work_cells),
                allow_nan_columns=["dtn_iterations", "uzawa_iterations_first_dtn",
                                   "max_dev_sigma", "dtn_iterations_alt_tol", "tail_rate"]
                + [c for c in tab if c.startswith("its_")])
    fig = sols.get(tuple(float(w) for w in prm.figure_omegas))  # Figure 4.21's dampings
    fig = fig if fig is not None and fig.info.converged else None
    if prm.monolithic:
        holds, ev, info = rd44.monolithic_reading(pr, sols, prm, tab)
        claims.append(Claim("(beyond the thesis) a monolithic semismooth Newton gives the "
                            "same solution" if holds is None else
                            "(beyond the thesis) the monolithic semismooth Newton (stamp, "
                            "work piece and nodal contact forces at once) gives the DtN "
                            "solution", holds, ev, kind="beyond", id="monolithic"))
        meta.update(info)
    return ArtefactResult(
        "table_4_2", tab, published=PUBLISHED_42, keys=("omega_D", "omega_N"),
        tolerances={"dtn_iterations": ("factor", prm.iteration_factor)}, claims=claims,
        notes=" ".join(runs44.MORTAR_CHOICES) + " Empty dtn_iterations = no convergence "
        "(reason column); uzawa_first_run has the first count of every run; "
        "dtn_iterations_alt_tol: the iteration at which the same run's relative increment "
        f"first fell below {prm.alt_tol_dtn:g} (empty where the run did not converge). "
        + rd44.readings_note(prm, tab, pub),
        meta=meta, exports=f44.mortar_exports(pr, fig) if fig is not None else {})
