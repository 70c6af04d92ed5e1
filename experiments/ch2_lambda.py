"""Chapter 2, Section 2.2.5, Example 3: the choice of lambda_Nit (Figures 2.5-2.12).

For lambda_Nit in {1, 5, 10, 20}: Example 1 (smooth), h-version p1 = p2 = 1, 2, 3, errors
against the mesh size (Figures 2.5-2.8); Example 2 (singular), h-version p = 1 and p-version
on FE h^-1 = 4 / BE h^-1 = 6, errors against DOF (Figures 2.9-2.12).  The coupled system of
each mesh is assembled once and solved for all four lambda_Nit
(:func:`hpfebe.scenes.interface.lambda_sweep`).  Claims (thesis lines ~3940-4100):
lambda = 1 does not converge for p = 1; lambda = 5 gives a reduced rate for p = 3
(smooth); the convergence rates for lambda = 10 and 20 are almost the same, "i.e. the
bilinear form becomes coercive"; singular: the curves do not change from lambda = 5 on.
How each claim is decided: ``interface.LAMBDA_CHOICES`` and
:mod:`hpfebe.scenes.interface_readings`.  Beside the sweeps, the coercivity threshold
lambda*(p) of every mesh (:func:`hpfebe.coupling.coercivity_threshold`) tests whether
coercivity is what separates the curves that change from those that do not.  The two
examples are independent :data:`SCENES`.
"""

from __future__ import annotations

import pandas as pd

from hpfebe.scenes import interface, interface_readings as rd
from hpfebe.suite import (ArtefactResult, Claim, from_config, new_figure, progress,
                          readable_log_ticks, reference_slope, select_scenes, style_axes)

ARTEFACTS = ("figure_2_5", "figure_2_6", "figure_2_7", "figure_2_8", "figure_2_9",
             "figure_2_10", "figure_2_11", "figure_2_12")
#: independent computations: the smooth and the singular example
SCENES = {"smooth": ("figure_2_5", "figure_2_6", "figure_2_7", "figure_2_8"),
          "singular": ("figure_2_9", "figure_2_10", "figure_2_11", "figure_2_12")}

#: the scene's parameters (config section ch2_lambda)
Params = interface.LambdaScene


def _sweep(prm: Params, name: str, series: str, cases, desc: str) -> pd.DataFrame:
    """One row per (case, lambda_Nit) (:func:`hpfebe.scenes.interface.sweep_rows`)."""
    return pd.DataFrame(interface.sweep_rows(name, series, cases, prm.lambdas, prm.alpha,
                                             prm.h_def, desc, False, progress))


#: line styles of the four error curves: (part, norm) -> (label, marker, linestyle)
STYLES = {("fe", "h1"): ("energy-err (FE)", "o", "-"),
          ("fe", "l2"): ("L2-error (FE)", "s", "-"),
          ("be", "h1"): ("energy-err (BE)", "^", "--"),
          ("be", "l2"): ("L2-error (BE)", "D", "--")}


# ----------------------------------------------------------------------------- smooth
def _smooth_claims(lambda_nit, d, ref, degrees, star) -> list[Claim]:
    if lambda_nit == 1.0:
        return [Claim("lambda_Nit = 1: no convergence for p = 1", *rd.no_convergence(d),
                      id="no_convergence")]
    if lambda_nit == 5.0 and 3 in degrees:
        return [Claim("lambda_Nit = 5: reduced convergence rate for p = 3",
                      *rd.reduced_p3(d, ref), id="reduced_p3"),
                Claim("beyond the thesis: lambda_Nit = 5 is below the coercivity threshold "
                      "lambda*(3) on every mesh of the sweep, and the p = 3 rates are "
                      "nevertheless those of lambda_Nit = 20",
                      *rd.below_threshold(d, ref, star, lambda_nit), kind="beyond")]
    if lambda_nit == 10.0:
        return [Claim("lambda_Nit = 10 and 20 give almost the same convergence rates",
                      *rd.same_rates(d, ref, degrees), id="same_rates"),
                Claim("beyond the thesis: lambda_Nit = 10 and 20 give the same errors "
                      "(within 5 %)", *rd.same_errors(d, ref, star, degrees), kind="beyond")]
    return []


def _per_lambda(prm: Params, df: pd.DataFrame, first: int, title: str, xlabel: str,
                draw, claims, notes: str, meta: dict) -> list[ArtefactResult]:
    """One figure per lambda_Nit (figure_2_<first + k>): ``draw(ax, d)`` plots the rows
    ``d`` of that lambda, ``claims(lambda_nit, d, ref)`` states the claims against the
    largest lambda."""
    ref = df[df.lambda_nit == max(prm.lambdas)]
    out = []
    for k, lambda_nit in enumerate(prm.lambdas):
        d = df[df.lambda_nit == lambda_nit]
        fig, ax = new_figure((7.0, 5.0))
        draw(ax, d)
        style_axes(ax, xlabel, "error", f"{title}, lambda_Nit = {lambda_nit:g}",
                   title_size=9, legend=dict(fontsize=6, ncol=2))
        out.append(ArtefactResult(
            name=f"figure_2_{first + k}", table=d.reset_index(drop=True), figure=fig,
            claims=claims(lambda_nit, d, ref),
            meta=dict(meta, alpha=prm.alpha, h_def=prm.h_def, lambdas=list(prm.lambdas)),
            notes=notes + " Choices: " + " ".join(interface.LAMBDA_CHOICES)))
    return out


