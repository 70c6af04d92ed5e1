"""Chapter 2, Section 2.2.5, Example 3: the choice of lambda_Nit (Figures 2.5-2.12).

For lambda_Nit in {1, 5, 10, 20}: Example 1 (smooth), h-version p1 = p2 = 1, 2, 3, errors
against the mesh size (Figures 2.5-2.8); Example 2 (singular), h-version p = 1 and p-version
on FE h^-1 = 4 / BE h^-1 = 6, errors against DOF (Figures 2.9-2.12).  The coupled system of
each mesh is assembled once and solved for all four lambda_Nit
(:func:`hpfebe.coupling.errors.lambda_sweep`).  Claims (thesis lines ~3940-4100):
lambda = 1 does not converge for p = 1; lambda = 5 gives a reduced rate for p = 3
(smooth); lambda = 10 and 20 give the same curves; singular: the curves do not change
from lambda = 5 on.  How each claim is decided is in :data:`CHOICES`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe.params import from_config
from hpfebe.results import ArtefactResult, Claim

from experiments._ch2 import add_slope, rates, sweep

ARTEFACTS = ("figure_2_5", "figure_2_6", "figure_2_7", "figure_2_8", "figure_2_9",
             "figure_2_10", "figure_2_11", "figure_2_12")

log = logging.getLogger(__name__)

CHOICES = (
    "alpha = 0, h1 = edge length, BE-part post-processing and meshes as in "
    "ch2_convergence.",
    "'Does not converge': the last FE energy rate (w.r.t. h^-1) is below 0.3.",
    "'Reduced rate': the last FE energy rate is more than 0.3 below the lambda = 20 rate, "
    "or the BE energy rate is.",
    "'The same curves': all errors (FE and BE, L2 and energy) within 5 % of lambda = 20.",
    "The lambda_Nit sweep is on the meshes up to FE h^-1 = 23 (smooth) and 64 (singular) "
    "in the full configuration.",
)
SAME = 0.05            # "the same curves": all errors within 5 % of the largest lambda
SLOWER = 0.3           # "reduced rate": last energy rate more than 0.3 lower


@dataclass(frozen=True)
class Params:
    lambdas: tuple[float, ...] = (1.0, 5.0, 10.0, 20.0)   # lambda_Nit values
    alpha: float = 0.0
    h_def: str = "edge"
    smooth_pairs: tuple[tuple[int, ...], ...] = ((2, 3), (5, 6), (11, 12), (23, 24))
    degrees: tuple[int, ...] = (1, 2, 3)
    singular_pairs: tuple[tuple[int, ...], ...] = ((4, 8), (8, 12), (16, 20), (32, 36),
                                                   (64, 68))
    singular_p_mesh: tuple[int, ...] = (4, 6)
    singular_p_degrees: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7)

    def __post_init__(self):
        for name in ("smooth_pairs", "singular_pairs"):
            if any(len(pr) != 2 for pr in getattr(self, name)):
                raise ValueError(f"ch2_lambda.{name} must be [fe_h_inv, be_h_inv] pairs, "
                                 f"got {getattr(self, name)}")
        if len(self.singular_p_mesh) != 2:
            raise ValueError(f"ch2_lambda.singular_p_mesh must be [fe_h_inv, be_h_inv], "
                             f"got {self.singular_p_mesh}")
        if not self.lambdas:
            raise ValueError("ch2_lambda.lambdas must not be empty")


def _last_rate(df, part, x):
    g = df.sort_values(x)
    return float(rates(g[x], g[f"{part}_h1"])[-1])


def _max_rel_diff(a, b, cols=("fe_l2", "fe_h1", "be_l2", "be_h1")):
    """Largest |a/b - 1| over the error columns (rows matched by position)."""
    r = np.concatenate([(a[c].to_numpy() / b[c].to_numpy()) for c in cols])
    return float(np.max(np.abs(r - 1.0)))


def _figure(title, xlabel):
    fig = Figure(figsize=(7.0, 5.0))
    ax = fig.subplots()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("error")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    return fig, ax


# ----------------------------------------------------------------------------- smooth
def _smooth_claims(lambda_nit, d, ref, degrees) -> list[Claim]:
    if lambda_nit == 1.0:
        g = d[d.p == 1].sort_values("fe_h_inv")
        r = _last_rate(g, "fe", "fe_h_inv")
        return [Claim("lambda_Nit = 1: no convergence for p = 1", bool(r < SLOWER),
                      f"last FE energy rate {r:.2f}; FE energy errors p=1: "
                      + ", ".join(f"{v:.3e}" for v in g.fe_h1))]
    if lambda_nit == 5.0 and 3 in degrees:
        g, g20 = d[d.p == 3], ref[ref.p == 3]
        rf, rf20 = _last_rate(g, "fe", "fe_h_inv"), _last_rate(g20, "fe", "fe_h_inv")
        rb, rb20 = _last_rate(g, "be", "be_h_inv"), _last_rate(g20, "be", "be_h_inv")
        return [Claim(
            "lambda_Nit = 5: reduced convergence rate for p = 3",
            bool((rf < rf20 - SLOWER) or (rb < rb20 - SLOWER)),
            f"last energy rates p=3: FE {rf:.2f} (lambda=20: {rf20:.2f}), BE {rb:.2f} "
            f"(lambda=20: {rb20:.2f}); largest deviation from lambda=20 "
            f"{_max_rel_diff(g, g20):.1%}")]
    if lambda_nit == 10.0:
        devs = {p: _max_rel_diff(d[d.p == p].sort_values("fe_h_inv"),
                                 ref[ref.p == p].sort_values("fe_h_inv")) for p in degrees}
        return [Claim(
            "lambda_Nit = 10 and 20 give almost the same curves",
            bool(max(devs.values()) <= SAME),
            "largest relative difference of the errors to lambda = 20: " + ", ".join(
                f"p={p}: {v:.1%}" for p, v in devs.items()) + ". With alpha = 0 the "
            "computed coercivity threshold is ~1.1 p^2 (figure_coercivity): lambda = 10 "
            "lies just below it for p = 3, where lambda = 20 gives smaller errors.")]
    return []


def _per_lambda(prm: Params, df: pd.DataFrame, first: int, title: str, xlabel: str,
                draw, claims, notes: str) -> list[ArtefactResult]:
    """One figure per lambda_Nit (figure_2_<first + k>): ``draw(ax, d)`` plots the rows
    ``d`` of that lambda, ``claims(lambda_nit, d, ref)`` states the claims against the
    largest lambda."""
    ref = df[df.lambda_nit == max(prm.lambdas)]
    out = []
    for k, lambda_nit in enumerate(prm.lambdas):
        d = df[df.lambda_nit == lambda_nit]
        fig, ax = _figure(f"{title}, lambda_Nit = {lambda_nit:g}", xlabel)
        draw(ax, d)
        ax.legend(fontsize=6, ncol=2)
        out.append(ArtefactResult(
            name=f"figure_2_{first + k}", table=d.reset_index(drop=True), figure=fig,
            claims=claims(lambda_nit, d, ref),
            meta=dict(alpha=prm.alpha, h_def=prm.h_def, lambdas=list(prm.lambdas)),
            notes=notes + " Choices: " + " ".join(CHOICES)))
    return out


def smooth_figures(prm: Params, sm: pd.DataFrame) -> list[ArtefactResult]:
    """Figures 2.5-2.8: Example 1, h-version, errors against 1/h, one lambda_Nit each."""
    def draw(ax, d):
        for p in prm.degrees:
            g = d[d.p == p].sort_values("fe_h_inv")
            for part, hcol in (("be", "be_h_inv"), ("fe", "fe_h_inv")):
                for norm, nm in (("l2", "L2-error"), ("h1", "energy-err")):
                    ax.loglog(g[hcol], g[f"{part}_{norm}"], "o-" if part == "fe" else "s--",
                              ms=3, label=f"{nm} ({part.upper()}, p={p})")
            add_slope(ax, g.fe_h_inv, g.fe_h1.iloc[0], -p, f"h^{p}")

    return _per_lambda(prm, sm, 5, "Example 1, h-version", "1/h", draw,
                       lambda lam, d, ref: _smooth_claims(lam, d, ref, prm.degrees),
                       "Errors against 1/h (FE h^-1 for FE curves, BE h^-1 for BE curves).")


# ----------------------------------------------------------------------------- singular
def _singular_claim(lambda_nit, d, sref) -> Claim:
    key = ["series", "p", "dof"]
    if lambda_nit >= 5.0:
        dh = _max_rel_diff(d[d.series == "h"].sort_values(key),
                           sref[sref.series == "h"].sort_values(key))
        dp = {p: _max_rel_diff(d[(d.series == "p") & (d.p == p)],
                               sref[(sref.series == "p") & (sref.p == p)])
              for p in sorted(d[d.series == "p"].p.unique())}
        return Claim(f"singular: lambda_Nit = {lambda_nit:g} gives the same curves as larger "
                     "lambda (unchanged from lambda = 5 on)",
                     bool(max([dh] + list(dp.values())) <= SAME),
                     f"largest relative difference to lambda = 20: h-version {dh:.1%}; "
                     "p-version " + ", ".join(f"p={p}: {v:.1%}" for p, v in dp.items())
                     + " (alpha = 0: the threshold grows like p^2, so high p needs larger "
                     "lambda)")
    dev = _max_rel_diff(d.sort_values(key), sref.sort_values(key))
    return Claim("singular: lambda_Nit = 1 differs from the larger values", bool(dev > SAME),
                 f"largest relative difference to lambda = 20: {dev:.2%}")


def singular_figures(prm: Params, sg: pd.DataFrame) -> list[ArtefactResult]:
    """Figures 2.9-2.12: Example 2, h- and p-version, errors against DOF."""
    def draw(ax, d):
        for series, mk in (("h", "o-"), ("p", "s--")):
            g = d[d.series == series].sort_values("dof")
            for part in ("be", "fe"):
                for norm, nm in (("h1", "energy-err"), ("l2", "L2-error")):
                    ax.loglog(g.dof, g[f"{part}_{norm}"], mk, ms=3,
                              label=f"{series}: {nm} ({part.upper()})")
        gh = d[d.series == "h"].sort_values("dof")
        add_slope(ax, gh.dof, gh.be_h1.iloc[0], -1 / 3, "DOF^-1/3")

    return _per_lambda(prm, sg, 9, "Example 2, h- and p-version", "DOF", draw,
                       lambda lam, d, ref: [_singular_claim(lam, d, ref)],
                       "h-version p = 1 (FE h^-1 = 4..., BE h^-1 = 8...) and p-version "
                       "(FE h^-1 = 4, BE h^-1 = 6), errors against DOF.")


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    """Figures 2.5-2.12 (``quick`` is unused: config/quick.yaml sets the sizes)."""
    prm = from_config(Params, config, scene="ch2_lambda")
    kw = dict(lambdas=prm.lambdas, alpha=prm.alpha, h_def=prm.h_def)
    sm = sweep("smooth", "h",
               [(fh, bh, p) for p in prm.degrees for fh, bh in prm.smooth_pairs],
               desc="smooth lambda sweep", **kw)
    qf, qb = prm.singular_p_mesh
    sg = pd.concat([sweep("singular", "h", [(fh, bh, 1) for fh, bh in prm.singular_pairs],
                          desc="singular h lambda sweep", **kw),
                    sweep("singular", "p", [(qf, qb, p) for p in prm.singular_p_degrees],
                          desc="singular p lambda sweep", **kw)], ignore_index=True)
    return smooth_figures(prm, sm) + singular_figures(prm, sg)
