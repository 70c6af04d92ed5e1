"""Table 3.1 and Figure 3.1: penalty h-BEM for frictionless contact with a rigid line.

Section 3.2.5 (thesis lines 8540-8640).  Omega = [-1,1]^2, Gamma_D = [-1,1] x {1} (u = 0),
Gamma_C = [-1,1] x {-1}, Gamma_N = the vertical sides (traction free), rigid straight
obstacle y = -1 + d (d = 2e-4) moving up into the body, E = 266926, nu = 0.29, p = 1 on
uniform meshes with n elements per side (:mod:`hpfebe.scenes.penalty`).
Penalty formulation (3.45)-(3.46) with the discrete Steklov-Poincare operator S_hat
(Section 1.4):

    <S_hat U, v> + (1/eps) int_{Gamma_C} (U_n - g)_+ v_n ds = 0,   g = -d,   eps = C_eps h,

solved by :func:`hpfebe.contact.solve_penalty` (semismooth Newton, exact integration of the
positive part).  Error (thesis): err(U) = | <S_hat U, U>^(1/2) - ||u_lim||_S |, with
||u_lim||_S = 0.154398 from Aitken extrapolation (the thesis writes the difference the
other way round; the tabulated errors are positive and <S_hat U, U>^(1/2) grows towards the
limit, so the absolute value is meant).  The choices where the thesis is silent are
:data:`CHOICES`.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from hpfebe.analysis import aitken, observed_rates
from hpfebe.scenes import penalty as scene
from hpfebe.suite import (ArtefactResult, Claim, from_config, new_figure, progress,
                          published_table, rate_claim, slope_line, style_axes, timed)

ARTEFACTS = ("table_3_1", "figure_3_1")

log = logging.getLogger(__name__)

#: ||u_lim||_S of Table 3.1 (thesis's Aitken extrapolation, its norm scale)
PUBLISHED_ULIM = 0.154398

CHOICES = (
    "h = 1/n (n elements per side) - this reproduces the tabulated eps (DOF 22 <-> n = 4).",
    "DOF = the free displacement unknowns, 2 (3n - 1) (22, 46, ..., 766 as in the table).",
    "Plane strain and plane stress are both run; the one whose Aitken limit matches "
    "0.154398 is reported in the err column, the other beside it.",
    "Norm scale: the thesis's energy norms are sqrt(2) times ours for the same E, nu "
    "(S_hat of this package passes an exact patch test: S_hat U = int sigma(u) n . v for "
    "every linear and quadratic elastic field). All 24 tabulated errors are reproduced "
    "only with that factor; norm_scale (default sqrt(2)) is applied and the unscaled "
    "values are kept in err_unscaled. Since the problem is linear in d once Gamma_C is in "
    "full contact, the factor is exactly what an obstacle shift d sqrt(2) = 2.83e-4 or a "
    "norm convention (2 <S_hat U, U>)^(1/2) gives (checked: n = 4, C_eps = 1e-4: "
    "0.0326598 with d sqrt(2) against the published 0.154398 - 0.121739 = 0.0326594); "
    "doubling E at the same eps does not (0.01826). The thesis's code is not available to "
    "decide which.",
    "||u_lim||_S is our own Aitken extrapolation of <S_hat U,U>^(1/2) over the three "
    "finest meshes of the smallest C_eps (shown beside 0.154398); err uses it.",
)

#: the parameters of the scene (config section ch3_penalty)
Params = scene.PenaltyScene


def error_table(data: pd.DataFrame, prm: Params, ulim: dict, best: str) -> pd.DataFrame:
    """Table 3.1: err = |scale (||u_lim|| - <S_hat U,U>^(1/2))| of the eps = C_eps h runs of
    plane ``best``, the other plane's err beside it."""
    scale = prm.norm_scale
    other = [pl for pl in prm.planes if pl != best]
    main = data[(data.plane == best) & (data.kind == "C_eps h")].copy()
    main["err"] = (scale * (ulim[best] - main.norm)).abs()
    main["err_published_ulim"] = (PUBLISHED_ULIM - scale * main.norm).abs()
    main["err_unscaled"] = (ulim[best] - main.norm).abs()
    main["norm_S"] = main.norm
    main["ulim_S"] = ulim[best]
    if other:
        o = data[(data.plane == other[0]) & (data.kind == "C_eps h")].set_index(["C_eps", "n"])
        main["err_" + other[0]] = [abs(scale * (ulim[other[0]] - o.loc[(c, n), "norm"]))
                                   for c, n in zip(main.C_eps, main.n)]
    main = main.sort_values(["C_eps", "n"], ascending=[False, True])
    cols = ["C_eps", "dof", "eps", "err", "err_published_ulim", "err_unscaled", "norm_S",
            "ulim_S"] + (["err_" + other[0]] if other else []) + \
        ["n", "newton_iterations", "final_residual", "min_pressure", "max_pressure",
         "wall_time_s", "assembly_s"]
    return main[cols].reset_index(drop=True)


