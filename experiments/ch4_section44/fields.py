"""Figures 4.22 (penalty) and 4.21 (mortar), Section 4.4: the fields at full lift, their
colour bars against the published ones, and the explanations of the bars that differ
(frictionless contact, plastic flow), each re-tested on the sensitivity variants;
Figure 4.21 adds the comparison with the penalty solution (:mod:`.comparison`) and the
work piece formulation (plain Q1 against B-bar)."""

from __future__ import annotations

import time
from dataclasses import replace

import pandas as pd
from matplotlib.figure import Figure

from hpfebe.scenes import section44 as s44
from hpfebe.scenes import section44_fields as f44
from hpfebe.scenes import section44_figures as fig44
from hpfebe.scenes import section44_runs as runs44
from hpfebe.suite import ArtefactResult, Claim, progress, range_claim

from .comparison import comparison_claims
from .penalty import _penalty_notes
from .plots import fields_figure

S44 = s44.Section44Scene


def colour_ranges(bodies: dict, r) -> pd.DataFrame:
    """Figure 4.22's colour ranges of the penalty run ``r``."""
    return pd.DataFrame(f44.colour_ranges(bodies, r.peak.fields["dev_sigma_norm"]))


def mortar_ranges(bodies: dict, sol) -> pd.DataFrame:
    """Figure 4.21's colour ranges of the mortar solution ``sol``."""
    return pd.DataFrame(f44.colour_ranges(bodies, sol.extra["fields"]["dev_sigma_norm_mean"],
                                          mortar=True))


def figure_claims(prm: S44, ranges: pd.DataFrame, fig: str = "4.22",
                  dev_max: float = s44.PUB_DEV_MAX) -> list[Claim]:
    """The colour bars of Figure ``fig`` (ids ``<field>_<body>``, ``dev_max``): each
    extreme against the published one (relative difference), Dirichlet extremes not
    tested."""
    out = []
    for _, row in ranges[ranges.field != "dev_sigma_norm"].iterrows():
        c = range_claim(f"Figure {fig} colorbar of {row.field} in the {row.body}",
                        f"{row.body} {row.field}", (row.ours_min, row.ours_max),
                        (row.published_min, row.published_max), prm.range_tol,
                        fixed=f44.fixed_extremes(prm, row.body, row.field, row.ours_min,
                                              row.ours_max))
        out.append(replace(c, id=f"{row.field}_{row.body}"))
    if fig == "4.22":
        out[[c.id for c in out].index("u_x_stamp")].evidence += fig44.stamp_expansion(
            prm, ranges[ranges.body == "stamp"].set_index("field").loc["u_y", "ours_max"])
    dmax = float(ranges[ranges.field == "dev_sigma_norm"].ours_max.iloc[0])
    out.append(Claim(f"max ||dev sigma_m|| = {dev_max} (Figure {fig}), within "
                     f"{prm.range_tol:.0%}", *fig44.dev_max_reading(prm, dmax, dev_max),
                     id="dev_max"))
    return out


# --------------------------------------------------------------------------- explanations
def frictionless_claim(prm: S44, solve, variants: dict) -> Claim:
    """(explanation of Figure 4.22's stamp u_x colour bar) frictionless contact
    (:func:`hpfebe.scenes.section44_figures.frictionless_reading`)."""
    return Claim(f"the thesis's stamp u_x colour bar (Figure 4.22) is that of frictionless "
                 f"contact: in every sensitivity variant our frictionless penalty run gives "
                 f"its maximum within {prm.range_tol:.0%}, our Coulomb mu_f = {prm.mu_f:g} "
                 f"run misses it by more than {prm.range_tol:.0%}",
                 *fig44.frictionless_reading(prm, solve, variants), kind="explanation",
                 id="frictionless", explains=("u_x_stamp",))


def flow_claim(fig: str, reading: tuple) -> Claim:
    """(hypothesis for the work piece's u_x colour bar of Figure ``fig``) the thesis's
    work piece flows less than ours (:func:`hpfebe.scenes.section44_figures.flow_reading`)."""
    return Claim(f"the thesis's work piece flows less than ours (Figure {fig}): its u_x "
                 f"maximum lies between our elastic-only one and ours in every sensitivity "
                 f"variant (not derived: a reading of the u_x colour bar)", *reading,
                 kind="hypothesis", id="plastic_flow", explains=("u_x_work",))


# --------------------------------------------------------------------------- artefacts
def figures(prm: S44, solve=runs44.run_penalty) -> dict:
    """Figures 4.22 and 4.21: the penalty runs of Table 4.3's parameters, the mortar
    DtN solution, the comparison and the sensitivity variants of both figures'
    explanations."""
    t0 = time.perf_counter()
    runs = {f: solve(prm, f) for f in progress(prm.eps_n_factors, desc="penalty")}
    variants = s44.sensitivity_variants(prm)
    fig22 = figure_4_22(prm, runs, solve, variants, time.perf_counter() - t0)
    pr = runs44.mortar_scene(prm)
    pen_ranges = fig22.table if "ours_max" in fig22.table else None
    fig21 = figure_4_21(prm, pr, runs, pen_ranges, solve, variants)
    return {"figure_4_22": fig22, "figure_4_21": fig21}


