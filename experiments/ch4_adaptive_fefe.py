"""Figures 4.13-4.16 (Section 4.2.8, thesis lines 14920-15080): adaptive h-refinement for
FE/FE two-body frictional contact with the penalty method.

Scene (:mod:`hpfebe.scenes.adaptive_fefe`, with the choices where the thesis is silent,
``CHOICES``): slave [-1/2, 1/2] x [0, 2] with its top fixed, master [-2, 2] x [-2, 0] with
its bottom displaced by (0, 5e-4), E = 266926, nu = 0.29, Coulomb mu_f = 0.1, P1
triangles; penalty contact, semismooth Newton with load increments (Algorithm 4.1).
Each body has its own indicator (3.100) with the contact datum on Gamma_C and its own
marking (Algorithm 3.2, maximum strategy, theta = 0.9).  figure_4_13: the initial and
the adaptive meshes after steps 5, 10, 21, 36, 42; figure_4_14 / figure_4_15: indicator
in Omega_s / Omega_m against DOF, uniform vs adaptive; figure_4_16: the displacement
after the last step (VTU exports of the last meshes and fields).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe.scenes import adaptive_fefe as scene
from hpfebe.suite import (ArtefactResult, Claim, beats_uniform_claim, from_config,
                          new_figure, progress, slope_line, style_axes)

ARTEFACTS = ("figure_4_13", "figure_4_14", "figure_4_15", "figure_4_16")
NUMBA = False    # FE/FE only: runs beside the job that compiles the numba kernels


def concentration_claims(prm, meshes: list, t13: pd.DataFrame):
    """The two claims of Figure 4.13 (CHOICES) and the feature shares for the meta."""
    r, ev, shares, conc_ok, most_ok = prm.feature_radius, [], {}, True, True
    for body, (c, local, h0) in scene.feature_concentration(prm, meshes).items():
        conc_ok &= bool(c.enrichment >= prm.enrichment and
                        all(v <= h0 * prm.feature_h_ratio for v in local))
        most_ok &= bool(c.share >= prm.concentration_share)
        shares[body] = [c.share, c.area_share, c.enrichment]
        loc = ", ".join(f"({x:g},{y:g}): h {v:.3g}"
                        for (x, y), v in zip(scene.FEATURE_POINTS[body], local))
        ev.append(f"{body}: {c.n_new} new vertices, {100 * c.share:.1f}% of them within "
                  f"{r} of the features, a neighbourhood of {100 * c.area_share:.1f}% of "
                  f"the area (density {c.enrichment:.1f}x the mean); local h at the "
                  f"feature points (initial h {h0:.3g}): {loc}")
    hist = "; ".join(f"step {int(q.step)}: {100 * q.new_near_features_slave:.0f}% / "
                     f"{100 * q.new_near_features_master:.0f}%" for q in t13.itertuples()
                     if q.step > 0)
    ok, wider = [], []
    for body, w in scene.wider_radius(prm, meshes).items():
        ok.append(None if w is None else bool(w[1].enrichment >= prm.enrichment))
        wider.append(f"{body}: no new vertices" if w is None else
                     f"{body}: {100 * w[1].share:.1f}% of the new vertices within r = "
                     f"{w[0]:.3g} of the features ({w[0] / r:.2g} x feature_radius), a "
                     f"neighbourhood of {100 * w[1].area_share:.1f}% of the area, density "
                     f"{w[1].enrichment:.1f}x the mean")
    share = f"{100 * prm.concentration_share:.0f}%"
    return [
        Claim("the refinement concentrates in the zone of actual contact and near the "
              "points where the boundary conditions change (contact / no contact, no "
              "contact / Dirichlet)", bool(conc_ok),
              f"criterion: in both bodies the density of new vertices within {r} of the "
              f"features is >= {prm.enrichment}x the mean and every feature point is "
              f"refined to h <= {prm.feature_h_ratio} h0. " + "; ".join(ev),
              id="concentrates"),
        Claim("most of the refinement happens there", bool(most_ok),
              f"criterion: >= {share} of the new vertices of each body within {r} of the "
              f"features. Share slave / master after each shown step: {hist}" +
              ("" if most_ok else ". Later steps of the maximum strategy (theta = 0.9) "
               "also refine isolated elements away from the features once the singular "
               "zones are resolved (visible as scattered patches in the master)"),
              id="most"),
        Claim("the thesis's 'near' is wider than feature_radius: within the radius holding "
              f"{share} of each body's new vertices their density is still >= "
              f"{prm.enrichment}x the mean", None if None in ok else bool(all(ok)),
              "; ".join(wider) + ". A reading of the thesis's words (it gives no radius), "
              "not a cause derived from its computation", kind="hypothesis", id="wider",
              explains=("most",))], shares


def _plot_meshes(meshes, steps):
    ncol = min(len(steps), 3)
    nrow = int(math.ceil(len(steps) / ncol))
    fig = Figure(figsize=(4.2 * ncol, 4.0 * nrow))
    for i, k in enumerate(steps):
        ax = fig.add_subplot(nrow, ncol, i + 1)
        for m, col in zip(meshes[k], ("tab:blue", "tab:red")):
            ax.triplot(m.p[0], m.p[1], m.t.T, color=col, lw=0.3)
        ax.set_aspect("equal")
        ax.set_title("initial mesh" if k == 0 else f"after refinement step {k}", fontsize=9)
        ax.set_xticks([]), ax.set_yticks([])
    fig.suptitle("Figure 4.13: adaptive meshes (slave blue, master red)")
    fig.tight_layout()
    return fig


def _plot_decay(ad, un, body, fig_no):
    fig, ax = new_figure((6, 4.5))
    dcol, ecol = f"dof_{body}", f"eta_{body}"
    ax.loglog(un[dcol], un[ecol], "s-", label="uniform")
    ax.loglog(ad[dcol], ad[ecol], "o-", ms=3, label="adaptive")
    d0, e0 = float(un[dcol].iloc[0]), float(un[ecol].iloc[0])
    dd = np.array([d0, max(float(un[dcol].max()), float(ad[dcol].max()))])
    for s, ls in ((-0.5, "k--"), (-0.25, "k:")):
        slope_line(ax, dd, s, (d0, e0), ls, lw=0.8, label=f"DOF^{s}")
    style_axes(ax, f"DOF ({body})", "indicator (3.100)",
               f"Figure {fig_no}: error indicator in $\\Omega_{body[0]}$", legend={})
    fig.tight_layout()
    return fig


def _plot_displacement(pr, res):
    fig, axes = new_figure((11, 5), 1, 2)
    for j, (ax, comp) in enumerate(zip(axes, ("x", "y"))):
        vals = [b.nodal_displacement(u)[j] for b, u in
                ((pr.slave, res.u_slave), (pr.master, res.u_master))]
        lo, hi = min(v.min() for v in vals), max(v.max() for v in vals)
        for b, v in zip((pr.slave, pr.master), vals):
            tpc = ax.tripcolor(b.mesh.p[0], b.mesh.p[1], b.mesh.t.T, v, shading="gouraud",
                               vmin=lo, vmax=hi, cmap="viridis")
        fig.colorbar(tpc, ax=ax, shrink=0.8, format="%.1e")
        ax.set_aspect("equal")
        ax.set_title(f"{comp}-component of the displacement")
    fig.suptitle("Figure 4.16: displacements after the last adaptive refinement step")
    fig.tight_layout()
    return fig


VTU_NOTE = (" VTU files for ParaView (final adaptive and uniform meshes, displacement, "
            "indicator): figure_4_16_<adaptive|uniform>_final_<slave|master>.vtu.")


def figure_4_13(prm, hist, notes, meta) -> ArtefactResult:
    meshes = hist.meshes
    steps = prm.shown_steps(len(meshes))
    t13 = pd.DataFrame(scene.concentration_rows(prm, hist, steps))
    claims, shares = concentration_claims(prm, meshes, t13)
    return ArtefactResult(
        name="figure_4_13", table=t13, figure=_plot_meshes(meshes, steps), claims=claims,
        notes=notes + " Meshes shown: steps " + ", ".join(map(str, steps)) +
        " (thesis: initial, 5, 10, 21, 36, 42). Features: the contact segment "
        "[-1/2, 1/2] x {0}, the slave corners (+-1/2, 2), the master corners (+-2, -2); "
        "new_near_features_* = share of the vertices added since the initial mesh within "
        f"{prm.feature_radius} of them." + VTU_NOTE,
        meta=dict(meta, conforming=bool(t13["conforming"].all()), feature_shares=shares))


def decay_result(body, fig_id, fig_no, ad, un, rates, notes, meta) -> ArtefactResult:
    """Figure 4.14 (slave) / 4.15 (master): indicator vs DOF, adaptive and uniform."""
    (ra, ru), dcol, ecol = rates, f"dof_{body}", f"eta_{body}"
    beats = beats_uniform_claim(
        f"adaptive refinement gives a smaller indicator in Omega_{body[0]} than uniform "
        "refinement at equal DOF", ad[dcol], ad[ecol], un[dcol], un[ecol])
    beats = dataclasses.replace(beats, evidence=beats.evidence + (
        f". Observed rates (slope of log eta vs log DOF): adaptive {ra:.3f} (last third), "
        f"uniform {ru:.3f} (last 3 meshes)."), id="beats")
    newton = Claim("Newton converges at every load step of every refinement step",
                   bool(ad["newton_converged"].all() and un["newton_converged"].all()),
                   f"iterations per load step: adaptive max {int(ad['newton_max'].max())}, "
                   f"uniform max {int(un['newton_max'].max())}; total per refinement step "
                   f"{int(ad['newton_total'].min())}-{int(ad['newton_total'].max())}",
                   kind="beyond", id="newton")
    cols = ["mode", "step", dcol, ecol, "newton_per_load_step", "newton_total",
            "newton_max", "newton_converged", f"elements_{body}", f"marked_{body}",
            f"h_min_{body}", "dof", "n_stick", "n_slip", "n_open", "t_solve_s",
            "t_estimate_s"]
    return ArtefactResult(
        name=fig_id, table=pd.concat([ad, un], ignore_index=True)[cols],
        figure=_plot_decay(ad, un, body, fig_no), claims=[beats, newton],
        notes=notes + f" Indicator = (sum_K eta_K^2)^(1/2) over Omega_{body[0]}, vs that "
        "body's DOF. Uniform: red refinement of every triangle of both bodies until each "
        "body's DOF exceeds its last adaptive DOF. marked_*: cells marked by the maximum "
        "strategy (0 in the uniform run). Reference slopes DOF^-1/2 (optimal for P1) and "
        "DOF^-1/4.",
        meta=dict(meta, rate_adaptive=ra, rate_uniform=ru,
                  eta_adaptive_last=float(ad[ecol].iloc[-1])))


def figure_4_16(prm, hist, exports, notes, meta) -> ArtefactResult:
    pr, res = hist.state
    t16 = pd.DataFrame(scene.displacement_rows(pr, res))
    pen, states = float(-res.g_n[res.weights > 0].min()), res.state_names
    return ArtefactResult(
        name="figure_4_16", table=t16, figure=_plot_displacement(pr, res),
        claims=[Claim("the slave is pushed up and compressed by the master (u_y between 0 "
                      "at the slave's top and 5e-4 at the master's bottom)",
                      bool(t16["uy_min"].min() >= -1e-12 and
                           t16["uy_max"].max() <= prm.u_master * (1 + 1e-9)),
                      f"u_y range slave [{t16.uy_min[0]:.3e}, {t16.uy_max[0]:.3e}], master "
                      f"[{t16.uy_min[1]:.3e}, {t16.uy_max[1]:.3e}]; max penetration "
                      f"{pen:.3e}; final contact states: {states.count('stick')} stick, "
                      f"{states.count('slip')} slip, {states.count('open')} open",
                      kind="beyond", id="uy_range")],
        notes=notes + f" Fields after adaptive refinement step {prm.n_refinements}." +
        VTU_NOTE, meta=dict(meta, max_penetration=pen), exports=exports)


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    """Figures 4.13-4.16 (``quick`` is unused: config/quick.yaml sets the sizes)."""
    prm = from_config(scene.AdaptiveStudy, config, scene="ch4_adaptive_fefe")
    (ad, ad_hist), (un, un_hist), meta = scene.adaptive_and_uniform(prm, progress)
    notes = scene.notes(prm, ad, un)
    rates = {b: scene.observed_rates(ad, un, b) for b in scene.BODIES}
    exports = {**scene.vtu_meshes("adaptive_final", *ad_hist.state, ad_hist.eta),
               **scene.vtu_meshes("uniform_final", *un_hist.state, un_hist.eta)}
    ad, un = pd.DataFrame(ad), pd.DataFrame(un)
    return [figure_4_13(prm, ad_hist, notes, meta), *(
        decay_result(b, f"figure_4_{n}", f"4.{n}", ad, un, rates[b], notes, meta)
        for b, n in (("slave", 14), ("master", 15))), figure_4_16(prm, ad_hist, exports,
                                                                  notes, meta)]
