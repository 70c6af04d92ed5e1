"""Chapter 2, Section 2.2.5, Example 3: the choice of lambda_Nit (Figures 2.5-2.12).

For lambda_Nit in {1, 5, 10, 20}: Example 1 (smooth), h-version p1 = p2 = 1, 2, 3, errors
against the mesh size (Figures 2.5-2.8); Example 2 (singular), h-version p = 1 and p-version
on FE h^-1 = 4 / BE h^-1 = 6, errors against DOF (Figures 2.9-2.12).  The coupled system of
each mesh is assembled once and solved for all four lambda_Nit
(:func:`hpfebe.scenes.interface.lambda_sweep`).  Claims (thesis lines ~3940-4100):
lambda = 1 does not converge for p = 1; lambda = 5 gives a reduced rate for p = 3
(smooth); the convergence rates for lambda = 10 and 20 are almost the same, "i.e. the
bilinear form becomes coercive"; singular: the curves do not change from lambda = 5 on.
How each claim is decided is in :data:`CHOICES`.  Beside the sweeps, the coercivity
threshold lambda*(p) of every mesh (:func:`hpfebe.coupling.coercivity_threshold`)
tests whether coercivity is what separates the curves that change from those that do
not.  The two examples are independent :data:`SCENES`.
"""

from __future__ import annotations

import logging
import numpy as np
import pandas as pd

from hpfebe.scenes import interface
from hpfebe.suite import (ArtefactResult, Claim, from_config, new_figure, readable_log_ticks,
                          reference_slope, select_scenes, style_axes)

from experiments._ch2 import rates, sweep

ARTEFACTS = ("figure_2_5", "figure_2_6", "figure_2_7", "figure_2_8", "figure_2_9",
             "figure_2_10", "figure_2_11", "figure_2_12")
#: independent computations: the smooth and the singular example
SCENES = {"smooth": ("figure_2_5", "figure_2_6", "figure_2_7", "figure_2_8"),
          "singular": ("figure_2_9", "figure_2_10", "figure_2_11", "figure_2_12")}

log = logging.getLogger(__name__)

CHOICES = (
    "alpha = 0, h1 = edge length, BE-part post-processing and meshes as in "
    "ch2_convergence.",
    "'Does not converge': the last FE energy rate (w.r.t. h^-1) is below 0.3.",
    "'Reduced rate': the last FE energy rate is more than 0.3 below the lambda = 20 rate, "
    "or the BE energy rate is.",
    "'Almost the same convergence rates' (smooth, lambda = 10 and 20): the last rates of "
    "all four error curves of every p within 0.15 (the rate tolerance of the tables) of "
    "lambda = 20.",
    "'The same curves': all errors (FE and BE, L2 and energy) within 5 % of lambda = 20.",
    "Coercivity: lambda*(p) of each mesh of the sweep (same alpha and h1) - a_h is "
    "positive definite iff lambda_Nit > lambda*.",
    "The lambda_Nit sweep is on the meshes up to FE h^-1 = 23 (smooth) and 64 (singular) "
    "in the full configuration.",
)
SAME = 0.05            # "the same curves": all errors within 5 % of the largest lambda
SLOWER = 0.3           # "reduced rate": last energy rate more than 0.3 lower
RATE_TOL = 0.15        # "almost the same rates": last rates within 0.15
ERRORS = ("fe_l2", "fe_h1", "be_l2", "be_h1")

#: the scene's parameters (config section ch2_lambda)
Params = interface.LambdaScene


def _last_rate(df, part, x, norm="h1"):
    g = df.sort_values(x)
    return float(rates(g[x], g[f"{part}_{norm}"])[-1])


def _max_rel_diff(a, b, cols=ERRORS):
    """Largest |a/b - 1| over the error columns (rows matched by position)."""
    r = np.concatenate([(a[c].to_numpy() / b[c].to_numpy()) for c in cols])
    return float(np.max(np.abs(r - 1.0)))


def thresholds(prm: Params, example: str, cases) -> pd.DataFrame:
    """lambda*(p) (coercivity threshold, Lemma 2.2.3) of every (fe_h_inv, be_h_inv, p) of
    ``cases``, with the sweep's alpha and h1 (:func:`.interface.threshold_rows`)."""
    return pd.DataFrame(interface.threshold_rows(prm, example, cases))


def _deviations(d, ref, star) -> pd.DataFrame:
    """Per mesh and p: the largest |e / e_ref - 1| over the four errors against the
    reference lambda, and lambda* of that mesh."""
    key = ["series", "p", "fe_h_inv", "be_h_inv"]
    m = d.merge(ref, on=key, suffixes=("", "_ref")).merge(star, on=key)
    dev = np.max([np.abs(m[c] / m[f"{c}_ref"] - 1.0) for c in ERRORS], axis=0)
    return m[key + ["lambda_nit", "lambda_star"]].assign(dev=dev)


