"""Chapter 2, Section 2.2.5, Examples 1 and 2: convergence of hp-Nitsche FE/BE coupling.

Weak form (2.3)-(2.4), lambda_Nit = 10, solved by hpfebe.coupling.NitscheFEBE; errors by
hpfebe.coupling.errors (FE part in Omega1, BE part in Omega2, trace energy |u - U2|_W).
Example 1 (smooth, (2.10)-(2.12)): h-version p1 = p2 = 1, 2, 3 with FE h^-1 = 2, 5, 11, 23,
47 and BE h^-1 = 3, 6, 12, 24, 48 (Tables 2.1, 2.2); p-version on FE h = 1/5 (75 elements)
and BE h = 1/6 (24 elements), p1 = p2 = 1..8, against the h-version p = 2 (Figure 2.2).
Example 2 (singular, (2.13)-(2.15)): h-version p = 1, FE h^-1 = 4..256, BE h^-1 = 8..260;
p-version p = 1..7 on FE h^-1 = 4, BE h^-1 = 6 (Tables 2.3, 2.4; Figure 2.4).
Figures 2.1 and 2.3: the computed solutions.  Beyond the thesis: error against wall time
(figure_work_precision_ch2), each run timed up to ``timing_repeats`` times, fewer once
its timings sum to ``timing_budget_s`` (the minimum is plotted).  Two :data:`SCENES`:
Example 1, and Example 2 with the work-precision figure, which times the runs of both
examples' sweeps: a run computes each sweep once
(:func:`sweep_memo`), so the work-precision figure repeats the cheap Example 1 sweep
only when the scenes run as separate jobs.  Rates: log(e_prev/e) /
log(h_prev/h), for the p-series log(e_prev/e) / log(p/p_prev).  The model problems, mesh
sequences, sweeps and the choices where the thesis is silent
(``interface.CONVERGENCE_CHOICES``): :mod:`hpfebe.scenes.interface`; the claims' verdicts:
:mod:`hpfebe.scenes.interface_readings`.
"""

from __future__ import annotations

import functools
import time
from dataclasses import replace

import numpy as np
import pandas as pd
from matplotlib.tri import Triangulation

from hpfebe.scenes import interface, interface_readings as rd
from hpfebe.suite import (ArtefactResult, Claim, from_config_sections, joint_claim,
                          new_figure, progress, published_ratio, published_table,
                          rate_claim, reference_slope, select_scenes, style_axes, timed)

ARTEFACTS = ("table_2_1", "table_2_2", "table_2_3", "table_2_4", "figure_2_1", "figure_2_2",
             "figure_2_3", "figure_2_4", "figure_work_precision_ch2")
#: independent computations: Example 1, and Example 2 with the timed runs of both (the
#: work-precision figure shares Example 2's sweep, the expensive one)
SCENES = {"smooth": ("table_2_1", "table_2_2", "figure_2_1", "figure_2_2"),
          "singular": ("table_2_3", "table_2_4", "figure_2_3", "figure_2_4",
                       "figure_work_precision_ch2")}

KEYS = ("series", "h_inv", "p")
TOL = {"l2_error": ("factor", 2.0), "h1_error": ("factor", 2.0),
       "l2_rate": ("abs", 0.15), "h1_rate": ("abs", 0.15)}
TOL_SINGULAR = dict(TOL, h1_rate=("abs", 0.1))
PUBLISHED = {"table_2_1": "table_2_1_nitsche_smooth_h_BE.csv",
             "table_2_2": "table_2_2_nitsche_smooth_h_FE.csv",
             "table_2_3": "table_2_3_nitsche_singular_BE.csv",
             "table_2_4": "table_2_4_nitsche_singular_FE.csv"}
L2_RATE_NOTE = ("tolerance 0.25 on L2: the thesis's own L2 rates on this non-nested "
                "sequence scatter by up to 0.5")
Params = interface.ConvergenceScene


def _published(name: str) -> pd.DataFrame:
    return published_table(PUBLISHED[name])


def _ratio(table, name, *cols) -> pd.Series:
    """reproduced / published of ``cols`` (rows in both tables, keys series, h_inv, p)."""
    return pd.concat([published_ratio(table, _published(name), KEYS, c) for c in cols])


