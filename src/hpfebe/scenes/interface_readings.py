"""Chapter 2 (Section 2.2.5) read against the thesis, on the sweeps of
:mod:`hpfebe.scenes.interface`: Examples 1 and 2, Tables 2.1-2.4 and Figures 2.1-2.4
(:func:`factor_2`, :func:`p_version`, :func:`p_vs_h`, :func:`be_postprocessing`,
:func:`p_faster`, :func:`l2_rate_scatter`, :func:`exponential`, :func:`solution_range`,
:func:`fastest`); Example 3, the choice of lambda_Nit, Figures 2.5-2.12 (thesis lines
~3940-4100: :func:`no_convergence`, :func:`reduced_p3`, :func:`below_threshold`,
:func:`same_rates`, :func:`same_errors`, :func:`same_curves`, :func:`coercivity`,
:func:`differs`); and the coercivity threshold of Lemma 2.2.3 (:func:`threshold_growth`,
:func:`lemma`, :func:`example3`).  Ratios to the published tables are passed in (the
published frames live in the report).  Each returns the verdict (True, False or None)
and the evidence string."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..analysis import observed_rates

__all__ = ["ERRORS", "RATE_TOL", "SAME", "SLOWER", "THESIS_LAMBDAS", "be_postprocessing",
           "below_threshold", "coercivity", "differs", "example3", "exponential",
           "factor_2", "fastest", "l2_rate_scatter", "last", "lemma", "no_convergence",
           "p_faster", "p_version", "p_vs_h", "reduced_p3", "same_curves", "same_errors",
           "same_rates", "solution_range", "threshold_growth", "thresholds"]

SAME = 0.05            # "the same curves": all errors within 5 % of the largest lambda
SLOWER = 0.3           # "reduced rate": last energy rate more than 0.3 lower
RATE_TOL = 0.15        # "almost the same rates": last rates within 0.15
ERRORS = ("fe_l2", "fe_h1", "be_l2", "be_h1")
THESIS_LAMBDAS = (1, 5, 10)      # the lambda_Nit of Example 3


# ------------------------------------------------------------ Examples 1 and 2
def last(table, series: str, p, col: str) -> float:
    """Last entry of ``col`` in a part table: series h at degree p, or series p."""
    g = table[(table.series == series) & ((table.p == p) if series == "h" else True)]
    return float(g[col].iloc[-1])


def factor_2(ratio) -> tuple:
    """All ratios reproduced / published in [0.5, 2]."""
    return (bool(ratio.between(0.5, 2.0).all()),
            f"reproduced/published in [{ratio.min():.3f}, {ratio.max():.3f}] over "
            f"{len(ratio)} entries")


def p_version(t23, pub23, r_p: float) -> str:
    """Why the p-version energy rate of Table 2.3 is not reproduced (numbers of this run;
    ``pub23``: the published Table 2.3)."""
    tp = t23[t23.series == "p"].sort_values("p")
    th = t23[t23.series == "h"].sort_values("h_inv")
    pub = pub23[pub23.series == "p"].set_index("p")
    hi = tp[tp.p >= 2].set_index("p")
    ratio = pub.loc[hi.index, "h1_error"] / hi["h1_error"]
    interp = (tp.h1_error / tp.h1_interp_exact - 1.0).abs()[tp.p >= 3]
    return (
        f"last p-version H1 rate {r_p:.3f} (w.r.t. p). The H1 error in Omega2 is the "
        "interpolation error of the r^(2/3) corner on the fixed post-processing mesh: it "
        "equals the error of the same Q_p interpolant of the exact u to "
        f"{100 * interp.max():.1f} % for p >= 3. The published H1 errors lie "
        f"{ratio.min():.2f}-{ratio.max():.2f}x above ours for p >= 2, although the FE "
        "errors of the same runs equal Table 2.4 to the printed digits and the same "
        "measure reproduces Table 2.1 and the h-version here; we found no post-processing "
        "that gives them. The BE solution itself converges much faster: its trace energy "
        "error |u - U2|_W (the BE part of the norm of Theorem 2.2.3) has the rate "
        f"{tp.trace_energy_rate.iloc[-1]:.2f} in p (h-version: "
        f"{th.trace_energy_rate.iloc[-1]:.2f} in h), because u = 0 on both Gamma_D sides "
        "of the corner: the trace is smooth. So the printed 0.8 (and the 2/3 of the "
        "h-version) measure the resolution of r^(2/3) by the post-processing mesh, not the "
        "5/6 of Theorem 2.2.3 (the measured rate lies in the theory band [5/6, 4/3]).")


def p_vs_h(t23) -> tuple:
    """The p-version's last BE energy rate above the h-version's, its L2 rate below."""
    r_h, r_p = last(t23, "h", 1, "h1_rate"), last(t23, "p", None, "h1_rate")
    l2_h, l2_p = last(t23, "h", 1, "l2_rate"), last(t23, "p", None, "l2_rate")
    return (bool(r_p > r_h and l2_p < l2_h),
            f"energy {r_p:.3f} vs {r_h:.3f}, L2 {l2_p:.3f} vs {l2_h:.3f}")


def be_postprocessing(fe, be_h, be_p) -> tuple:
    """The ratios reproduced / published of Table 2.4 (``fe``) within 1 %, of the BE
    h-version rows (``be_h``) within a factor 2, of the BE p-version rows p >= 2
    (``be_p``) not."""
    return (bool(fe.between(0.99, 1.01).all() and be_h.between(0.5, 2.0).all()
                 and not be_p.between(0.5, 2.0).all()),
            f"the FE errors of the same solves equal Table 2.4 (reproduced/published in "
            f"[{fe.min():.3f}, {fe.max():.3f}], {len(fe)} entries), the BE measure reproduces "
            f"the h-version rows ([{be_h.min():.3f}, {be_h.max():.3f}]), only the BE "
            f"p-version rows p >= 2 are off ([{be_p.min():.3f}, {be_p.max():.3f}]). A "
            "hypothesis, not an explanation: it locates the difference but no "
            "post-processing we tried gives the printed numbers.")


def p_faster(t24, sg_h, sg_p) -> tuple:
    """The last FE H1 error of the p-version below the h-version's, with fewer DOF."""
    e_p, e_h = last(t24, "p", None, "h1_error"), last(t24, "h", 1, "h1_error")
    return (bool(e_p < e_h and sg_p.dof.max() < sg_h.dof.max()),
            f"p-version H1 error {e_p:.3e} with {int(sg_p.dof.max())} DOF vs h-version "
            f"{e_h:.3e} with {int(sg_h.dof.max())} DOF")


