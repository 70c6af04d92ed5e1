"""The scene ``hp_rate`` of ``experiments.ch3_penalty_hp``: Theorem 3.2.6 (thesis lines
8363-8480), eps = C_pen (h/p)^{1-epsilon}, the energy error against the reference
solution, the corner singularity that limits the rate (figure_penalty_hp_rate)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe.contact import singular_exponent
from hpfebe.scenes import penalty as scene, penalty_readings as rd
from hpfebe.suite import (ArtefactResult, Claim, new_figure, progress, rate_claim,
                          slope_line, style_axes, timed)

Params = scene.PenaltyHpScene


def beyond(claim: Claim) -> Claim:
    """``claim`` as a result beyond the thesis."""
    return replace(claim, kind="beyond")


def rate_claims(rate_tab: pd.DataFrame, prm: Params, lam: float) -> list[Claim]:
    """Theorem 3.2.6 (C = C_pen[0]); with the penalty error negligible (C = C_pen[-1]) the
    corner singularity: rate lambda in h, p^(-2 lambda); higher p, smaller error."""
    hp = prm.hp_rate
    predicted = 1.0 - hp.epsilon
    claims = [Claim(
        f"Theorem 3.2.6: with eps = C (h/p)^(1-epsilon) (C = {hp.C_pen[0]:g}, epsilon = "
        f"{hp.epsilon:g}) the energy error ||u - U^eps|| = O((h/p)^(1-epsilon)) = "
        f"O((h/p)^{predicted:.2f}) (observed rate in h >= {predicted - 0.1:.2f} for "
        "every p)", *rd.theorem(rate_tab, prm, lam), id="theorem_3_2_6")]
    if len(hp.C_pen) > 1:
        worst, ev = rd.singular_h(rate_tab, prm, lam)
        claims.append(beyond(rate_claim(
            "(beyond the thesis) the hypothesis u in H~^(3/2)(Sigma) of Theorem 3.2.6 "
            "fails here: with the penalty error negligible, the uniform-mesh rate in h "
            f"is the corner singularity exponent lambda = {lam:.3f} (clamped/free "
            f"right angle, plane strain nu = {prm.nu:g}) for every p, not the h/p rate 1 "
            "(finest rate within 0.1 of lambda)", worst, lam, 0.1,
            what="finest rate in h (the p farthest from lambda)")))
        claims[-1].evidence += ev
        sp = rd.singular_p(rate_tab, prm)
        if sp is not None:
            rp, p_lo, p_hi, ev = sp
            claims.append(beyond(rate_claim(
                f"(beyond the thesis) p-refinement on a fixed uniform mesh converges "
                f"like p^(-2 lambda) = p^(-{2 * lam:.2f}) (p-version at a node "
                "singularity; Theorem 3.2.6 would give p^-1): observed within 0.25",
                rp, 2 * lam, 0.25, what=f"rate in p between p={p_lo} and p={p_hi}")))
            claims[-1].evidence += ev
    return claims + [Claim(f"Higher p gives a smaller error on the same mesh (C = {C:g})",
                           *rd.p_smaller(rate_tab, prm, C), kind="beyond")
                     for C in hp.C_pen]


def rate_figure(rate_tab: pd.DataFrame, prm: Params) -> Figure:
    hp = prm.hp_rate
    predicted = 1.0 - hp.epsilon
    fig, ax = new_figure((6.5, 4.8))
    colors = dict(zip(hp.p, ["C0", "C1", "C2", "C3", "C4", "C5"]))
    for (C, p), g in rate_tab.groupby(["C_pen", "p"], sort=False):
        main = C == hp.C_pen[0]
        ax.loglog(g.dof, g.energy_error, "o-" if main else "s--", color=colors.get(p),
                  alpha=1.0 if main else 0.6, label=f"p = {p}, C = {C:g}")
    dd = np.array([rate_tab.dof.min(), rate_tab.dof.max()], float)
    e0 = rate_tab.energy_error.max()
    slope_line(ax, dd, -predicted, (dd[0], 1.2 * e0), alpha=0.6,
               label=f"DOF^-{predicted:.2f} (Thm 3.2.6)")
    slope_line(ax, dd, -1.0, (dd[0], 0.5 * e0), "k:", alpha=0.6,
               label="DOF^-1 (h/p, smooth u)")
    style_axes(ax, "DOF", r"$\|I U^\epsilon - U_{ref}\|_{\hat S}$",
               f"hp-penalty BEM, eps = C (h/p)^{predicted:g}",
               legend=dict(fontsize="x-small", ncol=2))
    return fig


def rate_result(prm: Params, jit_s: float) -> ArtefactResult:
    (rows, ref), hp_s = timed(scene.hp_rate_rows, prm, progress)
    rate_df = pd.DataFrame(rows)
    rate_tab = rate_df[["p", "n_per_side", "h", "dof", "eps", "energy_error", "rate",
                        "newton_iterations", "wall_time_s", "C_pen", "rate_dof",
                        "energy_error_rel", "err_norm_diff", "final_residual",
                        "newton_s"]].copy().reset_index(drop=True)
    lam = singular_exponent(prm.nu, scene.PLANE)
    claims = rate_claims(rate_tab, prm, lam)
    notes = (
        f"Reference: n_ref = {ref['n_ref']}, p_ref = {ref['p_ref']}, eps_ref = "
        f"{ref['eps_ref']:.3g}, DOF {ref['dof_ref']}, ||U_ref||_S = {ref['norm_ref']:.10f} "
        f"(x sqrt2 = {prm.norm_scale * ref['norm_ref']:.6f}; Table 3.1 limit 0.154398). "
        "energy_error = ||I U - U_ref||_{S_ref} (absolute, our norm scale); "
        "energy_error_rel divides by ||U_ref||_S; err_norm_diff = |<S U,U>^(1/2) - "
        "||U_ref||_S| (Table 3.1 style, ~ square of the energy error). rate/rate_dof NaN "
        "on the first mesh of each (C_pen, p) (allowed). wall_time_s = Newton + error "
        "evaluation (+ S_hat assembly on the first C_pen of a mesh); newton_s = Newton "
        f"only. Corner exponent lambda = {lam:.4f}. Choices: " + " ".join(scene.HP_RATE_CHOICES))
    meta = dict(jit_s=round(jit_s, 3), run_s=round(hp_s, 3), C_pen=list(prm.hp_rate.C_pen),
                epsilon=prm.hp_rate.epsilon,
                final_rates={f"C={C:g}": {p: float(v[-1]) for p, v in
                                          rd.final_rates(rate_tab, C).items()}
                             for C in prm.hp_rate.C_pen},
                corner_exponent=lam,
                reference={k: (float(v) if isinstance(v, float) else v)
                           for k, v in ref.items()},
                max_dof=int(rate_tab.dof.max()),
                allow_nan_columns=["rate", "rate_dof"])
    hp = prm.hp_rate       # ParaView: the highest p on the finest mesh, C_pen[0]
    n, p = hp.n_per_side[-1], max(hp.p)
    vtu = scene.representative_exports(prm, n, p, hp.C_pen[0] * (1.0 / n / p)
                                       ** (1.0 - hp.epsilon), -prm.d)
    return ArtefactResult(name="figure_penalty_hp_rate", table=rate_tab,
                          figure=rate_figure(rate_tab, prm), claims=claims, notes=notes,
                          meta=meta, exports=vtu)