def example_sweeps(prm: Params, example: str):
    """(h-sweep, p-sweep, seconds) of ``example``, with the companion columns (the BE
    trace energy error, the interpolation error of the exact u) of the tables."""
    def sweeps():
        return [pd.DataFrame(interface.sweep_rows(
            example, series, cases, [prm.lambda_nit], prm.alpha, prm.h_def, "", True,
            progress)) for series, cases in interface.sweep_cases(prm, example).items()]
    (h, p), seconds = timed(sweeps)
    return h, p, seconds


def sweep_memo(prm: Params):
    """example -> :func:`example_sweeps` of ``prm``, each computed once: the tables of an
    example and the work-precision figure use the same runs."""
    return functools.cache(lambda example: example_sweeps(prm, example))


def _meta(prm: Params, jit_s: float, **seconds) -> dict:
    return dict(jit_s=round(jit_s, 2), **{k: round(v, 2) for k, v in seconds.items()},
                lambda_nit=prm.lambda_nit, alpha=prm.alpha, h_def=prm.h_def)


def _notes(prm: Params) -> str:
    return (f"lambda_Nit = {prm.lambda_nit}, alpha = {prm.alpha:g}, h1 = {prm.h_def} length "
            "of the FE element on Gamma_I. BE part: domain errors in Omega2 of the Q_p "
            "equidistant interpolant (BE mesh size) of the representation-formula solution; "
            "FE part: domain errors in Omega1. Choices where the thesis is silent: "
            + " ".join(interface.CONVERGENCE_CHOICES))


def _table(name, table, part, claims, tol, meta, notes) -> ArtefactResult:
    nan_cols = ["l2_rate", "h1_rate"] + (["trace_energy_rate"] if part == "BE" else [])
    return ArtefactResult(name=name, table=table, published=PUBLISHED[name], keys=KEYS,
                          tolerances=tol, claims=claims, notes=notes,
                          meta=dict(meta, allow_nan_columns=nan_cols))


# ----------------------------------------------------------------------------- claims
def _factor_2_claim(table: pd.DataFrame, name: str, text: str) -> Claim:
    """All L2 and H1 errors within a factor 2 of the published ones."""
    return Claim(text, *rd.factor_2(_ratio(table, name, "l2_error", "h1_error")),
                 id="factor_2")


def _h_rates_claim(table: pd.DataFrame, part: str, p: int) -> Claim:
    """Last h-version rates ~p+1 (L2, tolerance 0.25) and ~p (H1, tolerance 0.15)."""
    return replace(joint_claim(
        f"{part} part, p={p}: rates ~{p + 1} (L2) and ~{p} (H1_0)",
        rate_claim("", rd.last(table, "h", p, "l2_rate"), p + 1, 0.25, "L2 rate"),
        rate_claim("", rd.last(table, "h", p, "h1_rate"), p, 0.15, "H1 rate"),
        note=L2_RATE_NOTE), id=f"rates_p{p}")


def _claims_2_3(t23: pd.DataFrame) -> list[Claim]:
    r_p = rd.last(t23, "p", None, "h1_rate")
    c_h = rate_claim("BE energy rate of the h-version ~0.66 (theory 2/3)",
                     rd.last(t23, "h", 1, "h1_rate"), 2 / 3, 0.08, "h-version H1 rate")
    c_p = rate_claim("BE energy rate of the p-version ~0.8 (theory 4/3 - 1/2 = 5/6)", r_p,
                     0.8, 0.1, "p-version H1 rate")
    c_p.evidence = rd.p_version(t23, _published("table_2_3"), r_p)
    return [replace(c_h, id="h_rate"), replace(c_p, id="p_rate"),
            Claim("p-version: better energy rate, worse L2 rate than the h-version in Omega2 "
                  "(0.8 vs 0.66, 1.19 vs 1.4)", *rd.p_vs_h(t23), id="p_vs_h")]


def _be_postprocessing_hypothesis(t23: pd.DataFrame, t24: pd.DataFrame,
                                  explains: tuple[str, ...]) -> Claim:
    """Hypothesis for the BE p-version rows of Table 2.3: the same discrete solution as
    the thesis's (its FE errors equal Table 2.4), another BE post-processing."""
    return Claim(
        "the BE rows of the p-version (p >= 2) differ because the thesis post-processed "
        "the same discrete solution differently (a post-processing we could not identify)",
        *rd.be_postprocessing(
            _ratio(t24, "table_2_4", "l2_error", "h1_error"),
            _ratio(t23[t23.series == "h"], "table_2_3", "l2_error", "h1_error"),
            _ratio(t23[(t23.series == "p") & (t23.p >= 2)], "table_2_3", "l2_error",
                   "h1_error")),
        kind="hypothesis", id="be_postprocessing", explains=explains)