def l2_rate_scatter(table, pub, keys, tol: float) -> tuple | None:
    """In each h-version row whose L2 rate is off the published one by more than
    ``tol``, the published rate lies farther from p+1 than ours; None if none is off."""
    m = table.merge(pub, on=list(keys), suffixes=("", "_pub"))
    m = m[(m.series == "h") & ((m.l2_rate - m.l2_rate_pub).abs() > tol)]
    if m.empty:
        return None
    closer = ((m.l2_rate - (m.p + 1)).abs() < (m.l2_rate_pub - (m.p + 1)).abs()).all()
    return (bool(closer), "off L2 rates ours/published: " + ", ".join(
        f"p={int(r.p)} h^-1={int(r.h_inv)}: {r.l2_rate:.2f}/{r.l2_rate_pub:.2f}"
        for r in m.itertuples()) + ". A reading of the printed table: what the thesis "
                                   "computed differently on these meshes is not known.")


def exponential(sm_p) -> tuple:
    """Each degree reduces the FE H1 error by a factor below 0.35."""
    q = sm_p.fe_h1.to_numpy()[1:] / sm_p.fe_h1.to_numpy()[:-1]
    return (bool(np.all(q < 0.35)), "FE H1 error ratios per degree: "
            + ", ".join(f"{v:.3f}" for v in q)
            + " (a fixed reduction factor per degree = exponential in p)")


def solution_range(lo: float, hi: float, top: float) -> tuple:
    """The computed range lo..hi is 0..top within 0.02."""
    return (bool(abs(lo) < 0.02 and abs(hi - top) < 0.02),
            f"computed range {lo:.4f}..{hi:.4f}")


def fastest(wp, examples) -> tuple:
    """Per example, the fastest run reaching 3 x the smallest p-version error; holds if
    for the smooth one that is a p-version run."""
    best = {}
    for name in examples:
        d = wp[wp.problem == name]
        err = d.fe_h1 + d.be_h1
        hit = d[err <= float(err[d.series == "p"].min()) * 3]
        best[name] = hit.sort_values("wall_time_s").iloc[0] if len(hit) else None
    return (bool(best["smooth"] is not None and best["smooth"].series == "p"),
            "; ".join(f"{k}: fastest to reach the target error: {v.series}-version p={v.p} "
                      f"({v.wall_time_s:.3f} s)" for k, v in best.items() if v is not None))


# ------------------------------------------------------------ Example 3 (lambda_Nit)
def last_rate(df, part, x, norm="h1") -> float:
    g = df.sort_values(x)
    return float(observed_rates(1.0 / np.asarray(g[x], float),
                                np.asarray(g[f"{part}_{norm}"], float))[-1])


