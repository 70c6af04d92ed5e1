"""Chapter 2, Section 2.2.5, Example 3: the choice of lambda_Nit (Figures 2.5-2.12).

For lambda_Nit in {1, 5, 10, 20}: Example 1 (smooth), h-version p1 = p2 = 1, 2, 3, errors
against the mesh size (Figures 2.5-2.8); Example 2 (singular), h-version p = 1 and p-version
on FE h^-1 = 4 / BE h^-1 = 6, errors against DOF (Figures 2.9-2.12).  The coupled system of
each mesh is assembled once and solved for all four lambda_Nit (only the penalty blocks are
rescaled).  Claims (lines ~3940-4100): lambda = 1 does not converge for p = 1; lambda = 5
gives a reduced rate for p = 3 (smooth); lambda = 10 and 20 give the same curves; singular:
the curves do not change from lambda = 5 on.

Choices: alpha = 0, h1 = edge length, BE-part post-processing and meshes as in
experiments/ch2_convergence.py.  "Does not converge": the FE energy error on the finest
mesh is not below half of that on the coarsest.  "Reduced rate": the last FE energy rate
is more than 0.3 below the lambda = 20 rate, or the BE energy rate is.  "The same curves":
all errors within 5 % of lambda = 20.  The lambda_Nit sweep is on the meshes up to
FE h^-1 = 23 (smooth) and 64 (singular) in the full configuration.
"""

from __future__ import annotations

import logging

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe.results import ArtefactResult, Claim

from experiments._ch2 import add_slope, rates, sweep

ARTEFACTS = ("figure_2_5", "figure_2_6", "figure_2_7", "figure_2_8", "figure_2_9",
             "figure_2_10", "figure_2_11", "figure_2_12")

log = logging.getLogger(__name__)
LAMBDAS = (1.0, 5.0, 10.0, 20.0)


def _rate(df, part, x):
    g = df.sort_values(x)
    return float(rates(g[x], g[f"{part}_h1"])[-1])