# --------------------------------------------------------------------------- claims
PUBLISHED_FILE = "table_3_1_penalty_eps.csv"
LINEAR_TOL = 0.15                  # "the linear rate is achieved": rate within 0.15 of 1
LINEAR_TOLS = (0.1, 0.15, 0.2)     # ... and the tolerances the comparison must survive


def _published_rates(dofs=None) -> dict:
    """Observed rates of the published Table 3.1 per C_eps, from its second mesh on
    (only the rows with DOF in ``dofs``, if given)."""
    pub = published_table(PUBLISHED_FILE)
    if dofs is not None:
        pub = pub[pub.dof.isin(list(dofs))]
    # rates in h = 1/n, n = (dof/2 + 1)/3 elements per side (DOF = 2 (3n - 1))
    return {C: observed_rates(3.0 / (g.dof.to_numpy() / 2 + 1), g.err.to_numpy())[1:]
            for C, g in pub.groupby("C_eps", sort=False)}


def _first_linear(n, rates, tol) -> int | None:
    """The first mesh (n per side) whose rate is within ``tol`` of 1 (rates[k] belongs to
    n[k + 1])."""
    ok = np.flatnonzero(np.abs(np.asarray(rates) - 1.0) <= tol)
    return int(n[ok[0] + 1]) if ok.size else None


def _monotone(first: list) -> bool:
    """Reached on coarser (or the same) meshes as C_eps decreases (None: never)."""
    order = [np.inf if f is None else f for f in first]
    return bool(all(a >= b for a, b in zip(order[:-1], order[1:])))


def ulim_claim(prm: Params, ulim: dict, best: str) -> Claim:
    scale = prm.norm_scale
    rel = abs(scale * ulim[best] - PUBLISHED_ULIM) / PUBLISHED_ULIM
    ev = "; ".join(f"plane {pl}: Aitken limit {ulim[pl]:.6f} (x sqrt2-scale {scale:.6g}: "
                   f"{scale * ulim[pl]:.6f})" for pl in prm.planes)
    ev += (f". Plane {best} matches to {rel:.1e} relative with the norm scale {scale:.6g} "
           "(see notes); ")
    ev += "".join(f"plane {pl} differs by "
                  f"{abs(scale * ulim[pl] - PUBLISHED_ULIM) / PUBLISHED_ULIM:.1e}."
                  for pl in prm.planes if pl != best)
    return Claim(text=f"||u_lim||_S = {PUBLISHED_ULIM} (Aitken extrapolation)",
                 holds=bool(rel < 1e-4), evidence=ev, id="ulim")


def norm_scale_hypothesis(table: pd.DataFrame, prm: Params) -> Claim:
    """The reading that makes ||u_lim||_S and the err column match: the thesis's norms
    are ``norm_scale`` x ours.  A factor read off the published limit, not derived."""
    pub = published_table(PUBLISHED_FILE)
    m = table.merge(pub, on=["C_eps", "dof"], suffixes=("", "_pub"))
    scaled, unscaled = m.err / m.err_pub, m.err_unscaled / m.err_pub
    return Claim(
        text=f"the thesis's energy norms are {prm.norm_scale:.6g} x ours (sqrt(2): a norm "
             "convention (2 <S_hat U, U>)^(1/2) or an obstacle shift d sqrt(2); the thesis's "
             "code is not available to decide)",
        holds=bool(scaled.between(1 / 1.1, 1.1).all()
                   and not unscaled.between(1 / 1.1, 1.1).any()),
        evidence=f"with the factor, err / published err in [{scaled.min():.4f}, "
                 f"{scaled.max():.4f}] over {len(m)} entries; without it in "
                 f"[{unscaled.min():.4f}, {unscaled.max():.4f}]. A factor read off "
                 "||u_lim||_S, not derived: the match of ||u_lim||_S and of the err column "
                 "rests on it.", kind="hypothesis", id="norm_scale", explains=("ulim",))