def _claims_2_4(t24: pd.DataFrame, sg_h: pd.DataFrame, sg_p: pd.DataFrame) -> list[Claim]:
    return [replace(rate_claim("FE part H1 rate 1.0 for p = 1 (h-version)",
                               rd.last(t24, "h", 1, "h1_rate"), 1.0, 0.1,
                               "h-version FE H1 rate"), id="h_rate"),
            Claim("FE part: the p-version converges significantly faster than the h-version",
                  *rd.p_faster(t24, sg_h, sg_p), id="p_faster")]


def _l2_rate_hypothesis(table: pd.DataFrame, name: str) -> list[Claim]:
    """Hypothesis for the off L2 rates of Tables 2.1, 2.2 (none if no L2 rate is off)."""
    r = rd.l2_rate_scatter(table, _published(name), KEYS, TOL["l2_rate"][1])
    return [] if r is None else [Claim(
        "the off L2 rates are the scatter of the thesis's own L2 rates on the non-nested "
        "mesh sequence (there the thesis's rate lies farther from p+1 than ours)", *r,
        kind="hypothesis", id="l2_rate_scatter", explains=("cells:l2_rate",))]


# ----------------------------------------------------------------------------- figures
def solution_figure(prm: Params, example: str, meta: dict) -> ArtefactResult:
    """Figure 2.1 (smooth) or 2.3 (singular): U1 on the FE mesh (p = 1), the BE part by
    the representation formula on a mesh of Omega2; the colorbar range."""
    name, fe_h, be_h, title, top, extra = SOLUTION_FIGURES[example]
    model, sol, d2, vals = interface.solution_fields(example, fe_h, be_h, prm.lambda_nit)
    m = model.domain.mesh
    fig, ax = new_figure((6.0, 5.0))
    for mesh, v in ((m, sol.U1[:m.p.shape[1]]), (d2, vals)):
        tri = np.vstack([mesh.t[[0, 1, 2]].T, mesh.t[[0, 2, 3]].T])
        pc = ax.tripcolor(Triangulation(mesh.p[0], mesh.p[1], tri), v, shading="gouraud",
                          vmin=0.0, vmax=float(np.max(sol.U1)), cmap="viridis")
        if mesh is m:
            fig.colorbar(pc, ax=ax, shrink=0.8)
    a = model.be_mesh
    ax.plot(np.r_[a.a[:, 0], a.a[0, 0]], np.r_[a.a[:, 1], a.a[0, 1]], "w-", lw=1.2)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.text(0.02, 0.02, r"$\Omega_1$: FE ($h^{-1}$=%g), $\Omega_2$: BE ($h^{-1}$=%g), "
            "white: $\\partial\\Omega_2$" % (fe_h, be_h), transform=ax.transAxes, fontsize=7,
            color="w")
    lo, hi = float(min(sol.U1.min(), vals.min())), float(max(sol.U1.max(), vals.max()))
    return ArtefactResult(
        name=name, table=pd.DataFrame([dict(quantity="solution_min", value=lo),
                                       dict(quantity="solution_max", value=hi)]),
        figure=fig, claims=[Claim(f"solution range 0..{top:g} (colorbar of Figure "
                                  f"{name[-3:].replace('_', '.')})",
                                  bool(abs(lo) < 0.02 and abs(hi - top) < 0.02),
                                  f"computed range {lo:.4f}..{hi:.4f}", id="range")],
        notes=f"p = 1, FE h^-1 = {fe_h}, BE h^-1 = {be_h}, lambda_Nit = "
              f"{prm.lambda_nit:g}{extra}.", meta=meta)


SOLUTION_FIGURES = {
    "smooth": ("figure_2_1", 23, 24, "Example 1: u = (x+1)/((x+1)^2+(y+2)^2)", 0.5,
               "; Omega2 by the representation formula at the nodes of a mesh of size 1/48"),
    "singular": ("figure_2_3", 32, 36, "Example 2: u = r^(2/3) sin(2 theta/3)", 1.26, "")}
#: the error curves of a convergence figure: (part, norm, label); h-version solid with
#: circles, p-version dashed with squares, one colour per curve
_PARTS = (("be", "h1", "energy-err (BE)"), ("be", "l2", "L2-error (BE)"),
          ("fe", "h1", "energy-err (FE)"), ("fe", "l2", "L2-error (FE)"))