def max_rel_diff(a, b, cols=ERRORS) -> float:
    """Largest |a/b - 1| over the error columns (rows matched by position)."""
    r = np.concatenate([(a[c].to_numpy() / b[c].to_numpy()) for c in cols])
    return float(np.max(np.abs(r - 1.0)))


def deviations(d, ref, star) -> pd.DataFrame:
    """Per mesh and p: the largest |e / e_ref - 1| over the four errors against the
    reference lambda, and lambda* of that mesh."""
    key = ["series", "p", "fe_h_inv", "be_h_inv"]
    m = d.merge(ref, on=key, suffixes=("", "_ref")).merge(star, on=key)
    dev = np.max([np.abs(m[c] / m[f"{c}_ref"] - 1.0) for c in ERRORS], axis=0)
    return m[key + ["lambda_nit", "lambda_star"]].assign(dev=dev)


def _points(df) -> str:
    return ", ".join(f"{r.series}-version p={r.p} FE 1/{r.fe_h_inv:g}: {r.dev:.1%} "
                     f"(lambda* {r.lambda_star:.2f})" for r in df.itertuples()) or "none"


def no_convergence(d) -> tuple:
    """Smooth, p = 1: the last FE energy rate below SLOWER."""
    g = d[d.p == 1].sort_values("fe_h_inv")
    r = last_rate(g, "fe", "fe_h_inv")
    return (bool(r < SLOWER), f"last FE energy rate {r:.2f}; FE energy errors p=1: "
            + ", ".join(f"{v:.3e}" for v in g.fe_h1))


def _rates_p3(d, ref) -> tuple:
    g, g20 = d[d.p == 3], ref[ref.p == 3]
    return (last_rate(g, "fe", "fe_h_inv"), last_rate(g20, "fe", "fe_h_inv"),
            last_rate(g, "be", "be_h_inv"), last_rate(g20, "be", "be_h_inv"), g, g20)


def reduced_p3(d, ref) -> tuple:
    """Smooth, p = 3: the FE or BE energy rate more than SLOWER below the reference's."""
    rf, rf20, rb, rb20, g, g20 = _rates_p3(d, ref)
    return (bool((rf < rf20 - SLOWER) or (rb < rb20 - SLOWER)),
            f"last energy rates p=3: FE {rf:.2f} (lambda=20: {rf20:.2f}), BE {rb:.2f} "
            f"(lambda=20: {rb20:.2f}); largest deviation from lambda=20 "
            f"{max_rel_diff(g, g20):.1%}")


def below_threshold(d, ref, star, lambda_nit) -> tuple:
    """lambda_nit below lambda*(3) on every mesh, the p = 3 rates within RATE_TOL of
    the reference's."""
    rf, rf20, rb, rb20, _, _ = _rates_p3(d, ref)
    s3 = star[star.p == 3].lambda_star
    return (bool((s3 > lambda_nit).all() and abs(rf - rf20) <= RATE_TOL
                 and abs(rb - rb20) <= RATE_TOL),
            f"lambda*(3) = {s3.min():.2f}..{s3.max():.2f} over the meshes FE h^-1 = "
            + ", ".join(f"{v:g}" for v in star[star.p == 3].fe_h_inv)
            + f"; last energy rates FE {rf:.2f} / {rf20:.2f}, BE {rb:.2f} / {rb20:.2f} "
              "(lambda = 5 / 20)")


def same_rates(d, ref, degrees) -> tuple:
    """The last rates (FE/BE, L2/energy) within RATE_TOL of the reference's."""
    diff = {p: max(abs(last_rate(d[d.p == p], part, h, norm)
                       - last_rate(ref[ref.p == p], part, h, norm))
                   for part, h in (("fe", "fe_h_inv"), ("be", "be_h_inv"))
                   for norm in ("h1", "l2")) for p in degrees}
    return (bool(max(diff.values()) <= RATE_TOL),
            "largest difference of the last rates (FE/BE, L2/energy) to lambda = 20: "
            + ", ".join(f"p={p}: {v:.3f}" for p, v in diff.items())
            + f" (tolerance {RATE_TOL})")