def rate_claims(table: pd.DataFrame, prm: Params) -> list[Claim]:
    """Linear rate for C_eps <= 1e-5; reached on coarser meshes as C_eps decreases."""
    rates, first_linear = {}, {}
    for C in prm.C_eps:
        sub = table[table.C_eps == C]
        rates[C] = observed_rates(1.0 / sub.n.to_numpy(), sub.err.to_numpy())
        first_linear[C] = _first_linear(sub.n.to_numpy(), rates[C][1:], LINEAR_TOL)
    text = "For C_eps <= 1e-5 the linear rate err ~ h is achieved"
    every = "; ".join(f"C_eps={C:g}: rates " + ", ".join(f"{x:.2f}" for x in rates[C][1:])
                      for C in prm.C_eps)
    small = [rates[C][-1] for C in prm.C_eps if C <= 1e-5]
    if small:
        claim = replace(rate_claim(text, max(small, key=lambda r: abs(r - 1.0)), 1.0, 0.15,
                                   what="finest rate (the worst C_eps <= 1e-5)"),
                        id="linear_rate")
        claim.evidence += ". " + every
    else:
        claim = Claim(text, None, "no C_eps <= 1e-5 in the sweep. " + every,
                      id="linear_rate")
    claims = [claim]
    decreasing = sorted(prm.C_eps, reverse=True)
    mono = _monotone([first_linear[C] for C in decreasing])
    ev = f"first mesh (n per side) with rate within {LINEAR_TOL} of 1: " + ", ".join(
        f"C_eps={C:g}: {first_linear[C]}" for C in decreasing)
    pub = _published_rates()
    if pub:
        ev += ". The thesis's own Table 3.1 gives the rates " + "; ".join(
            f"C_eps={C:g}: " + ", ".join(f"{x:.2f}" for x in r) for C, r in pub.items())
    if not mono:
        ev += (". Not monotone for the smallest C_eps, in the published numbers as in ours: "
               "once the penalty error is negligible, what remains is the discretisation "
               "error of the contact problem, whose rate is still below 1 on coarse meshes")
    claims.append(Claim(text="With decreasing C_eps the linear rate is reached on coarser "
                             "meshes", holds=mono, evidence=ev, id="coarser"))
    if not mono and pub:
        claims.append(_same_as_published(table, decreasing, rates))
    return claims


def _same_as_published(table, decreasing, rates) -> Claim:
    """Explanation of a failed "coarser meshes" claim: the published rates (on the
    meshes run) give the same first linear mesh per C_eps as ours at every tolerance of
    LINEAR_TOLS, so the statement fails on the thesis's own numbers as on ours."""
    n = np.sort(table.n.unique())
    pub = _published_rates(table.dof.unique())
    same, verdicts = True, []
    for tol in LINEAR_TOLS:
        ours = [_first_linear(n, rates[C][1:], tol) for C in decreasing]
        theirs = [_first_linear(n, pub[C], tol) if C in pub else None for C in decreasing]
        same &= ours == theirs
        verdicts.append(f"tolerance {tol:g}: ours {ours}, published {theirs} "
                        f"({'monotone' if _monotone(theirs) else 'not monotone'})")
    pub_fails = not _monotone([_first_linear(n, pub[C], LINEAR_TOL) if C in pub else None
                               for C in decreasing])
    return Claim(
        text="the thesis's own Table 3.1 contradicts the statement in the same way: its "
             "rates give the same first linear mesh per C_eps as ours",
        holds=bool(same and pub_fails),
        evidence="first mesh with a rate within the tolerance of 1, C_eps = "
                 + ", ".join(f"{C:g}" for C in decreasing) + ": " + "; ".join(verdicts)
                 + ". The difference is between the sentence and the thesis's table, not "
                   "between the thesis's computation and ours.",
        kind="explanation", id="same_as_published", explains=("coarser",))


def fixed_eps_claim(data: pd.DataFrame, prm: Params, ulim: dict, best: str) -> Claim:
    fx = data[(data.plane == best) & (data.kind == "fixed")]
    ev, holds = [], True
    for e in prm.fixed_eps:
        s = fx[fx.eps == e].sort_values("n")
        er = (prm.norm_scale * (ulim[best] - s.norm)).abs().to_numpy()
        ratio = er[-2] / er[-1]
        holds &= bool(ratio < 1.2)
        ev.append(f"eps={e:g}: err " + ", ".join(f"{x:.3e}" for x in er)
                  + f" (last ratio {ratio:.3f})")
    return Claim(text="For a fixed penalty parameter the error does not decrease when the "
                      "mesh is refined", holds=holds, evidence="; ".join(ev), id="fixed_eps")