def _convergence_figure(h, pv, title, slopes):
    fig, ax = new_figure((7.0, 5.0))
    for df, tag, ls, mk in ((h, "h", "-", "o"), (pv, "p", "--", "s")):
        for part, norm, nm in _PARTS:
            ax.loglog(df.dof, df[f"{part}_{norm}"], ls=ls, marker=mk, ms=4,
                      label=f"{tag}: {nm}")
        ax.loglog(df.dof, df.be_energy, ls=ls, marker=mk, ms=3, alpha=0.6,
                  label=f"{tag}: trace energy |u-U2|_W (BE)")
    for s, y0, lab in slopes:
        reference_slope(ax, h.dof, y0, s, lab)
    style_axes(ax, "DOF", "error", title, title_size=9, legend=dict(fontsize=6, ncol=2))
    return fig


# ----------------------------------------------------------------------------- scenes
def smooth_scene(prm: Params, jit_s: float, sweeps) -> list[ArtefactResult]:
    """Example 1: Tables 2.1 (BE part), 2.2 (FE part), Figures 2.1, 2.2 (``sweeps``:
    :func:`sweep_memo`)."""
    sm_h, sm_p, t = sweeps("smooth")
    meta, (pf, pb) = _meta(prm, jit_s, smooth_s=t), prm.smooth.p_mesh
    out = []
    for name, part, h_col in (("table_2_1", "BE", "be_h_inv"), ("table_2_2", "FE", "fe_h_inv")):
        table = pd.DataFrame(interface.part_table(sm_h, part.lower(), h_col))
        claims = [_h_rates_claim(table, part, p) for p in prm.smooth.degrees]
        claims.append(_factor_2_claim(table, name, f"{part} errors reproduce the published "
                                      f"Table {name[-3:].replace('_', '.')}"))
        claims += _l2_rate_hypothesis(table, name)
        out.append(_table(name, table, part, claims, TOL, meta, _notes(prm) + (
            " Rates on the thesis's non-nested sequence (h^-1 = 2, 5, 11, 23, 47) scatter, "
            "as in the thesis. The first rate of each sweep is NaN (no previous mesh).")))
    h2 = sm_h[sm_h.p == 2]
    fig = _convergence_figure(h2, sm_p, f"Example 1: h-version p=2 vs p-version (FE "
                              f"h=1/{pf}, BE h=1/{pb})",
                              [(-1.0, h2.fe_h1.iloc[0], "DOF$^{-1}$"),
                               (-1.5, h2.fe_l2.iloc[0], "DOF$^{-3/2}$")])
    return out + [solution_figure(prm, "smooth", meta), ArtefactResult(
        name="figure_2_2", table=pd.concat([h2, sm_p], ignore_index=True), figure=fig,
        claims=[Claim("the p-version converges exponentially (smooth solution)",
                      *rd.exponential(sm_p), id="exponential")],
        notes=_notes(prm) + f" p-version on FE h^-1 = {pf} (75 elements), BE h^-1 = "
                            f"{pb} (24 elements), p1 = p2.", meta=meta)]


def singular_scene(prm: Params, jit_s: float, sweeps) -> list[ArtefactResult]:
    """Example 2: Tables 2.3 (BE part), 2.4 (FE part), Figures 2.3, 2.4, and the
    work-precision figure of both examples (:func:`work_precision`)."""
    sg_h, sg_p, t = sweeps("singular")
    meta, (qf, qb) = _meta(prm, jit_s, singular_s=t), prm.singular.p_mesh
    sg_all = pd.concat([sg_h, sg_p], ignore_index=True)
    t23 = pd.DataFrame(interface.part_table(sg_all, "be", "be_h_inv"))
    t24 = pd.DataFrame(interface.part_table(sg_all, "fe", "fe_h_inv"))
    c23, c24 = _claims_2_3(t23), _claims_2_4(t24, sg_h, sg_p)
    f2 = "errors within a factor 2 of the published table"
    c23 = c23 + [_factor_2_claim(t23, "table_2_3", f2), _be_postprocessing_hypothesis(
        t23, t24, ("p_rate", "p_vs_h", "factor_2") + tuple(
            f"cells:{c}[series=p]" for c in TOL_SINGULAR))]
    c24 = c24 + [_factor_2_claim(t24, "table_2_4", f2)]
    notes = _notes(prm) + (
        " p-version on FE h^-1 = 4, BE h^-1 = 6 (table headers; the caption of Figure 2.4 "
        "says 1/6, 1/8). BE p-version rows for p >= 2 differ from the thesis (see the "
        "claims); the FE rows are exact.")
    fig = _convergence_figure(sg_h, sg_p, "Example 2: h-version p=1 vs p-version "
                              f"(FE h=1/{qf}, BE h=1/{qb})",
                              [(-1 / 3, sg_h.be_h1.iloc[0], "DOF$^{-1/3}$"),
                               (-0.5, sg_h.fe_h1.iloc[0], "DOF$^{-1/2}$")])
    hyp = _be_postprocessing_hypothesis(t23, t24, ("p_vs_h",))
    return [_table("table_2_3", t23, "BE", c23, TOL_SINGULAR, meta, notes),
            _table("table_2_4", t24, "FE", c24, TOL_SINGULAR, meta, notes),
            solution_figure(prm, "singular", meta),
            ArtefactResult(name="figure_2_4", table=sg_all, figure=fig,
                           claims=[c23[2], c24[1], hyp], notes=_notes(prm), meta=meta),
            work_precision(prm, jit_s, sweeps)]