def _star_meta(star: pd.DataFrame) -> dict:
    return dict(lambda_star=[dict(fe_h_inv=int(r.fe_h_inv), be_h_inv=int(r.be_h_inv),
                                  p=int(r.p), lambda_star=round(float(r.lambda_star), 4))
                             for r in star.itertuples()])


def smooth_figures(prm: Params) -> list[ArtefactResult]:
    """Figures 2.5-2.8: Example 1, h-version, errors against 1/h, one lambda_Nit each."""
    cases = [(fh, bh, p) for p in prm.degrees for fh, bh in prm.smooth_pairs]
    sm = _sweep(prm, "smooth", "h", cases, "smooth lambda sweep")
    star = pd.DataFrame(interface.threshold_rows(prm, "smooth", cases)).assign(series="h")
    colours = {p: f"C{k}" for k, p in enumerate(prm.degrees)}

    def draw(ax, d):
        for p in prm.degrees:
            g = d[d.p == p].sort_values("fe_h_inv")
            for (part, norm), (nm, mk, ls) in STYLES.items():
                ax.loglog(g[f"{part}_h_inv"], g[f"{part}_{norm}"], color=colours[p],
                          marker=mk, ls=ls, ms=3.5, mfc="none" if part == "be" else None,
                          label=f"{nm}, p={p}")
            reference_slope(ax, g.fe_h_inv, g.fe_h1.iloc[0], -p, f"$h^{p}$")
        readable_log_ticks(ax.xaxis)

    return _per_lambda(prm, sm, 5, "Example 1, h-version", "1/h", draw,
                       lambda lam, d, ref: _smooth_claims(lam, d, ref, prm.degrees, star),
                       "Errors against 1/h (FE h^-1 for FE curves, BE h^-1 for BE curves); "
                       "colour = p, marker/line = error. lambda* of every mesh in meta.",
                       _star_meta(star))


# ----------------------------------------------------------------------------- singular
def _singular_claims(lambda_nit, d, sref, star) -> list[Claim]:
    if lambda_nit < 5.0:
        return [Claim("singular: lambda_Nit = 1 differs from the larger values",
                      *rd.differs(d, sref), id="differs")]
    text = (f"singular: lambda_Nit = {lambda_nit:g} gives the same curves as larger "
            "lambda (unchanged from lambda = 5 on)")
    if lambda_nit >= sref.lambda_nit.iloc[0]:
        return [Claim(text, None, f"lambda_Nit = {lambda_nit:g} is the largest value of "
                                  "the sweep: there is no larger one to compare with",
                      id="same_curves")]
    same = Claim(text, *rd.same_curves(d, sref), id="same_curves")
    return [same] if same.holds else [same, Claim(
        f"the curves change (by more than {rd.SAME:.0%}) only where lambda_Nit = "
        f"{lambda_nit:g} is below the coercivity threshold lambda*(p) of the mesh, so "
        "that a_h is not coercive there", *rd.coercivity(d, sref, star),
        kind="explanation", id="coercivity", explains=("same_curves",))]


def singular_figures(prm: Params) -> list[ArtefactResult]:
    """Figures 2.9-2.12: Example 2, h- and p-version, errors against DOF."""
    qf, qb = prm.singular_p_mesh
    cases = {"h": [(fh, bh, 1) for fh, bh in prm.singular_pairs],
             "p": [(qf, qb, p) for p in prm.singular_p_degrees]}
    sg = pd.concat([_sweep(prm, "singular", series, c, f"singular {series} lambda sweep")
                    for series, c in cases.items()], ignore_index=True)
    star = pd.concat([pd.DataFrame(interface.threshold_rows(prm, "singular", c))
                      .assign(series=series) for series, c in cases.items()],
                     ignore_index=True)
    colours = {k: f"C{i}" for i, k in enumerate(STYLES)}

    def draw(ax, d):
        for series, ls, mk in (("h", "-", "o"), ("p", "--", "s")):
            g = d[d.series == series].sort_values("dof")
            for (part, norm), (nm, _, _) in STYLES.items():
                ax.loglog(g.dof, g[f"{part}_{norm}"], color=colours[(part, norm)], ls=ls,
                          marker=mk, ms=3.5, mfc="none" if series == "p" else None,
                          label=f"{series}: {nm}")
        gh = d[d.series == "h"].sort_values("dof")
        reference_slope(ax, gh.dof, gh.be_h1.iloc[0], -1 / 3, "DOF$^{-1/3}$", below=True)

    return _per_lambda(prm, sg, 9, "Example 2, h- and p-version", "DOF", draw,
                       lambda lam, d, ref: _singular_claims(lam, d, ref, star),
                       "h-version p = 1 (FE h^-1 = 4..., BE h^-1 = 8...) and p-version "
                       "(FE h^-1 = 4, BE h^-1 = 6), errors against DOF; colour = error, "
                       "solid/filled = h-version, dashed/open = p-version. lambda* of "
                       "every mesh in meta.", _star_meta(star))


SCENE_RUNS = {"smooth": smooth_figures, "singular": singular_figures}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """Figures 2.5-2.12 of the scenes asked for (None: both; ``quick`` is unused:
    config/quick.yaml sets the sizes)."""
    prm = from_config(Params, config, scene="ch2_lambda")
    return [r for name in select_scenes(SCENES, scenes, "ch2_lambda")
            for r in SCENE_RUNS[name](prm)]