def newton_claim(data: pd.DataFrame) -> Claim:
    it_max = int(data.newton_iterations.max())
    return Claim(
        kind="beyond",
        text="(solver) semismooth Newton converges in a bounded number of iterations",
        holds=bool(it_max <= 10),
        evidence=f"max {it_max} Newton iterations over all runs (the whole of Gamma_C is in "
                 "contact from the first iterate, so one Newton step solves the piecewise "
                 "linear system exactly); final residuals <= "
                 f"{data.final_residual.max():.1e}; contact pressure >= "
                 f"{data.min_pressure.min():.3g}")


# --------------------------------------------------------------------------- figure
def figure(table: pd.DataFrame, prm: Params, best: str) -> Figure:
    fig, ax = new_figure((6.0, 4.5))
    for C in prm.C_eps:
        sub = table[table.C_eps == C]
        ax.loglog(sub.dof, sub.err, "o-", label=f"$C_\\epsilon$ = {C:g}")
    dref = table.dof.drop_duplicates().sort_values().to_numpy()
    e0 = table[table.C_eps == min(prm.C_eps)].err.iloc[-1]
    slope_line(ax, dref, -1.0, (dref[-1], 1.5 * e0), alpha=0.6, label="slope -1 (h)")
    ax.xaxis.set_minor_formatter(NullFormatter())  # overlapping minor-tick labels
    style_axes(ax, "DOF", r"err$(U^\epsilon)$", f"Penalty h-BEM, eps = C_eps h (plane {best})",
               legend=dict(fontsize="small"))
    return fig


# --------------------------------------------------------------------------- run
def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    """Table 3.1 and Figure 3.1 (``quick`` is unused: config/quick.yaml sets the sizes)."""
    prm = from_config(Params, config, scene="ch3_penalty")
    jit_s = scene.warm_up(prm)  # compile (or load the numba cache)
    data, run_s = timed(lambda: pd.DataFrame([r for pl in prm.planes
                                              for r in scene.penalty_sweep(prm, pl, progress)]))

    # ||u_lim||_S: Aitken over the three finest meshes of the smallest C_eps, per plane
    Cmin = min(prm.C_eps)
    ulim = {}
    for pl in prm.planes:
        seq = data[(data.plane == pl) & (data.C_eps == Cmin)].sort_values("n").norm.to_numpy()
        ulim[pl] = aitken(*seq[-3:])
    scale = prm.norm_scale
    best = min(prm.planes, key=lambda pl: abs(scale * ulim[pl] - PUBLISHED_ULIM))
    table = error_table(data, prm, ulim, best)

    claims = [ulim_claim(prm, ulim, best), norm_scale_hypothesis(table, prm)] + \
        rate_claims(table, prm)
    if prm.fixed_eps:
        claims.append(fixed_eps_claim(data, prm, ulim, best))
    claims.append(newton_claim(data))

    notes = (
        f"Plane {best} reproduces ||u_lim||_S (ours: {ulim[best]:.7f}, times the norm scale "
        f"{scale:.6g}: {scale * ulim[best]:.6f}; thesis 0.154398). err = |scale * "
        "(||u_lim||_ours - <S_hat U,U>^(1/2))|; err_published_ulim uses the thesis's "
        "0.154398 instead; err_unscaled without the sqrt(2). h = 1/n, eps = C_eps h, DOF = "
        "free unknowns 2(3n-1). S_hat assembled once per mesh and reused for every eps; "
        "wall_time_s = Newton solve (+ S_hat assembly on the first C_eps row of a mesh). "
        "S_hat uses the zero-total-force constraint (scale-invariant, hpfebe.bem.lame). "
        "Choices where the thesis is silent: " + " ".join(CHOICES))
    meta = dict(jit_s=round(jit_s, 3), run_s=round(run_s, 3), planes=list(prm.planes),
                plane_reported=best, ulim={k: float(v) for k, v in ulim.items()},
                norm_scale=scale, max_dof=int(table.dof.max()),
                newton_iterations_max=int(data.newton_iterations.max()),
                allow_nan_columns=[],
                reading=f"the thesis's energy norms taken as {scale:.6g} x ours (read off "
                        "the published limit, not derived: hypothesis norm_scale)")
    common = dict(published=PUBLISHED_FILE, keys=("C_eps", "dof"),
                  tolerances={"err": ("factor", 1.1)}, claims=claims, notes=notes, meta=meta)
    return [ArtefactResult(name="table_3_1", table=table, **common),
            ArtefactResult(name="figure_3_1", table=table, figure=figure(table, prm, best),
                           **common)]