def _close(a, b, cols=("fe_l2", "fe_h1", "be_l2", "be_h1")):
    r = np.concatenate([(a[c].to_numpy() / b[c].to_numpy()) for c in cols])
    return float(np.max(np.abs(r - 1.0)))


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    lams = [float(x) for x in config.get("lambdas", LAMBDAS)]
    alpha = float(config.get("alpha", 0.0))
    h_def = str(config.get("h_def", "edge"))
    pairs = [tuple(x) for x in config.get("smooth_pairs", [[2, 3], [5, 6], [11, 12],
                                                           [23, 24]])]
    degrees = [int(p) for p in config.get("degrees", [1, 2, 3])]
    spairs = [tuple(x) for x in config.get("singular_pairs", [[4, 8], [8, 12], [16, 20],
                                                              [32, 36], [64, 68]])]
    qf, qb = config.get("singular_p_mesh", [4, 6])
    pdeg = [int(p) for p in config.get("singular_p_degrees", range(1, 8))]

    sm = sweep("smooth", "h", [(fh, bh, p) for p in degrees for fh, bh in pairs], lams,
               alpha, h_def, desc="smooth lambda sweep")
    sg = pd.concat([sweep("singular", "h", [(fh, bh, 1) for fh, bh in spairs], lams, alpha,
                          h_def, desc="singular h lambda sweep"),
                    sweep("singular", "p", [(qf, qb, p) for p in pdeg], lams, alpha, h_def,
                          desc="singular p lambda sweep")], ignore_index=True)
    meta = dict(alpha=alpha, h_def=h_def, lambdas=lams)
    ref = sm[sm.lam == max(lams)]
    results = []
    for k, lam in enumerate(lams):
        d = sm[sm.lam == lam]
        fig = Figure(figsize=(7.0, 5.0))
        ax = fig.subplots()
        for p in degrees:
            g = d[d.p == p].sort_values("fe_h_inv")
            for part, hcol in (("be", "be_h_inv"), ("fe", "fe_h_inv")):
                for norm, nm in (("l2", "L2-error"), ("h1", "energy-err")):
                    ax.loglog(g[hcol], g[f"{part}_{norm}"], "o-" if part == "fe" else "s--",
                              ms=3, label=f"{nm} ({part.upper()}, p={p})")
            add_slope(ax, g.fe_h_inv, g.fe_h1.iloc[0], -p, f"h^{p}")
        ax.set_xlabel("1/h")
        ax.set_ylabel("error")
        ax.set_title(f"Example 1, h-version, lambda_Nit = {lam:g}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
        claims = []
        if lam == 1.0:
            g = d[d.p == 1].sort_values("fe_h_inv")
            r = _rate(g, "fe", "fe_h_inv")
            claims.append(Claim("lambda_Nit = 1: no convergence for p = 1", bool(r < 0.3),
                                f"last FE energy rate {r:.2f}; FE energy errors p=1: "
                                + ", ".join(f"{v:.3e}" for v in g.fe_h1)))
        if lam == 5.0 and 3 in degrees:
            g, g20 = d[d.p == 3], ref[ref.p == 3]
            rf, rf20 = _rate(g, "fe", "fe_h_inv"), _rate(g20, "fe", "fe_h_inv")
            rb, rb20 = _rate(g, "be", "be_h_inv"), _rate(g20, "be", "be_h_inv")
            ok = (rf < rf20 - 0.3) or (rb < rb20 - 0.3)
            claims.append(Claim(
                "lambda_Nit = 5: reduced convergence rate for p = 3", bool(ok),
                f"last energy rates p=3: FE {rf:.2f} (lambda=20: {rf20:.2f}), BE {rb:.2f} "
                f"(lambda=20: {rb20:.2f}); largest deviation from lambda=20 "
                f"{_close(g, g20):.1%}"))
        if lam == 10.0:
            devs = {p: _close(d[d.p == p].sort_values("fe_h_inv"),
                              ref[ref.p == p].sort_values("fe_h_inv")) for p in degrees}
            claims.append(Claim(
                "lambda_Nit = 10 and 20 give almost the same curves",
                bool(max(devs.values()) <= 0.05),
                "largest relative difference of the errors to lambda = 20: " + ", ".join(
                    f"p={p}: {v:.1%}" for p, v in devs.items()) + ". With alpha = 0 the "
                "computed coercivity threshold is ~1.1 p^2 (figure_coercivity): lambda = 10 "
                "lies just below it for p = 3, where lambda = 20 gives smaller errors."))
        results.append(ArtefactResult(
            name=f"figure_2_{5 + k}", table=d.reset_index(drop=True), figure=fig,
            claims=claims, meta=meta,
            notes="Errors against 1/h (FE h^-1 for FE curves, BE h^-1 for BE curves). "
                  "alpha = 0, h1 = edge length; BE part: see ch2_convergence."))
    sref = sg[sg.lam == max(lams)]
    for k, lam in enumerate(lams):
        d = sg[sg.lam == lam]
        fig = Figure(figsize=(7.0, 5.0))
        ax = fig.subplots()
        for series, mk in (("h", "o-"), ("p", "s--")):
            g = d[d.series == series].sort_values("dof")
            for part in ("be", "fe"):
                for norm, nm in (("h1", "energy-err"), ("l2", "L2-error")):
                    ax.loglog(g.dof, g[f"{part}_{norm}"], mk, ms=3,
                              label=f"{series}: {nm} ({part.upper()})")
        gh = d[d.series == "h"].sort_values("dof")
        add_slope(ax, gh.dof, gh.be_h1.iloc[0], -1 / 3, "DOF^-1/3")
        ax.set_xlabel("DOF")
        ax.set_ylabel("error")
        ax.set_title(f"Example 2, h- and p-version, lambda_Nit = {lam:g}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
        claims = []
        if lam >= 5.0:
            key = ["series", "p", "dof"]
            dh = _close(d[d.series == "h"].sort_values(key), sref[sref.series == "h"].sort_values(key))
            pp = sorted(d[d.series == "p"].p.unique())
            dp = {p: _close(d[(d.series == "p") & (d.p == p)],
                            sref[(sref.series == "p") & (sref.p == p)]) for p in pp}
            claims.append(Claim(f"singular: lambda_Nit = {lam:g} gives the same curves as "
                                "larger lambda (unchanged from lambda = 5 on)",
                                bool(max([dh] + list(dp.values())) <= 0.05),
                                f"largest relative difference to lambda = 20: h-version "
                                f"{dh:.1%}; p-version " + ", ".join(
                                    f"p={p}: {v:.1%}" for p, v in dp.items())
                                + " (alpha = 0: the threshold grows like p^2, so high p "
                                "needs larger lambda)"))
        else:
            dev = _close(d.sort_values(["series", "p", "dof"]),
                         sref.sort_values(["series", "p", "dof"]))
            claims.append(Claim("singular: lambda_Nit = 1 differs from the larger values",
                                bool(dev > 0.05),
                                f"largest relative difference to lambda = 20: {dev:.2%}"))
        results.append(ArtefactResult(
            name=f"figure_2_{9 + k}", table=d.reset_index(drop=True), figure=fig,
            claims=claims, meta=meta,
            notes="h-version p = 1 (FE h^-1 = 4..., BE h^-1 = 8...) and p-version (FE "
                  "h^-1 = 4, BE h^-1 = 6), errors against DOF."))
    return results
