"""Figures 3.2-3.9: adaptive h-BEM for contact with Coulomb friction (Section 3.3.5,
thesis lines 10840-11180; the scene: :mod:`hpfebe.scenes.adaptive_bem`).

Penalty formulation (3.95), residual indicator (3.107)

    eta_I^2 = h_I ||P_n n + P_t t - S_hat U||^2_{L2(I cap Gamma_C)}
            + h_I ||d/ds (V Psi - (K + 1/2) U)||^2_{L2(I)},

Algorithm 3.2 with eta_I >= 0.9 max eta, p = 1, four elements per side (Fig. 3.3), six
refinement steps.  Example 1 (Figs. 3.2-3.6): rigid line y = -1 + d; the text says
d = 0.6e-4, the colorbars of Fig. 3.5 reach u_y = 5.922e-4: both are run.  Fig. 3.6:
err(U) = | |||U|||_B - |||U_190|||_B | ((3.105), U_190 uniform with 190 DOF), also against
a finer reference, and the error |||U_ref - U|||_B itself.  Example 2 (Figs. 3.7-3.9):
rigid segment x = -1 + d, |y| <= 1/2, d = 6e-4.  Figs. 3.5 / 3.9: displacements on a
grid by the representation formula (1.2).  Claims: :mod:`.claims`; figures:
:mod:`.figures`; the choices where the thesis is silent: ``scene.CHOICES``.
"""

from __future__ import annotations

import logging
import time

import pandas as pd

from hpfebe.scenes import adaptive_bem as scene
from hpfebe.suite import ArtefactResult, Claim, deformed_field_figure, from_config, timed

from .claims import (claim_adaptive, colorbar_claims, example2_claims, newton_claim,
                     refinement_claims, units_explanation)
from .figures import fig_error, fig_geometry, fig_initial_mesh, fig_mesh_sequence

ARTEFACTS = ("figure_3_2", "figure_3_3", "figure_3_4", "figure_3_5", "figure_3_6",
             "figure_3_7", "figure_3_8", "figure_3_9")

log = logging.getLogger(__name__)

QUICK = dict(n_steps=3, n_reference=32, grid=15, n_steps_extended=0)


def params(config: dict | None = None, quick: bool = False) -> scene.AdaptiveBEMScene:
    """The parameter object of the config section (``QUICK`` under it when quick)."""
    section = {**(QUICK if quick else {}), **(config or {})}
    return from_config(scene.AdaptiveBEMScene, section, scene="ch3_adaptive_bem")


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
            "Choices where the thesis is silent: " + " ".join(scene.CHOICES))


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    prm = params(config, quick)
    s = scene.setup(prm)
    jit_s = timed(lambda: scene.solve_on(scene.initial_mesh(2), prm,  # compile
                                         scene.gap_function(1, 1e-4), s.eps))[1]

    t_run = time.perf_counter()
    ext, ex1, ex1_alt = scene.run_example1(s)
    times = dict(ex1_adaptive=time.perf_counter() - t_run)
    rows, ref, ref_mesh, dof190 = scene.error_rows(s, ext)
    errtab = pd.DataFrame(rows)
    times["ex1"] = time.perf_counter() - t_run
    ex2, times["ex2"] = timed(lambda: {v: scene.adaptive_run(
        2, prm.example2_d, prm, s.eps, prm.n_steps, weight=s.w[v], memo=s.memo)
        for v in s.variants})
    rows, field1, field2 = scene.interior_fields(s, ex1, ex1_alt, ex2[s.primary])
    ranges = pd.DataFrame(rows)
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
    steps1, steps2, geo, init = map(pd.DataFrame, scene.tables(s, ex1, ex1_alt, ex2))
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
                       meta=nonan, exports=scene.final_exports(recs1)),
        ArtefactResult(name="figure_3_5", table=ranges[ranges.example == 1]
                       .reset_index(drop=True),
                       figure=deformed_field_figure(X, Y, u1, mag, f"Fig. 3.5: Example 1, d "
                                                    f"= {d_main:g}, after step {prm.n_steps}"),
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
                       exports=scene.final_exports(recs2)),
        ArtefactResult(name="figure_3_9", table=ranges[ranges.example == 2]
                       .reset_index(drop=True),
                       figure=deformed_field_figure(X2, Y2, u2, mag, f"Fig. 3.9: Example 2, d "
                                                    f"= {d2:g}, after step {prm.n_steps}"),
                       claims=[cl["range2"]], notes=notes, meta=nonan),
    ]
