"""Figures 3.2-3.9: adaptive h-BEM for contact with Coulomb friction (Section 3.3.5).

Thesis lines 10840-11180.  One elastic body Omega = [-1, 1]^2 (E = 266926, nu = 0.29,
plane strain), u = 0 on Gamma_D = [-1, 1] x {1}, Gamma_C = the other three sides
(Gamma_N empty), Coulomb friction mu_f = 0.1, penalty formulation (3.95) solved by
Newton (:func:`hpfebe.contact.solve_friction`), residual indicator (3.107)

    eta_I^2 = h_I ||P_n n + P_t t - S_hat U||^2_{L2(I cap Gamma_C)}
            + h_I ||d/ds (V Psi - (K + 1/2) U)||^2_{L2(I)}

(:func:`hpfebe.adaptivity.lame_contact_indicators`, the contact datum from
the law of :mod:`hpfebe.constitutive.laws`) and Algorithm 3.2 with the maximum criterion
eta_I >= 0.9 max eta (:func:`hpfebe.adaptivity.adapt`), p = 1 (V_h continuous piecewise
linear (3.92), W_h piecewise constant (3.93)), initial mesh four elements per side
(Fig. 3.3), six refinement steps (seven solves).

* Example 1 (Figs. 3.2-3.6): rigid line y = -1 + d below the body (gap g = -d on the
  bottom side, constraint U_n <= g with the outward normal).  The text says d = 0.6e-4,
  the colorbars of Fig. 3.5 reach u_y = 5.922e-4: both are run.  Fig. 3.6:
  err(U) = | |||U|||_B - |||U_190|||_B |, U_190 the uniform solution with 190 DOF
  (32 elements per side), for uniform and adaptive refinement; also against a finer
  uniform reference, and the error |||U_ref - U|||_B itself
  (:func:`hpfebe.adaptivity.true_error`).
* Example 2 (Figs. 3.7-3.9): rigid segment x = -1 + d, y in [-1/2, 1/2], d = 6e-4
  (gap g = -d on that part of the left side).
* Figs. 3.5 / 3.9: displacements at the nodes of an auxiliary grid by the
  representation formula (1.2) (interior nodes; on the boundary the trace U itself).

|||U|||_B of (3.105) for a discrete solution: (<W U, U> + <V Psi, Psi>
+ eps_n ||p_n||^2_{L2(Gamma_C)} + eps_t ||t_t||^2_{L2(Gamma_C)})^(1/2)
(:func:`hpfebe.adaptivity.norm_B`).

The scene (geometry, obstacles, the solve on one mesh, the adaptive loop, the reference)
is :mod:`hpfebe.scenes.adaptive_bem`; the claims are in :mod:`.claims`, the figures in
:mod:`.figures`.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pandas as pd

from hpfebe.io import boundary_vtu
from hpfebe.scenes import adaptive_bem as scene
from hpfebe.suite import ArtefactResult, Claim, from_config, timed

from .claims import (claim_adaptive, colorbar_claims, example2_claims, newton_claim,
                     refinement_claims, units_explanation)
from .figures import fig_error, fig_geometry, fig_initial_mesh, fig_interior, fig_mesh_sequence

ARTEFACTS = ("figure_3_2", "figure_3_3", "figure_3_4", "figure_3_5", "figure_3_6",
             "figure_3_7", "figure_3_8", "figure_3_9")

log = logging.getLogger(__name__)

CHOICES = (
    "Penalty parameters (3.110) eps_n >= C h_max, eps_t >= C F h_max: one fixed pair for "
    "the whole refinement sequence, eps_n = eps_t = C_pen h_max(T_0) with h_max(T_0) = 0.5 "
    "(it then satisfies (3.110) on every refined mesh, and all meshes approximate the same "
    "penalty solution u^eps, which err(U) presupposes).  In the solver's convention the "
    "tangential law is t_t = (1/eps_t) U_t (stick), so its eps_t is the thesis's eps_t / F "
    "and (3.110) reads eps_t >= C h_max for it too.  C_pen = 1e-7 (the smallest C_eps of "
    "Table 3.1; with it the Fig. 3.5 / 3.9 colorbar ranges are met within 0.6 % / 1.5 % of "
    "the published span, with 1e-6 the penetration lowers max u_y by 6 %; both reported).",
    "One load step (the obstacle displacement d is a geometric gap; no load history).",
    "Gap outside the obstacle: \"far\", g = 1 (no contact possible).",
    "|||U|||_B of (3.105) for a discrete solution: (<W U, U> + <V Psi, Psi> "
    "+ eps_n ||P_n||^2_{L2(Gamma_C)} + eps_t ||P_t||^2_{L2(Gamma_C)})^(1/2) (the energy "
    "norms of W and V as realisations of the H~^(1/2) and H^(-1/2) norms, the penalty "
    "terms at the solver's Gauss points; eps_t F^(-1) of the thesis = solver's eps_t).",
    "Contact datum of (3.107): P_n n + P_t t = -p_n n - t_t t evaluated from U at the "
    "indicator's quadrature points (one load step: t_t = clip(U_t / eps_t, +-mu_f p_n)).",
    "Indicator variants.  (3.107) adds h_I ||P_n n + P_t t - S_hat U||^2 (a traction, units "
    "of stress) and h_I ||d/ds (V Psi - (K + 1/2) U)||^2 (a strain); with E = 266926 the "
    "second is ~1e-11 of the first (initial mesh: 14.2^2 against (5.5e-5)^2), so the "
    "literal indicator (\"literal\") sees only the displacement error, and the traction "
    "error ||psi - Psi||_V, half of |||.|||_B, is never targeted.  \"balanced\" multiplies "
    "the consistency term by E' = E / (1 - nu^2) (then eta^2 / E' estimates both halves of "
    "|||.|||_B^2 in the same units).  Both are run; figures of meshes and fields use the "
    "first of ``indicators`` (default \"literal\").",
    "Error of Fig. 3.6.  The thesis's err(U) = | |||U|||_B - |||U_190|||_B | is a "
    "difference of norms (it crosses zero when |||U|||_B is not monotone, as under adaptive "
    "refinement here).  Also computed: the error itself, |||U_ref - U|||_B without the "
    "penalty terms, (<W e_u, e_u> + <V e_psi, e_psi>)^(1/2), on the common refinement of "
    "the uniform reference mesh and the last adaptive meshes, on which U_ref is computed "
    "and into which every (nested, bisection-refined) P1/P0 solution embeds exactly.  "
    "\"Adaptive better\" means below 0.95 x the uniform error, log-log interpolated at "
    "the same DOF.",
    "Deformed configurations are drawn magnified by ``magnification`` (default 1e3, not "
    "the thesis's 1e4: with |u| ~ 6e-4, 1e4 moves the boundary by 3 body widths).",
    "Auxiliary grid: ``grid`` x ``grid`` nodes on [-1, 1]^2.",
)

# published colorbar ranges (report/published/scalars.csv, section 3.3.5)
PUBLISHED = {
    "example1": {"ux": (-0.1243e-3, 0.1243e-3), "uy": (0.0, 0.5922e-3)},
    "example2": {"ux": (0.0, 0.6561e-3), "uy": (-0.2003e-3, 0.1762e-3)},
}

QUICK = dict(n_steps=3, n_reference=32, grid=15, n_steps_extended=0)


def params(config: dict | None = None, quick: bool = False) -> scene.AdaptiveBEMScene:
    """The parameter object of the config section (``QUICK`` under it when quick)."""
    section = {**(QUICK if quick else {}), **(config or {})}
    return from_config(scene.AdaptiveBEMScene, section, scene="ch3_adaptive_bem")


def final_vtu(recs):
    """meshio mesh of the last adaptive boundary mesh with U (V_hp^2) and the indicator."""
    st = recs[-1]["state"]
    op = st["op"]
    mesh = boundary_vtu(op.mesh, op.V_space, {"displacement": st["U"]}, d=2)
    elem = mesh.cell_data["element"][0]
    mesh.cell_data["eta"] = [np.asarray(recs[-1]["eta"], dtype=float)[elem]]
    return mesh


def _range_rows(example, d, C, u, name):
    pub = PUBLISHED[name]
    rows = []
    for c, comp in enumerate(("ux", "uy")):
        lo, hi = float(u[..., c].min()), float(u[..., c].max())
        plo, phi = pub[comp]
        span = phi - plo
        rows.append(dict(example=example, quantity=f"{comp}_range", d=d, C_pen=C,
                         published_min=plo, published_max=phi, min=lo, max=hi,
                         rel_dev_max=abs(hi - phi) / abs(span),
                         rel_dev_min=abs(lo - plo) / abs(span)))
    return rows


def _interior_fields(s: scene.Setup, ex1, ex1_alt, recs2):
    """Grid displacements of the last meshes (Figs. 3.5, 3.9) and their colorbar ranges:
    Example 1 for every d (the first is d_main), with C_pen_alt, Example 2."""
    prm = s.prm
    runs = [(1, d, prm.C_pen, ex1[(d, s.primary)]) for d in prm.example1_d]
    runs += [(1, s.d_main, prm.C_pen_alt, ex1_alt)] if ex1_alt is not None else []
    runs += [(2, prm.example2_d, prm.C_pen, recs2)]
    fields = [scene.grid_displacement(recs[-1]["state"], prm.grid) for *_, recs in runs]
    ranges = pd.DataFrame([r for (ex, d, C, _), (_, _, u) in zip(runs, fields)
                           for r in _range_rows(ex, d, C, u, f"example{ex}")])
    ranges.insert(1, "indicator", s.primary)
    return ranges, fields[0], fields[-1]


# ----------------------------------------------------------------------------- run
def _notes(s: scene.Setup, ref_mesh, ref, dof190, times) -> str:
    prm = s.prm
    return ("Penalty parameters (not in the thesis): eps_n = eps_t = C_pen h_max(T_0) = "
            f"{prm.C_pen:g} x {s.h0:g} = {s.eps:g}, fixed over the refinement (satisfies "
            f"(3.110) on every mesh); sensitivity run with C_pen = {prm.C_pen_alt:g}. "
            f"Plane {prm.plane}, one load step, p = 1, theta = {prm.theta}, "
            f"{prm.n_steps} refinement steps. Indicator variants: "
            + ", ".join(f"{v} (consistency weight {s.w[v]:.6g})" for v in s.variants)
            + f"; figures of meshes and fields use '{s.primary}'. U_190: uniform, "
            f"{prm.n_190} elements per side ({dof190} DOF); reference for err_ref and "
            f"err_true: {ref_mesh.n_elements} elements ({ref['ndof']} DOF), the common "
            f"refinement of the uniform mesh with {prm.n_reference} elements per side "
            "and the last adaptive meshes (every solution embeds exactly). Figure 3.6 "
            "table: n is NaN for adaptive rows and step is NaN for uniform rows; rows with "
            f"beyond_thesis = True are adaptive steps after step {prm.n_steps} (longer "
            "runs, not in the thesis). "
            f"Wall times: Example 1 adaptive runs {times['ex1_adaptive']:.1f} s, Example 1 "
            f"total {times['ex1']:.1f} s, Example 2 {times['ex2']:.1f} s. "
            "Choices where the thesis is silent: " + " ".join(CHOICES))


def _error_table(s: scene.Setup, ext):
    """Fig. 3.6: the thesis's err(U) = | |||U|||_B - |||U_190|||_B |, the same against the
    finer reference and the error |||U_ref - U|||_B itself (:func:`scene.error_rows`);
    returns (errtab, ref, ref_mesh, dof190)."""
    rows, B190, ref, ref_mesh, dof190 = scene.error_rows(s, ext)
    errtab = pd.DataFrame(rows)
    errtab["err"] = (errtab.norm_B - B190).abs()
    errtab["err_ref"] = (errtab.norm_B - ref["norm_B"]).abs()
    errtab["norm_B_190"] = B190
    errtab["norm_B_reference"] = ref["norm_B"]
    errtab["dof_190"] = dof190
    errtab["dof_reference"] = ref["ndof"]
    errtab = errtab[["refinement", "dof", "err", "err_ref", "err_true", "norm_B",
                     "norm_B_190", "norm_B_reference", "dof_190", "dof_reference", "n",
                     "step", "beyond_thesis", "newton_iterations", "wall_time_s"]]
    return errtab, ref, ref_mesh, dof190


def _tables(s: scene.Setup, ex1, ex1_alt, ex2):
    """Steps tables of both examples, the geometry table and the initial mesh table."""
    prm = s.prm
    rows = [r for (d, v) in ex1 for r in scene.steps_rows(ex1[(d, v)], s.eps, d, 1, v)]
    if ex1_alt is not None:
        rows += scene.steps_rows(ex1_alt, s.eps_alt, s.d_main, 1, s.primary)
    steps1 = pd.DataFrame(rows)
    steps2 = pd.DataFrame([r for v in s.variants
                           for r in scene.steps_rows(ex2[v], s.eps, prm.example2_d, 2, v)])
    geo = [dict(example=ex, d=d, E=prm.E, nu=prm.nu, plane=prm.plane, mu_f=prm.mu_f,
                eps_n=s.eps, eps_t=s.eps, C_pen=prm.C_pen, h_max0=s.h0)
           for ex, d in [(1, d) for d in prm.example1_d] + [(2, prm.example2_d)]]
    mesh0 = scene.initial_mesh(prm.n_initial)
    init = pd.DataFrame(dict(element=np.arange(mesh0.n_elements), x0=mesh0.a[:, 0],
                             y0=mesh0.a[:, 1], x1=mesh0.b[:, 0], y1=mesh0.b[:, 1],
                             label=mesh0.labels, length=mesh0.lengths))
    return steps1, steps2, pd.DataFrame(geo), init


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    prm = params(config, quick)
    s = scene.setup(prm)
    jit_s = timed(lambda: scene.solve_on(scene.initial_mesh(2), prm,  # compile
                                         scene.gap_function(1, 1e-4), s.eps))[1]

    t_run = time.perf_counter()
    ext, ex1, ex1_alt = scene.run_example1(s)
    times = dict(ex1_adaptive=time.perf_counter() - t_run)
    errtab, ref, ref_mesh, dof190 = _error_table(s, ext)
    times["ex1"] = time.perf_counter() - t_run
    ex2, times["ex2"] = timed(lambda: {v: scene.adaptive_run(
        2, prm.example2_d, prm, s.eps, prm.n_steps, weight=s.w[v], memo=s.memo)
        for v in s.variants})
    ranges, field1, field2 = _interior_fields(s, ex1, ex1_alt, ex2[s.primary])
    run_s = time.perf_counter() - t_run

    all_recs = [r for rs in list(ex1.values()) + list(ext.values()) for r in rs] + \
        [r for rs in ex2.values() for r in rs] + (ex1_alt or [])
    claims = dict(newton=newton_claim(all_recs, ref), refine=refinement_claims(s, ex1),
                  adaptive=[claim_adaptive(errtab, v, ref["ndof"], prm.n_steps)
                            for v in s.variants])
    n_ext = max(prm.n_steps, prm.n_steps_extended)
    if n_ext > prm.n_steps:
        claims["adaptive"] += [claim_adaptive(errtab, v, ref["ndof"], n_ext,
                                               beyond=True) for v in s.variants]
    units = units_explanation(s, ext, errtab, claims["adaptive"])
    claims["adaptive"] += [units] if units is not None else []
    claims["d"], claims["range1"], claims["range2"], best_d = colorbar_claims(s, ranges)
    claims["ex2"], claims["geo2"] = example2_claims(s, ex2)
    steps1, steps2, geo, init = _tables(s, ex1, ex1_alt, ex2)
    p1 = steps1[(steps1.indicator == s.primary) & (steps1.d == s.d_main)
                & (steps1.eps_n == s.eps)]
    p2 = steps2[steps2.indicator == s.primary]
    meta = dict(jit_s=round(jit_s, 3), run_s=round(run_s, 3), eps_n=s.eps, eps_t=s.eps,
                eps_alt=s.eps_alt, C_pen=prm.C_pen, n_steps=prm.n_steps,
                indicator_primary=s.primary, consistency_weights=s.w,
                example1_s=round(times["ex1"], 3), example2_s=round(times["ex2"], 3),
                newton_iterations_example1=[int(x) for x in p1.newton_iterations],
                newton_iterations_example2=[int(x) for x in p2.newton_iterations],
                dof_example1=[int(x) for x in p1.dof], dof_example2=[int(x) for x in p2.dof],
                dof_reference=int(ref["ndof"]), d_matching_colorbars=best_d,
                allow_nan_columns=["n", "step"])
    tables = dict(steps1=steps1, steps2=steps2, geo=geo, init=init, errtab=errtab,
                  ranges=ranges, dof0=int(p1.dof.iloc[0]), ref_ndof=ref["ndof"],
                  dof190=dof190)
    out = _artefacts(s, tables, claims, (ex1[(s.d_main, s.primary)], ex2[s.primary]),
                     (field1, field2), _notes(s, ref_mesh, ref, dof190, times), meta)
    log.info("ch3_adaptive_bem: run %.1f s (example 1 %.1f s, example 2 %.1f s)", run_s,
             times["ex1"], times["ex2"])
    return out


def _artefacts(s: scene.Setup, tb, cl, recs, fields, notes, meta):
    """The eight ArtefactResults (tables, figures, claims)."""
    prm, mag = s.prm, s.prm.magnification
    recs1, recs2 = recs
    (X, Y, u1), (X2, Y2, u2) = fields
    d_main, d2 = s.d_main, prm.example2_d
    mesh0 = scene.initial_mesh(prm.n_initial)
    nonan = dict(meta, allow_nan_columns=[])
    geo, ranges = tb["geo"], tb["ranges"]
    t1 = "Example 1: rigid line y = -1 + d below the body"
    t2 = "Example 2: rigid segment x = -1 + d, |y| <= 1/2"
    return [
        ArtefactResult(name="figure_3_2", table=geo,
                       figure=fig_geometry(1, d_main, "Fig. 3.2 " + t1),
                       claims=list(cl["d"]), notes=notes, meta=nonan),
        ArtefactResult(name="figure_3_3", table=tb["init"], figure=fig_initial_mesh(mesh0),
                       claims=[Claim(text="Initial mesh: four straight elements per side",
                                     holds=bool(mesh0.n_elements == 4 * 4),
                                     evidence=f"{mesh0.n_elements} elements, "
                                              f"{tb['dof0']} free DOF (the "
                                              "thesis's coarsest uniform mesh: 22)",
                                     id="initial_mesh")],
                       notes=notes, meta=nonan),
        ArtefactResult(name="figure_3_4", table=tb["steps1"],
                       figure=fig_mesh_sequence(recs1, mag, f"Fig. 3.4 (d = {d_main:g}, "
                                                f"{s.primary} indicator)"),
                       claims=cl["refine"] + [cl["newton"]], notes=notes,
                       meta=nonan, exports={"final_mesh": final_vtu(recs1)}),
        ArtefactResult(name="figure_3_5", table=ranges[ranges.example == 1]
                       .reset_index(drop=True),
                       figure=fig_interior(X, Y, u1, mag, f"Fig. 3.5: Example 1, d = "
                                           f"{d_main:g}, after step {prm.n_steps}"),
                       claims=[cl["range1"]] + cl["d"], notes=notes, meta=nonan),
        ArtefactResult(name="figure_3_6", table=tb["errtab"],
                       figure=fig_error(tb["errtab"], f"Fig. 3.6: Example 1, d = "
                                        f"{d_main:g}; reference {tb['ref_ndof']} DOF; "
                                        f"adaptive steps > {prm.n_steps} and uniform "
                                        f"> {tb['dof190']} DOF are beyond the thesis"),
                       claims=cl["adaptive"], notes=notes, meta=meta),
        ArtefactResult(name="figure_3_7", table=geo[geo.example == 2].reset_index(drop=True),
                       figure=fig_geometry(2, d2, "Fig. 3.7 " + t2), claims=[cl["geo2"]],
                       notes=notes, meta=nonan),
        ArtefactResult(name="figure_3_8", table=tb["steps2"],
                       figure=fig_mesh_sequence(recs2, mag, f"Fig. 3.8 (d = {d2:g}, "
                                                f"{s.primary} indicator)"),
                       claims=cl["ex2"] + [cl["newton"]], notes=notes, meta=nonan,
                       exports={"final_mesh": final_vtu(recs2)}),
        ArtefactResult(name="figure_3_9", table=ranges[ranges.example == 2]
                       .reset_index(drop=True),
                       figure=fig_interior(X2, Y2, u2, mag, f"Fig. 3.9: Example 2, d = "
                                           f"{d2:g}, after step {prm.n_steps}"),
                       claims=[cl["range2"]], notes=notes, meta=nonan),
    ]