def _failed(name: str, reason: str, notes: str, meta: dict | None = None) -> ArtefactResult:
    """The artefact of a figure whose run failed: no fields, the reason as its claim."""
    fig = name.split("_", 1)[1].replace("_", ".")
    return ArtefactResult(name, pd.DataFrame({"converged": [False]}), Figure(figsize=(4, 2)),
                          claims=[Claim(f"Figure {fig} fields", None, reason)], notes=notes,
                          meta=meta or {})


def figure_4_22(prm: S44, runs: dict, solve, variants: dict, runs_s: float
                ) -> ArtefactResult:
    """Figure 4.22: the fields of the figure_factor run, its colour ranges, and the
    explanations of the ranges that differ, re-tested on the sensitivity variants."""
    t0 = time.perf_counter()
    notes, failed = _penalty_notes(runs)
    r = runs[prm.figure_factor]
    meta = dict(penalty_runs_s=runs_s, all_converged=not failed)
    if r.peak is None:
        return _failed("figure_4_22", r.result.reason, notes, meta)
    bodies = r.bodies(prm.h_stamp)
    ranges = colour_ranges(bodies, r)
    claims = figure_claims(prm, ranges)
    claims.append(frictionless_claim(prm, solve, variants))
    claims.append(flow_claim("4.22", fig44.penalty_flow(prm, solve, variants)))
    meta.update(dof_fe=int(r.fe.ndofs), dof_be=int(r.peak.u_stamp.size),
                allow_nan_columns=["published_min"],
                sensitivity_s=time.perf_counter() - t0)
    fig = fields_figure(bodies, ranges, r.peak.fields["dev_sigma_norm"],
                        f"penalty FE/BE, 1/eps_n = {r.factor:g} E_m, 1/eps_t = half, full "
                        "lift 1e-4")
    return ArtefactResult("figure_4_22", ranges, fig, claims=claims, notes=notes, meta=meta,
                          exports=f44.penalty_exports(prm, r))


def figure_4_21(prm: S44, pr, runs: dict, pen_ranges=None, solve=runs44.run_penalty,
                variants: dict | None = None) -> ArtefactResult:
    """Figure 4.21: the DtN solution at figure_omegas, its colour ranges, the
    comparison with the penalty runs ``runs`` (factor -> Run, Table 4.3's parameters)
    and its split, the formulation check against Figure 4.22's ranges ``pen_ranges``;
    the explanations re-tested on the sensitivity ``variants`` (default
    :func:`sensitivity_variants`)."""
    key = tuple(float(w) for w in prm.figure_omegas)
    sol = runs44.dtn_run(pr, prm, *key)
    notes = " ".join(runs44.MORTAR_CHOICES)
    if not sol.info.converged:
        return _failed("figure_4_21", sol.info.reason, notes)
    variants = s44.sensitivity_variants(prm) if variants is None else variants
    bodies = s44.mortar_bodies(pr, sol)
    ranges = mortar_ranges(bodies, sol)
    claims = figure_claims(prm, ranges, "4.21", s44.PUB_MORTAR_DEV_MAX)
    meta = dict(allow_nan_columns=["ours_min", "ours_max", "published_min", "published_max",
                                   "rel_l2", "rel_max", "n_points"], omegas=list(key),
                dtn_iterations=sol.info.iterations)
    table = ranges.assign(quantity="colorbar", variant="")
    t = time.perf_counter()
    mortar = runs44.mortar_variants(prm, pr, sol, variants)
    claims.append(flow_claim("4.21", fig44.mortar_flow(prm, mortar)))
    pen = runs.get(prm.figure_factor)
    if pen is not None and pen.peak is not None:
        free = runs44.dtn_run(pr, prm, *prm.figure_omegas, F=0.0)
        rows, extra = f44.comparison_rows(prm, pr, sol, free, runs, solve)
        diff = pd.DataFrame(rows)
        claims.extend(comparison_claims(rows, prm, f44.variant_rows(
            prm, mortar, solve, variants)))
        if prm.compare_variants and pen_ranges is not None:
            claims.append(Claim(
                "(analysis) plain Q1 ('full') and B-bar work pieces give colorbar ranges "
                f"within {prm.range_tol:.0%} of each other (shift in % of the published "
                "span)", *fig44.formulation_reading(prm, ranges.to_dict("records"),
                                                    pen_ranges.to_dict("records"), extra),
                kind="beyond", id="formulation"))
        meta["variant_run_s"] = {k: r.wall_s for k, r in extra.items()}
        table = pd.concat([table, diff.assign(quantity="mortar_vs_penalty")],
                          ignore_index=True)
    meta["comparison_s"] = time.perf_counter() - t
    plastic = sol.extra["fields"]["eps_p_norm_mean"] > 0
    meta["plastic_area"] = float(pr.work.dx.sum(axis=1)[plastic].sum())
    fig = fields_figure(bodies, ranges, sol.extra["fields"]["dev_sigma_norm_mean"],
                        f"mortar FEM + DtN (omega_D, omega_N) = {key}, Tresca F = "
                        f"{prm.F:g}, {sol.info.iterations} DtN iterations; plastic area "
                        f"{meta['plastic_area']:.3g}", plastic)
    return ArtefactResult("figure_4_21", table, fig, claims=claims, notes=notes + " "
                          + " ".join(f"variant {k}: {v}." for k, v in f44.VARIANTS.items()),
                          meta=meta, exports=f44.mortar_exports(pr, sol))