def _points(df) -> str:
    return ", ".join(f"{r.series}-version p={r.p} FE 1/{r.fe_h_inv:g}: {r.dev:.1%} "
                     f"(lambda* {r.lambda_star:.2f})" for r in df.itertuples()) or "none"


#: line styles of the four error curves: (part, norm) -> (label, marker, linestyle)
STYLES = {("fe", "h1"): ("energy-err (FE)", "o", "-"),
          ("fe", "l2"): ("L2-error (FE)", "s", "-"),
          ("be", "h1"): ("energy-err (BE)", "^", "--"),
          ("be", "l2"): ("L2-error (BE)", "D", "--")}


# ----------------------------------------------------------------------------- smooth
def _smooth_claims(lambda_nit, d, ref, degrees, star) -> list[Claim]:
    if lambda_nit == 1.0:
        g = d[d.p == 1].sort_values("fe_h_inv")
        r = _last_rate(g, "fe", "fe_h_inv")
        return [Claim("lambda_Nit = 1: no convergence for p = 1", bool(r < SLOWER),
                      f"last FE energy rate {r:.2f}; FE energy errors p=1: "
                      + ", ".join(f"{v:.3e}" for v in g.fe_h1), id="no_convergence")]
    if lambda_nit == 5.0 and 3 in degrees:
        g, g20 = d[d.p == 3], ref[ref.p == 3]
        rf, rf20 = _last_rate(g, "fe", "fe_h_inv"), _last_rate(g20, "fe", "fe_h_inv")
        rb, rb20 = _last_rate(g, "be", "be_h_inv"), _last_rate(g20, "be", "be_h_inv")
        s3 = star[star.p == 3].lambda_star
        return [Claim(
            "lambda_Nit = 5: reduced convergence rate for p = 3",
            bool((rf < rf20 - SLOWER) or (rb < rb20 - SLOWER)),
            f"last energy rates p=3: FE {rf:.2f} (lambda=20: {rf20:.2f}), BE {rb:.2f} "
            f"(lambda=20: {rb20:.2f}); largest deviation from lambda=20 "
            f"{_max_rel_diff(g, g20):.1%}", id="reduced_p3"),
            Claim(
            "beyond the thesis: lambda_Nit = 5 is below the coercivity threshold "
            "lambda*(3) on every mesh of the sweep, and the p = 3 rates are nevertheless "
            "those of lambda_Nit = 20",
            bool((s3 > lambda_nit).all() and abs(rf - rf20) <= RATE_TOL
                 and abs(rb - rb20) <= RATE_TOL),
            f"lambda*(3) = {s3.min():.2f}..{s3.max():.2f} over the meshes FE h^-1 = "
            + ", ".join(f"{v:g}" for v in star[star.p == 3].fe_h_inv)
            + f"; last energy rates FE {rf:.2f} / {rf20:.2f}, BE {rb:.2f} / {rb20:.2f} "
              "(lambda = 5 / 20)", kind="beyond")]
    if lambda_nit == 10.0:
        diff = {p: max(abs(_last_rate(d[d.p == p], part, h, norm)
                           - _last_rate(ref[ref.p == p], part, h, norm))
                       for part, h in (("fe", "fe_h_inv"), ("be", "be_h_inv"))
                       for norm in ("h1", "l2")) for p in degrees}
        devs = {p: _max_rel_diff(d[d.p == p].sort_values("fe_h_inv"),
                                 ref[ref.p == p].sort_values("fe_h_inv")) for p in degrees}
        dv = _deviations(d, ref, star)
        finest = dv[dv.fe_h_inv == dv.fe_h_inv.max()]
        worst = dv.loc[[dv.dev.idxmax()]]
        below = dv[dv.lambda_nit < dv.lambda_star]
        return [Claim(
            "lambda_Nit = 10 and 20 give almost the same convergence rates",
            bool(max(diff.values()) <= RATE_TOL),
            "largest difference of the last rates (FE/BE, L2/energy) to lambda = 20: "
            + ", ".join(f"p={p}: {v:.3f}" for p, v in diff.items())
            + f" (tolerance {RATE_TOL})", id="same_rates"),
            Claim(
            "beyond the thesis: lambda_Nit = 10 and 20 give the same errors (within 5 %)",
            bool(max(devs.values()) <= SAME),
            "largest relative difference of the errors to lambda = 20: " + ", ".join(
                f"p={p}: {v:.1%}" for p, v in devs.items()) + "; on the finest mesh: "
            + ", ".join(f"p={r.p}: {r.dev:.1%}" for r in finest.itertuples())
            + ". Largest: " + _points(worst) + "; meshes where lambda = 10 is "
            "below lambda*: " + _points(below) + " (coercivity does not single out the "
            "largest difference)", kind="beyond")]
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
            notes=notes + " Choices: " + " ".join(CHOICES)))
    return out