def work_precision(prm: Params, jit_s: float, sweeps) -> ArtefactResult:
    """Beyond the thesis: FE + BE energy error against wall time (assembly + solve) of
    the runs of ``sweeps`` (:func:`sweep_memo`), each timed up to ``timing_repeats``
    times (fewer once its timings sum to ``timing_budget_s``)."""
    t0 = time.perf_counter()
    rows = [r for example in interface.EXAMPLES for sweep in sweeps(example)[:2]
            for r in sweep.to_dict("records")]
    wp = pd.DataFrame(interface.work_precision_rows(prm, rows))
    fig, axs = new_figure((10.0, 4.5), 1, 2)
    for ax, name in zip(axs, interface.EXAMPLES):
        d = wp[wp.problem == name]
        for p, g in d[d.series == "h"].groupby("p"):
            ax.loglog(g.wall_time_s, g.fe_h1 + g.be_h1, "o-", ms=3, label=f"h-version p={p}")
        g = d[d.series == "p"]
        ax.loglog(g.wall_time_s, g.fe_h1 + g.be_h1, "s--", ms=3, label="p-version")
        style_axes(ax, "wall time (assembly + solve) [s], min of "
                   f"{wp.timings.min()}-{wp.timings.max()} timings",
                   "FE + BE energy error", name, title_size=9, legend=dict(fontsize=7))
    spread = float((wp.wall_time_max_s / wp.wall_time_s).max())
    return ArtefactResult(
        name="figure_work_precision_ch2",
        table=wp[["problem", "series", "p", "fe_h_inv", "be_h_inv", "dof", "fe_l2", "fe_h1",
                  "be_l2", "be_h1", "assembly_s", "solve_s", "wall_time_s",
                  "wall_time_max_s", "timings"]],
        figure=fig,
        claims=[Claim("beyond the thesis: for the smooth solution the p-version reaches a "
                      "given accuracy in less time than the h-version",
                      *rd.fastest(wp, interface.EXAMPLES), kind="beyond")],
        notes="Beyond the thesis. Wall time = assembly (FE stiffness, S_hat, coupling) + "
              "sparse LU solve of one run, single process, the minimum over "
              f"up to {prm.timing_repeats} repeats, fewer once a run's timings sum to "
              f"{prm.timing_budget_s:g} s (timings: their number; assembly_s, solve_s: "
              "minimum of each; "
              "wall_time_max_s: the slowest repeat; the largest slowest/fastest ratio is "
              f"{spread:.2f}); numba compilation excluded (measured separately: "
              f"{jit_s:.1f} s). Error = FE + BE energy error. The target error is 3 x the "
              "smallest error of the p-version.",
        meta=dict(_meta(prm, jit_s, total_s=time.perf_counter() - t0),
                  timing_repeats=prm.timing_repeats, timing_budget_s=prm.timing_budget_s,
                  timing_spread_max=round(spread, 3)))


SCENE_RUNS = {"smooth": smooth_scene, "singular": singular_scene}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """The artefacts of the scenes asked for (None: all; ``quick`` is unused:
    config/quick.yaml sets the sizes)."""
    prm = from_config_sections(Params, config, "ch2_convergence",
                               smooth=interface.SmoothParams,
                               singular=interface.SingularParams)
    names = select_scenes(SCENES, scenes, "ch2_convergence")
    jit_s, sweeps = interface.warm_up(prm), sweep_memo(prm)
    return [r for name in names for r in SCENE_RUNS[name](prm, jit_s, sweeps)]