def same_errors(d, ref, star, degrees) -> tuple:
    """All errors within SAME of the reference's; where the largest differences are."""
    devs = {p: max_rel_diff(d[d.p == p].sort_values("fe_h_inv"),
                            ref[ref.p == p].sort_values("fe_h_inv")) for p in degrees}
    dv = deviations(d, ref, star)
    finest = dv[dv.fe_h_inv == dv.fe_h_inv.max()]
    return (bool(max(devs.values()) <= SAME),
            "largest relative difference of the errors to lambda = 20: " + ", ".join(
                f"p={p}: {v:.1%}" for p, v in devs.items()) + "; on the finest mesh: "
            + ", ".join(f"p={r.p}: {r.dev:.1%}" for r in finest.itertuples())
            + ". Largest: " + _points(dv.loc[[dv.dev.idxmax()]]) + "; meshes where lambda "
            "= 10 is below lambda*: " + _points(dv[dv.lambda_nit < dv.lambda_star])
            + " (coercivity does not single out the largest difference)")


def same_curves(d, sref) -> tuple:
    """Singular: the h- and p-version errors within SAME of the largest lambda's."""
    key = ["series", "p", "dof"]
    dh = max_rel_diff(d[d.series == "h"].sort_values(key),
                      sref[sref.series == "h"].sort_values(key))
    dp = {p: max_rel_diff(d[(d.series == "p") & (d.p == p)],
                          sref[(sref.series == "p") & (sref.p == p)])
          for p in sorted(d[d.series == "p"].p.unique())}
    return (bool(max([dh] + list(dp.values())) <= SAME),
            f"largest relative difference to lambda = {sref.lambda_nit.iloc[0]:g}: "
            f"h-version {dh:.1%}; p-version " + ", ".join(f"p={p}: {v:.1%}"
                                                          for p, v in dp.items()))


def coercivity(d, sref, star) -> tuple:
    """No point changes by more than SAME where lambda_Nit > lambda* of its mesh."""
    dv = deviations(d, sref, star)
    changed = dv[dv.dev > SAME]
    coercive_changed = changed[changed.lambda_nit > changed.lambda_star]
    below_same = dv[(dv.lambda_nit < dv.lambda_star) & (dv.dev <= SAME)]
    return (bool(coercive_changed.empty),
            f"{len(changed)} of {len(dv)} points change; changed although lambda_Nit > "
            f"lambda*: {_points(coercive_changed)}; lambda_Nit < lambda* but unchanged: "
            f"{_points(below_same)}; the largest change: {_points(dv.loc[[dv.dev.idxmax()]])}"
            ". Coercivity (computed on the same meshes, same alpha and h1) does not "
            "separate the curves that change from those that do not.")


def differs(d, sref) -> tuple:
    """Some error differs by more than SAME from the largest lambda's."""
    key = ["series", "p", "dof"]
    dev = max_rel_diff(d.sort_values(key), sref.sort_values(key))
    return (bool(dev > SAME), f"largest relative difference to lambda = "
                              f"{sref.lambda_nit.iloc[0]:g}: {dev:.2%}")


# ------------------------------------------------------------ Lemma 2.2.3
def thresholds(a0) -> str:
    """Where lambda_Nit = 1, 5, 10 lie relative to lambda* (alpha = 0) for p = 1, 2, 3."""
    lines = []
    for p in (1, 2, 3):
        g = a0[a0.p == p]
        if g.empty:
            continue
        lo, hi = g.lambda_star.min(), g.lambda_star.max()
        rel = ", ".join(f"lambda={v} {'above' if v > hi else 'below' if v < lo else 'at'}"
                        for v in THESIS_LAMBDAS)
        lines.append(f"p={p}: lambda* in [{lo:.3f}, {hi:.3f}] over meshes "
                     f"{', '.join(g.mesh)}: {rel}")
    return "; ".join(lines)


def threshold_growth(main) -> tuple:
    """With alpha = 0, lambda*(p) strictly increasing in p."""
    g0 = main[main.alpha == 0.0].sort_values("p")
    return (bool(np.all(np.diff(g0.lambda_star) > 0)),
            "lambda*(p) = " + ", ".join(f"{v:.2f}" for v in g0.lambda_star))


def lemma(main) -> tuple:
    """lambda* below the sufficient bound of Lemma 2.2.3 everywhere."""
    return (bool(np.all(main.lambda_star <= main.lemma_bound)),
            "lambda* / bound = " + ", ".join(
                f"{v:.2f}" for v in (main.lambda_star / main.lemma_bound)))


def example3(table) -> tuple:
    """lambda*(1) in (1, 5) and lambda*(3) in (5, 10) on every mesh (alpha = 0)."""
    a0 = table[table.alpha == 0.0]
    s1, s3 = a0[a0.p == 1].lambda_star, a0[a0.p == 3].lambda_star
    return (bool(1 < s1.min() and s1.max() < 5 and 5 < s3.min() and s3.max() < 10),
            thresholds(a0))