def _star_meta(star: pd.DataFrame) -> dict:
    return dict(lambda_star=[dict(fe_h_inv=int(r.fe_h_inv), be_h_inv=int(r.be_h_inv),
                                  p=int(r.p), lambda_star=round(float(r.lambda_star), 4))
                             for r in star.itertuples()])


def smooth_figures(prm: Params) -> list[ArtefactResult]:
    """Figures 2.5-2.8: Example 1, h-version, errors against 1/h, one lambda_Nit each."""
    cases = [(fh, bh, p) for p in prm.degrees for fh, bh in prm.smooth_pairs]
    sm = sweep("smooth", "h", cases, lambdas=prm.lambdas, alpha=prm.alpha, h_def=prm.h_def,
               desc="smooth lambda sweep")
    star = thresholds(prm, "smooth", cases).assign(series="h")
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
    key = ["series", "p", "dof"]
    lam_max = sref.lambda_nit.iloc[0]
    if lambda_nit >= 5.0:
        text = (f"singular: lambda_Nit = {lambda_nit:g} gives the same curves as larger "
                "lambda (unchanged from lambda = 5 on)")
        if lambda_nit >= lam_max:
            return [Claim(text, None, f"lambda_Nit = {lambda_nit:g} is the largest value of "
                                      "the sweep: there is no larger one to compare with",
                          id="same_curves")]
        dh = _max_rel_diff(d[d.series == "h"].sort_values(key),
                           sref[sref.series == "h"].sort_values(key))
        dp = {p: _max_rel_diff(d[(d.series == "p") & (d.p == p)],
                               sref[(sref.series == "p") & (sref.p == p)])
              for p in sorted(d[d.series == "p"].p.unique())}
        same = Claim(text, bool(max([dh] + list(dp.values())) <= SAME),
                     f"largest relative difference to lambda = {lam_max:g}: h-version "
                     f"{dh:.1%}; p-version " + ", ".join(f"p={p}: {v:.1%}"
                                                         for p, v in dp.items()),
                     id="same_curves")
        if same.holds:
            return [same]
        dv = _deviations(d, sref, star)
        changed = dv[dv.dev > SAME]
        coercive_changed = changed[changed.lambda_nit > changed.lambda_star]
        below_same = dv[(dv.lambda_nit < dv.lambda_star) & (dv.dev <= SAME)]
        worst = dv.loc[[dv.dev.idxmax()]]
        return [same, Claim(
            f"the curves change (by more than {SAME:.0%}) only where lambda_Nit = "
            f"{lambda_nit:g} is below the coercivity threshold lambda*(p) of the mesh, so "
            "that a_h is not coercive there",
            bool(coercive_changed.empty),
            f"{len(changed)} of {len(dv)} points change; changed although lambda_Nit > "
            f"lambda*: {_points(coercive_changed)}; lambda_Nit < lambda* but unchanged: "
            f"{_points(below_same)}; the largest change: {_points(worst)}. Coercivity "
            "(computed on the same meshes, same alpha and h1) does not separate the curves "
            "that change from those that do not.",
            kind="explanation", id="coercivity", explains=("same_curves",))]
    dev = _max_rel_diff(d.sort_values(key), sref.sort_values(key))
    return [Claim("singular: lambda_Nit = 1 differs from the larger values", bool(dev > SAME),
                  f"largest relative difference to lambda = {lam_max:g}: {dev:.2%}",
                  id="differs")]


def singular_figures(prm: Params) -> list[ArtefactResult]:
    """Figures 2.9-2.12: Example 2, h- and p-version, errors against DOF."""
    kw = dict(lambdas=prm.lambdas, alpha=prm.alpha, h_def=prm.h_def)
    qf, qb = prm.singular_p_mesh
    cases = {"h": [(fh, bh, 1) for fh, bh in prm.singular_pairs],
             "p": [(qf, qb, p) for p in prm.singular_p_degrees]}
    sg = pd.concat([sweep("singular", series, c, desc=f"singular {series} lambda sweep", **kw)
                    for series, c in cases.items()], ignore_index=True)
    star = pd.concat([thresholds(prm, "singular", c).assign(series=series)
                      for series, c in cases.items()], ignore_index=True)
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
