"""Table 4.3 (Section 4.4, thesis line ~20700): the penalty FE/BE runs for 1/eps_n = 20,
10, 5, 2.5 x E_m (1/eps_t half of that; Algorithm 4.1 with the penalty laws
(4.19)-(4.20) and the consistent tangents (4.36)-(4.43)): Newton iterations and the L2
norm of the penetration ([u_n] - g)_+ on Gamma_C, their trends, the penetration's scaling
with eps_n, and the contact treatment (one or two passes) that decides the norms."""

from __future__ import annotations

import time
from dataclasses import replace

import pandas as pd

from hpfebe.scenes import section44 as s44
from hpfebe.scenes import section44_fields as f44
from hpfebe.scenes import section44_readings as rd44
from hpfebe.scenes import section44_runs as runs44
from hpfebe.suite import ArtefactResult, Claim, progress, published_table, rate_claim

S44 = s44.Section44Scene
PUBLISHED = "table_4_3_penalty_newton.csv"


def penalty_table(prm: S44, runs: dict) -> pd.DataFrame:
    return pd.DataFrame([runs44.penalty_row(prm, r) for r in runs.values()])


def penetration_slope(tab: pd.DataFrame) -> float:
    return runs44.penetration_slope(tab.inv_eps_n_over_E, tab.penetration_l2, tab.converged)


def slope_claim(prm: S44, tab: pd.DataFrame, fine: pd.DataFrame | None) -> Claim:
    """Penetration ~ eps_n on the finest mesh run (the table's mesh, or h_work_fine)."""
    c = rate_claim("(beyond the thesis) the L2 norm of the penetration is linear in eps_n "
                   "(log-log slope 1; on the finest work piece mesh run)",
                   penetration_slope(tab if fine is None else fine), 1.0, prm.slope_tol,
                   "slope")
    runs = [(name, q.penalty_cells, t, penetration_slope(t)) for name, t, q in (
        ("table mesh", tab, prm), ("fine mesh", fine, prm.fine())) if t is not None]
    thesis = penetration_slope(published_table(PUBLISHED).assign(converged=True))
    c.evidence += rd44.slope_evidence(runs + [("thesis", None, None, thesis)])
    return c


def penalty_claims(prm: S44, tab: pd.DataFrame, fine, runs: dict, other: dict,
                   published: pd.DataFrame) -> list[Claim]:
    """Table 4.3's statements: the trends, the penetration's scaling and norms, the
    contact treatment that decides them (with the other treatment ``other``), Newton."""
    pen, its = rd44.trend_readings(tab)
    out = [Claim("smaller penalty parameters eps reduce the L2 norm of the penetration",
                 *pen, id="penetration_trend"),
           Claim("smaller penalty parameters eps increase the number of Newton iterations "
                 "(thesis: 175 -> 520)", *its, id="newton_trend"),
           replace(slope_claim(prm, tab, fine), kind="beyond", id="slope"),
           Claim(f"penetration norms within a factor {prm.pen_factor:g} of Table 4.3 "
                 f"({rd44.passes_text(prm.two_pass)})",
                 *rd44.penetration_reading(prm, tab, published), id="penetration")]
    if other:
        within, n, holds, ev = rd44.passes_reading(prm, runs, other, published)
        out.append(Claim(
            "(analysis) the contact treatment decides Table 4.3's penetration norms: a "
            "single master-slave pass gives about twice the printed norms (ratio >= 1.5), "
            f"two passes (each body the slave once) match them; within a factor "
            f"{prm.pen_factor:g}: two-pass {within['two']} of {n}, single-pass "
            f"{within['single']} of {n}", holds, ev, kind="explanation", id="passes"))
    return out + [Claim("(beyond the thesis) with the consistent tangents, line search and "
                        "load stepping Newton needs an order of magnitude fewer iterations "
                        "than the thesis's 175-520", *rd44.newton_reading(tab, published),
                        kind="beyond", id="newton")]


# --------------------------------------------------------------------------- artefact
def _penalty_notes(runs: dict) -> tuple[str, list[str]]:
    failed = [f"1/eps_n = {f:g} E: {r.result.reason}" for f, r in runs.items()
              if not r.result.converged]
    return " ".join(runs44.CHOICES) + (" FAILED RUNS: " + "; ".join(failed) if failed else ""), \
        failed


def table_4_3(prm: S44, solve=runs44.run_penalty) -> ArtefactResult:
    """Table 4.3: the penalty sweep, with the other contact treatment and on the fine
    mesh beside it."""
    t0 = time.perf_counter()
    runs = {f: solve(prm, f) for f in progress(prm.eps_n_factors, desc="penalty")}
    tab = penalty_table(prm, runs)
    other = {}                           # the sweep with the other contact treatment
    if prm.compare_passes:
        po = replace(prm, two_pass=not prm.two_pass)
        other = {f: solve(po, f) for f in progress(prm.eps_n_factors,
                                                   desc="penalty, other passes")}
    fine = None
    if prm.h_work_fine > 0:
        pf = prm.fine()
        fine = penalty_table(pf, {f: solve(pf, f) for f in
                                  progress(prm.eps_n_factors, desc="penalty, fine mesh")})
    notes, failed = _penalty_notes(runs)
    published = published_table(PUBLISHED)
    meta = dict(run_s=time.perf_counter() - t0, all_converged=not failed,
                dof_fe=int(tab.dof_fe.iloc[0]), dof_be=int(tab.dof_be.max()),
                allow_nan_columns=["penetration_l2", "max_dev_sigma", "contact_force"],
                slope_table_mesh=penetration_slope(tab),
                slope_fine_mesh=None if fine is None else penetration_slope(fine),
                other_passes_penetration={f"{f:g}": r.penetration_l2 for f, r in
                                          other.items() if r.peak is not None},
                reading=rd44.reading_43(prm, tab, other, published))
    return ArtefactResult(
        "table_4_3", tab, published=PUBLISHED, keys=("inv_eps_n_over_E", "inv_eps_t_over_E"),
        tolerances={"penetration_l2": ("factor", prm.pen_factor)},
        claims=penalty_claims(prm, tab, fine, runs, other, published), notes=notes, meta=meta,
        exports=f44.penalty_exports(prm, runs[max(runs)]))     # the stiffest penalty
