"""hp-penalty BEM for frictionless contact: the rate of Theorem 3.2.6 and a stability stress test.

Beyond the thesis (issue 4).  The problem is the one of Table 3.1 (thesis lines 8540-8640,
:mod:`experiments.ch3_penalty`, body :func:`hpfebe.contact.limits.square_body`): rigid
line y = -1 + d (g = -d, d = 2e-4), E = 266926, nu = 0.29, plane strain (the plane that
reproduces ||u_lim||_S = 0.154398), uniform meshes with n elements per side, h = 1/n,
polynomial degree p on every element, penalty problem (3.57) solved by
:func:`hpfebe.contact.solve_penalty`.

``figure_penalty_hp_rate`` - Theorem 3.2.6 (thesis lines 8363-8480): if u is in
H~^{3/2}(Sigma), Tu in H^{1/2}(Gamma) and eps >= C~ (h/p)^{1-epsilon}, epsilon in
(0, 1/2), then

    ||u - U^eps||_{H~^{1/2}(Sigma)} <= C ( h/p ||u||_{3/2} + (eps + h/p) ||Tu||_{1/2} ),   (3.81)

i.e. with eps = C_pen (h/p)^{1-epsilon} the energy error is O((h/p)^{1-epsilon}).  The
error is measured against a reference solution on a nested finer mesh:

    energy_error = ||I U - U_ref||_{S_ref},   I = :func:`hpfebe.spaces.prolongate`.

The solution is not in H~^{3/2}(Sigma): the corners where Gamma_D meets Gamma_N (clamped /
traction free at 90 degrees) give displacement singularities r^lambda, lambda < 1
(:func:`hpfebe.contact.limits.singular_exponent`), so on uniform meshes the
discretisation error converges like h^lambda and the observed rate is
min(1 - epsilon, lambda) at best.

``figure_penalty_stability`` - stress test at a fixed mesh, eps = C_eps h down to
C_eps = 1e-20, for the flat obstacle of Table 3.1 (all of Gamma_C in contact; penalty
error against the eps -> 0 limit on the same mesh,
:func:`hpfebe.contact.limits.constrained_limit`) and a tilted one, g(x) = -d + s (x + 1)
(partial contact).  Every run is checked by
:func:`hpfebe.contact.limits.solve_penalty_checked` (condition number, relative residual,
componentwise backward error of G(U) = S_hat U + (1/eps) int (U_n - g_h)_+ v_n = 0).
The choices are :data:`RATE_CHOICES` and :data:`STABILITY_CHOICES`; the two artefacts are
independent :data:`SCENES`.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe.analysis import energy_norm, fitted_rate, observed_rates
from hpfebe.contact import solve_penalty
from hpfebe.contact.limits import (MACHEPS, constrained_limit, saturation_index,
                                   singular_exponent, solve_penalty_checked, square_body)
from hpfebe.suite.params import from_config
from hpfebe.suite.results import ArtefactResult, Claim, progress, rate_claim
from hpfebe.spaces import prolongate

from experiments.ch3_penalty import PUBLISHED_ULIM

ARTEFACTS = ("figure_penalty_hp_rate", "figure_penalty_stability")
#: independent computations: the hp-rate sweep and the fixed-mesh stress test
SCENES = {"hp_rate": ("figure_penalty_hp_rate",), "stability": ("figure_penalty_stability",)}

log = logging.getLogger(__name__)

PLANE = "strain"      # the plane of Table 3.1 that reproduces ||u_lim||_S

RATE_CHOICES = (
    "eps = C_pen (h/p)^{1-epsilon} with C_pen = 1e-6 (the C_eps of Table 3.1 whose rate is "
    "cleanest) and epsilon = 1/4 (the middle of (0, 1/2)); a second sweep with C_pen = "
    "1e-10 (penalty error negligible) separates the discretisation error from the penalty "
    "error.",
    "energy error = ||I U - U_ref||_{S_ref} = ((I U - U_ref)^T S_ref (I U - U_ref))^{1/2}, "
    "the S_hat energy norm (equivalent to the H~^{1/2}(Sigma) norm of Theorem 3.2.6) on "
    "the reference mesh, where I U is the exact embedding of the coarse solution into the "
    "(nested) reference space V_ref (nodal interpolation at the GLL points of the "
    "reference elements; n_ref is a multiple of every n and p_ref >= p, so I is exact) and "
    "U_ref the penalty solution on the reference mesh (n_ref, p_ref = 4) with a tiny "
    "eps_ref = C_ref h_ref / p_ref (C_ref = 1e-10: its own penalty error is ~1e-8 "
    "relative, the stress test shows this eps is numerically harmless). The error of "
    "U_ref itself is not included, so the errors of the finest meshes are slightly "
    "underestimated; the sweep stops at n_ref / 8 to keep this effect small (measured: "
    "n_ref = 64 instead of 128 changes the finest errors by <= 2% and the rates by "
    "<= 0.02). The Table 3.1-style error |<S_hat U, U>^{1/2} - <S_ref U_ref, "
    "U_ref>^{1/2}| (which behaves like the *square* of the energy error, Galerkin "
    "orthogonality) is given beside it (err_norm_diff).",
    "rate = log(e_{k-1}/e_k) / log(h_{k-1}/h_k) at fixed p (= rate in h/p), and rate_dof = "
    "the same against DOF^{-1}.",
    "DOF = free displacement unknowns 2 (number of V_hp nodes off Gamma_D).",
    "With epsilon = 1/4, 1 - epsilon = 0.75 and the corner exponent lambda = 0.718 "
    "(Williams' equation, nu = 0.29) are close, so the C_pen = 1e-10 sweep is what tells "
    "the penalty and the corner singularity apart (verdicts from the run).",
)

STABILITY_CHOICES = (
    "Fixed mesh n = 16 per side, eps = C_eps h with C_eps = 1e-4 ... 1e-20 (beyond the "
    "1e-12 asked for, to reach the breakdown), p = 1 and p = 2.",
    "flat: the Table 3.1 obstacle (the whole of Gamma_C in contact, so one Newton step "
    "solves the piecewise linear system); err = |0.154398 - sqrt(2) <S_hat U,U>^{1/2}| "
    "(the published limit and the norm scale of experiments.ch3_penalty), and "
    "penalty_error = ||U - U_0||_S / ||U_0||_S against the eps -> 0 limit on the same "
    "mesh, U_0 = the solution with U_n = -d imposed at the contact nodes (computed by "
    "elimination, no penalty, no ill-conditioning).",
    "tilted: g(x) = -d + 4e-4 (x + 1): contact on part of Gamma_C only, contact elements "
    "cut by the free boundary (the semismooth Newton really iterates). There is no "
    "reference limit: err and penalty_error are NaN (allowed) and delta_U = ||U(C_eps) - "
    "U(10 C_eps)||_S / ||U(C_eps)||_S shows whether the solutions still converge as "
    "eps -> 0.",
    "condition_number = numpy.linalg.cond (2-norm) of the Newton matrix S_hat + (1/eps) "
    "J_c(U) at the returned iterate on the free dofs; residual = the solver's final "
    "max-norm residual; relative_residual = residual / max|(S_hat U)_free| (the physical "
    "force scale, independent of eps); backward_error = max_i |G_i(U)| / (|A| |U|)_i "
    "(componentwise backward error, Oettli-Prager, of G(U) = 0 on the free dofs, A the "
    "Newton matrix: for tiny eps the residual cannot drop below ~ macheps (|A| |U|)_i in "
    "the contact rows - the rounding of U_n - g amplified by 1/eps - however exact U is; a "
    "residual in a row without penalty entries is not excused); accepted = the solver "
    "converged and (relative_residual <= 1e-6 or backward_error <= 20 macheps); LAPACK's "
    "ill-conditioning warnings (rcond < machine eps) are caught and appended to reason.",
)

CHOICES = RATE_CHOICES + STABILITY_CHOICES


@dataclass(frozen=True)
class HpRateParams:
    p: tuple[int, ...] = (1, 2, 3, 4)
    n_per_side: tuple[int, ...] = (2, 4, 8, 16)     # h = 1/n
    C_pen: tuple[float, ...] = (1e-6, 1e-10)        # eps = C_pen (h/p)^(1 - epsilon)
    epsilon: float = 0.25
    n_ref: int = 128
    p_ref: int = 4
    C_ref: float = 1e-10                            # eps_ref = C_ref h_ref / p_ref

    def __post_init__(self):
        if len(self.n_per_side) < 2:
            raise ValueError(f"hp_rate.n_per_side needs >= 2 meshes, got {self.n_per_side}")
        if not 0 < self.epsilon < 0.5:
            raise ValueError(f"hp_rate.epsilon must lie in (0, 1/2) (Theorem 3.2.6), got "
                             f"{self.epsilon}")
        if not self.p or min(self.p) < 1:
            raise ValueError(f"hp_rate.p must be degrees >= 1, got {self.p}")
        if not self.C_pen or min(self.C_pen) <= 0 or self.C_ref <= 0:
            raise ValueError(f"hp_rate.C_pen and C_ref must be positive, got {self.C_pen}, "
                             f"{self.C_ref}")
        if any(self.n_ref % n for n in self.n_per_side) or self.p_ref < max(self.p):
            raise ValueError(f"hp_rate.n_ref = {self.n_ref} must be a multiple of every n in "
                             f"{self.n_per_side} and p_ref = {self.p_ref} >= max p")


@dataclass(frozen=True)
class StabilityParams:
    n_per_side: int = 16
    p: tuple[int, ...] = (1, 2)
    C_eps: tuple[float, ...] = tuple(10.0 ** -k for k in range(4, 21))   # eps = C_eps h
    problems: tuple[str, ...] = ("flat", "tilted")
    tilt_slope: float = 4e-4             # tilted: g = -d + slope (x + 1)
    accept_relative_residual: float = 1e-6
    accept_backward_error_macheps: float = 20.0

    def __post_init__(self):
        if any(pr not in ("flat", "tilted") for pr in self.problems):
            raise ValueError(f"stability.problems must be 'flat' or 'tilted', got "
                             f"{self.problems}")
        if min(self.C_eps, default=1.0) <= 0 or list(self.C_eps) != sorted(self.C_eps,
                                                                           reverse=True):
            raise ValueError(f"stability.C_eps must be positive and decreasing, got "
                             f"{self.C_eps}")
        if self.n_per_side < 1 or not self.p or min(self.p) < 1:
            raise ValueError(f"stability.n_per_side and p must be >= 1, got "
                             f"{self.n_per_side}, {self.p}")


@dataclass(frozen=True)
class Params:
    E: float = 266926.0
    nu: float = 0.29
    d: float = 2e-4
    norm_scale: float = math.sqrt(2.0)     # as ch3_penalty (err vs the published limit)
    max_newton_iterations: int = 50
    hp_rate: HpRateParams = HpRateParams()
    stability: StabilityParams = StabilityParams()


def load_params(config: dict | None) -> Params:
    """Params from the ch3_penalty_hp section (subsections hp_rate, stability)."""
    section = dict(config or {})
    hp = from_config(HpRateParams, section.pop("hp_rate", None),
                     scene="ch3_penalty_hp.hp_rate")
    st = from_config(StabilityParams, section.pop("stability", None),
                     scene="ch3_penalty_hp.stability")
    return replace(from_config(Params, section, scene="ch3_penalty_hp"), hp_rate=hp,
                   stability=st)


def tilted_gap(d: float, slope: float):
    """The tilted obstacle g(x) = -d + slope (x + 1)."""
    return lambda x: -d + slope * (x[:, 0] + 1.0)


# --------------------------------------------------------------------------- hp rate
def reference_solution(prm: Params):
    """U_ref on the (n_ref, p_ref) mesh with eps_ref = C_ref h_ref / p_ref."""
    hp = prm.hp_rate
    t0 = time.perf_counter()
    ref = square_body(hp.n_ref, prm.E, prm.nu, PLANE, p=hp.p_ref)
    S_ref = ref.S_hat
    eps_ref = hp.C_ref * (1.0 / hp.n_ref) / hp.p_ref
    rref = solve_penalty(ref, eps_ref, -prm.d, S=S_ref, max_iter=prm.max_newton_iterations)
    if not rref.converged:
        raise RuntimeError(f"reference penalty solve failed: {rref.reason}")
    norm_ref = energy_norm(S_ref, rref.U)
    dof_ref = len(ref.V_space.free_dofs("D", components=2))
    info = dict(n_ref=hp.n_ref, p_ref=hp.p_ref, eps_ref=eps_ref, dof_ref=dof_ref,
                norm_ref=norm_ref, ref_s=time.perf_counter() - t0,
                ref_newton_iterations=rref.iterations)
    log.info("reference n=%d p=%d eps=%.3g dof=%d norm=%.10f (%.1f s)", hp.n_ref, hp.p_ref,
             eps_ref, dof_ref, norm_ref, info["ref_s"])
    return ref, S_ref, rref.U, info


def hp_rate_sweep(prm: Params):
    """Energy errors ||I U - U_ref||_{S_ref} of the eps = C_pen (h/p)^{1-epsilon} solutions
    (S_hat assembled once per mesh), with rates in h and in DOF^-1; and the reference info."""
    hp = prm.hp_rate
    ref, S_ref, U_ref, info = reference_solution(prm)
    rows = []
    for p in progress(hp.p, desc="p"):
        for n in hp.n_per_side:
            t1 = time.perf_counter()
            bem = square_body(n, prm.E, prm.nu, PLANE, p=p)
            S = bem.S_hat
            asm_s = time.perf_counter() - t1
            h = 1.0 / n
            for k, C_pen in enumerate(hp.C_pen):
                t2 = time.perf_counter()
                eps = C_pen * (h / p) ** (1.0 - hp.epsilon)
                res = solve_penalty(bem, eps, -prm.d, S=S, max_iter=prm.max_newton_iterations)
                newton_s = time.perf_counter() - t2
                if not res.converged:
                    raise RuntimeError(f"penalty Newton failed (p={p}, n={n}, eps={eps}): "
                                       f"{res.reason}")
                e = prolongate(bem.V_space, res.U, ref.V_space, components=2) - U_ref
                err = energy_norm(S_ref, e)
                rows.append(dict(C_pen=C_pen, p=p, n_per_side=n, h=h,
                                 dof=len(bem.V_space.free_dofs("D", components=2)), eps=eps,
                                 energy_error=err, energy_error_rel=err / info["norm_ref"],
                                 err_norm_diff=abs(energy_norm(S, res.U) - info["norm_ref"]),
                                 newton_iterations=res.iterations,
                                 final_residual=res.residuals[-1],
                                 wall_time_s=time.perf_counter() - t2 + (asm_s if k == 0
                                                                         else 0.0),
                                 newton_s=newton_s))
                log.info("C_pen=%g p=%d n=%d eps=%.3g energy error %.4e", C_pen, p, n, eps,
                         err)
    df = pd.DataFrame(rows).sort_values(["C_pen", "p", "n_per_side"],
                                        ascending=[False, True, True]).reset_index(drop=True)
    df["rate"] = np.nan
    df["rate_dof"] = np.nan
    for _, g in df.groupby(["C_pen", "p"]):
        df.loc[g.index, "rate"] = observed_rates(g.h.to_numpy(), g.energy_error.to_numpy())
        df.loc[g.index, "rate_dof"] = observed_rates(1.0 / g.dof.to_numpy(),
                                                     g.energy_error.to_numpy())
    return df, info


def beyond(claim: Claim) -> Claim:
    """``claim`` as a result beyond the thesis."""
    return replace(claim, kind="beyond")


def _final_rates(rate_tab: pd.DataFrame, C: float) -> dict:
    sub = rate_tab[rate_tab.C_pen == C]
    return {int(p): g.rate.to_numpy()[1:] for p, g in sub.groupby("p")}


def _fmt(rates: dict) -> str:
    return "; ".join(f"p={p}: " + ", ".join(f"{x:.2f}" for x in v) for p, v in rates.items())


def theorem_claim(rate_tab: pd.DataFrame, prm: Params, lam: float) -> Claim:
    """Theorem 3.2.6: observed rate in h >= 1 - epsilon - 0.1 for every p (C = C_pen[0])."""
    hp = prm.hp_rate
    predicted = 1.0 - hp.epsilon
    C_main, C_small = hp.C_pen[0], hp.C_pen[-1]
    r_main = _final_rates(rate_tab, C_main)
    holds = all(v[-1] >= predicted - 0.1 for v in r_main.values())
    ev = (f"rates in h/p at fixed p (n = {', '.join(map(str, hp.n_per_side))}) with C = "
          f"{C_main:g}: {_fmt(r_main)}; predicted 1 - epsilon = {predicted:.2f}.")
    if len(hp.C_pen) > 1:
        sub_m = rate_tab[rate_tab.C_pen == C_main].set_index(["p", "n_per_side"])
        sub_s = rate_tab[rate_tab.C_pen == C_small].set_index(["p", "n_per_side"])
        share = (sub_m.energy_error - sub_s.energy_error) / sub_m.energy_error
        ev += (f" The penalty is not what limits the rate: with C = {C_small:g} (penalty "
               f"error negligible) the errors are {100 * share.min():.0f}-"
               f"{100 * share.max():.0f}% smaller and the rates are the same (next claim); "
               "the observed rate is that of the discretisation error, h^lambda with the "
               f"corner exponent lambda = {lam:.3f}, which happens to lie close to "
               f"1 - epsilon = {predicted:.2f}.")
    if not holds:
        ev += (" The rates are below the prediction: the hypothesis u in H~^(3/2)(Sigma) "
               f"fails (clamped/free corners, lambda = {lam:.3f} < 1).")
    return Claim(
        text=f"Theorem 3.2.6: with eps = C (h/p)^(1-epsilon) (C = {C_main:g}, epsilon = "
             f"{hp.epsilon:g}) the energy error ||u - U^eps|| = O((h/p)^(1-epsilon)) = "
             f"O((h/p)^{predicted:.2f}) (observed rate in h >= {predicted - 0.1:.2f} for "
             "every p)",
        holds=bool(holds), evidence=ev, id="theorem_3_2_6")


def singularity_claims(rate_tab: pd.DataFrame, prm: Params, lam: float) -> list[Claim]:
    """With the penalty error negligible (C = C_pen[-1]): rate lambda in h, p^(-2 lambda)."""
    hp = prm.hp_rate
    C_small, n_fin = hp.C_pen[-1], hp.n_per_side[-1]
    r_s = _final_rates(rate_tab, C_small)
    worst = max((v[-1] for v in r_s.values()), key=lambda r: abs(r - lam))
    claim = beyond(rate_claim(
        "(beyond the thesis) the hypothesis u in H~^(3/2)(Sigma) of Theorem 3.2.6 "
        "fails here: with the penalty error negligible, the uniform-mesh rate in h "
        f"is the corner singularity exponent lambda = {lam:.3f} (clamped/free "
        f"right angle, plane strain nu = {prm.nu:g}) for every p, not the h/p rate 1 "
        "(finest rate within 0.1 of lambda)", worst, lam, 0.1,
        what="finest rate in h (the p farthest from lambda)"))
    claim.evidence += (f". C = {C_small:g}: rates {_fmt(r_s)}; lambda from Williams' "
                       "equation 4 kappa sin^2(lambda pi/2) + 4 lambda^2 = (kappa + 1)^2, "
                       f"kappa = 3 - 4 nu = {3 - 4 * prm.nu:.2f}. The contact side itself is "
                       "regular (full contact = sliding symmetry condition); the "
                       "singularities sit at the corners of Gamma_D.")
    claims = [claim]
    sub = rate_tab[(rate_tab.C_pen == C_small) & (rate_tab.n_per_side == n_fin)]
    if len(sub) >= 2:
        e_p = sub.set_index("p").energy_error
        p_lo, p_hi = int(e_p.index.min()), int(e_p.index.max())
        rp = -fitted_rate([p_lo, p_hi], [e_p[p_lo], e_p[p_hi]])
        claim = beyond(rate_claim(
            f"(beyond the thesis) p-refinement on a fixed uniform mesh converges "
            f"like p^(-2 lambda) = p^(-{2 * lam:.2f}) (p-version at a node "
            "singularity; Theorem 3.2.6 would give p^-1): observed within 0.25",
            rp, 2 * lam, 0.25, what=f"rate in p between p={p_lo} and p={p_hi}"))
        claim.evidence += (f". C = {C_small:g}, n = {n_fin}: energy error " + ", ".join(
            f"p={p}: {e:.3e}" for p, e in e_p.items()) +
            f" (p <= {p_hi} only: pre-asymptotic)")
        claims.append(claim)
    return claims


def p_claims(rate_tab: pd.DataFrame, prm: Params) -> list[Claim]:
    """Higher p gives a smaller error on the finest mesh, per C_pen."""
    claims = []
    for C in prm.hp_rate.C_pen:
        fin = rate_tab[rate_tab.C_pen == C].groupby("p").last()
        errs = fin.energy_error.to_numpy()
        claims.append(Claim(
            kind="beyond",
            text=f"Higher p gives a smaller error on the same mesh (C = {C:g})",
            holds=bool(np.all(np.diff(errs) < 0)),
            evidence=f"energy error at n = {prm.hp_rate.n_per_side[-1]}: " + ", ".join(
                f"p={p}: {e:.3e} (DOF {int(fin.dof[p])})" for p, e in zip(fin.index, errs))))
    return claims


def rate_figure(rate_tab: pd.DataFrame, prm: Params) -> Figure:
    hp = prm.hp_rate
    predicted = 1.0 - hp.epsilon
    fig = Figure(figsize=(6.5, 4.8))
    ax = fig.subplots()
    colors = dict(zip(hp.p, ["C0", "C1", "C2", "C3", "C4", "C5"]))
    for (C, p), g in rate_tab.groupby(["C_pen", "p"], sort=False):
        main = C == hp.C_pen[0]
        ax.loglog(g.dof, g.energy_error, "o-" if main else "s--", color=colors.get(p),
                  alpha=1.0 if main else 0.6, label=f"p = {p}, C = {C:g}")
    dd = np.array([rate_tab.dof.min(), rate_tab.dof.max()], float)
    e0 = rate_tab.energy_error.max()
    ax.loglog(dd, 1.2 * e0 * (dd / dd[0]) ** (-predicted), "k--", alpha=0.6,
              label=f"DOF^-{predicted:.2f} (Thm 3.2.6)")
    ax.loglog(dd, 0.5 * e0 * (dd / dd[0]) ** (-1.0), "k:", alpha=0.6,
              label="DOF^-1 (h/p, smooth u)")
    ax.set_xlabel("DOF")
    ax.set_ylabel(r"$\|I U^\epsilon - U_{ref}\|_{\hat S}$")
    ax.set_title(f"hp-penalty BEM, eps = C (h/p)^{predicted:g}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="x-small", ncol=2)
    return fig


def rate_result(prm: Params, jit_s: float) -> ArtefactResult:
    t_hp = time.perf_counter()
    rate_df, ref = hp_rate_sweep(prm)
    hp_s = time.perf_counter() - t_hp
    rate_tab = rate_df[["p", "n_per_side", "h", "dof", "eps", "energy_error", "rate",
                        "newton_iterations", "wall_time_s", "C_pen", "rate_dof",
                        "energy_error_rel", "err_norm_diff", "final_residual",
                        "newton_s"]].copy().reset_index(drop=True)
    lam = singular_exponent(prm.nu, PLANE)
    claims = [theorem_claim(rate_tab, prm, lam)]
    if len(prm.hp_rate.C_pen) > 1:
        claims += singularity_claims(rate_tab, prm, lam)
    claims += p_claims(rate_tab, prm)
    notes = (
        f"Reference: n_ref = {ref['n_ref']}, p_ref = {ref['p_ref']}, eps_ref = "
        f"{ref['eps_ref']:.3g}, DOF {ref['dof_ref']}, ||U_ref||_S = {ref['norm_ref']:.10f} "
        f"(x sqrt2 = {prm.norm_scale * ref['norm_ref']:.6f}; Table 3.1 limit 0.154398). "
        "energy_error = ||I U - U_ref||_{S_ref} (absolute, our norm scale); "
        "energy_error_rel divides by ||U_ref||_S; err_norm_diff = |<S U,U>^(1/2) - "
        "||U_ref||_S| (Table 3.1 style, ~ square of the energy error). rate/rate_dof NaN "
        "on the first mesh of each (C_pen, p) (allowed). wall_time_s = Newton + error "
        "evaluation (+ S_hat assembly on the first C_pen of a mesh); newton_s = Newton "
        f"only. Corner exponent lambda = {lam:.4f}. Choices: " + " ".join(RATE_CHOICES))
    meta = dict(jit_s=round(jit_s, 3), run_s=round(hp_s, 3), C_pen=list(prm.hp_rate.C_pen),
                epsilon=prm.hp_rate.epsilon,
                final_rates={f"C={C:g}": {p: float(v[-1]) for p, v in
                                          _final_rates(rate_tab, C).items()}
                             for C in prm.hp_rate.C_pen},
                corner_exponent=lam,
                reference={k: (float(v) if isinstance(v, float) else v)
                           for k, v in ref.items()},
                max_dof=int(rate_tab.dof.max()),
                allow_nan_columns=["rate", "rate_dof"])
    return ArtefactResult(name="figure_penalty_hp_rate", table=rate_tab,
                          figure=rate_figure(rate_tab, prm), claims=claims, notes=notes,
                          meta=meta)


# --------------------------------------------------------------------------- stability
def stability_sweep(prm: Params) -> pd.DataFrame:
    """One row per (p, problem, C_eps): the run's check (limits.PenaltyCheck), its energy,
    err / penalty_error (flat) and delta_U against the previous C_eps."""
    st = prm.stability
    n = st.n_per_side
    rows = []
    for p in st.p:
        bem = square_body(n, prm.E, prm.nu, PLANE, p=p)
        S = bem.S_hat
        U0 = constrained_limit(bem, -prm.d, S)
        n0 = energy_norm(S, U0)
        for prob in st.problems:
            gap = -prm.d if prob == "flat" else tilted_gap(prm.d, st.tilt_slope)
            prev = None
            for C in progress(st.C_eps, desc=f"p={p} {prob}"):
                eps = C / n
                res, chk = solve_penalty_checked(
                    bem, eps, gap, S=S, max_iter=prm.max_newton_iterations,
                    accept_rel=st.accept_relative_residual,
                    accept_eta=st.accept_backward_error_macheps)
                U = res.U
                finite = bool(np.all(np.isfinite(U)))
                nrm = energy_norm(S, U) if finite else math.nan
                row = dict(problem=prob, p=p, n=n, C_eps=C, eps=eps,
                           condition_number=chk.condition_number,
                           cond_x_macheps=chk.condition_number * MACHEPS,
                           newton_iterations=res.iterations, residual=chk.residual,
                           relative_residual=chk.relative_residual,
                           backward_error=chk.backward_error,
                           converged=bool(res.converged), accepted=chk.accepted,
                           reason=chk.reason, lapack_warning=chk.lapack_warning,
                           norm_S=nrm, wall_time_s=chk.solve_s)
                flat = prob == "flat"
                row["err"] = abs(PUBLISHED_ULIM - prm.norm_scale * nrm) if flat else math.nan
                row["penalty_error"] = (energy_norm(S, U - U0) / n0 if flat and finite
                                        else math.nan)
                row["delta_U"] = (energy_norm(S, U - prev) / nrm
                                  if prev is not None and finite else math.nan)
                prev = U
                rows.append(row)
                log.info("%s p=%d C_eps=%.0e cond=%.2e it=%d rel.res=%.1e %s", prob, p, C,
                         chk.condition_number, res.iterations, chk.relative_residual,
                         chk.reason)
    return pd.DataFrame(rows)


def breakdown_summary(df: pd.DataFrame) -> dict:
    """Per (problem, p): the largest C_eps at which the run is not accepted, at which
    LAPACK warns, at which the penalty error stops decreasing ~ eps (flat)."""
    out = {}
    for (prob, p), g in df.groupby(["problem", "p"], sort=False):
        g = g.sort_values("C_eps", ascending=False)
        bad = g[~g.accepted]
        warn = g[g.lapack_warning]
        info = dict(first_not_accepted=float(bad.C_eps.iloc[0]) if len(bad) else None,
                    not_accepted=[float(c) for c in bad.C_eps],
                    failed=[float(c) for c in g[~g.converged].C_eps],
                    false_convergence=[float(c) for c in g[g.converged & ~g.accepted].C_eps],
                    first_lapack_warning=float(warn.C_eps.iloc[0]) if len(warn) else None,
                    max_cond=float(g.condition_number.max()),
                    max_iterations=int(g.newton_iterations.max()))
        if prob == "flat":
            k = saturation_index(g.C_eps.to_numpy(), g.penalty_error.to_numpy())
            info["penalty_error_saturates_at"] = float(g.C_eps.iloc[k]) if k is not None \
                else None
            info["min_penalty_error"] = float(np.nanmin(g.penalty_error.to_numpy()))
        out[(prob, int(p))] = info
    return out


def _groups(st_df: pd.DataFrame, problem: str | None = None):
    """(problem, p, rows sorted by decreasing C_eps) in the sweep's order."""
    for (prob, p), g in st_df.groupby(["problem", "p"], sort=False):
        if problem is None or prob == problem:
            yield prob, int(p), g.sort_values("C_eps", ascending=False)


COND_SLOPE = -0.9      # "cond ~ 1/eps": log-log slope against C_eps below this
COND_SKIPS = (1, 2, 3)  # first runs left out of the fit (the penalty block not dominant)


def _cond_slope(g: pd.DataFrame, skip: int = 2) -> float:
    """Log-log slope of cond against C_eps over the runs before round-off
    (cond macheps < 1e-2), leaving out the first ``skip`` (NaN if fewer than 2 left)."""
    ok = g[g.cond_x_macheps < 1e-2]
    return fitted_rate(ok.C_eps.iloc[skip:], ok.condition_number.iloc[skip:]) \
        if len(ok) >= skip + 2 else math.nan


def conditioning_claims(st_df: pd.DataFrame) -> list[Claim]:
    """cond ~ 1/eps once the penalty block dominates (before round-off); where that
    fails, whether it holds over the accepted runs (the matrices of actual solutions)."""
    claims = []
    for prob, p, g in _groups(st_df):
        if (g.cond_x_macheps < 1e-2).sum() < 3:
            continue
        slope_c = _cond_slope(g)
        cid = f"cond_{prob}_p{p}"
        claims.append(Claim(
            text=f"Thesis (Ch. 1, 3, 4): the condition number of the Galerkin (Newton) "
                 f"matrix increases as the penalty parameter decreases [{prob}, p={p}]",
            holds=bool(slope_c < COND_SLOPE),
            evidence=f"cond from {g.condition_number.iloc[0]:.2e} (C_eps="
                     f"{g.C_eps.iloc[0]:g}) to {g.condition_number.iloc[-1]:.2e} (C_eps="
                     f"{g.C_eps.iloc[-1]:g}); log-log slope {slope_c:.3f} against C_eps "
                     "(cond ~ 1/eps) once the penalty block dominates", id=cid))
        if slope_c >= COND_SLOPE:
            acc = g[g.accepted]
            slopes = {k: _cond_slope(acc, k) for k in COND_SKIPS}
            bad = g[~g.accepted & (g.cond_x_macheps < 1e-2)]
            claims.append(Claim(
                text=f"the shallower slope [{prob}, p={p}] comes from the runs that are not "
                     "accepted (their matrix is that of a non-converged iterate, not of a "
                     "solution): over the accepted runs cond ~ 1/eps",
                holds=bool(all(v < COND_SLOPE for v in slopes.values())),
                evidence="log-log slope over the accepted runs, leaving out the first "
                         + ", ".join(f"{k}: {v:.3f}" for k, v in slopes.items())
                         + f" (all runs: {slope_c:.3f}); runs in the fit that are not "
                           "accepted: " + ", ".join(
                             f"C_eps={c:g} ({r})" for c, r in zip(bad.C_eps, bad.reason)),
                kind="explanation", id=f"{cid}_accepted", explains=(cid,)))
    return claims


def flat_claims(st_df: pd.DataFrame, summ: dict) -> list[Claim]:
    """Flat obstacle: accurate while accepted; the breakdown is reported, not hidden."""
    claims = []
    for prob, p, g in _groups(st_df, "flat"):
        v = summ[(prob, p)]
        sat = v["penalty_error_saturates_at"]
        acc, bad = g[g.accepted], g[~g.accepted]
        pe = acc.penalty_error.to_numpy()
        # accepted runs: the penalty error falls with eps until the round-off floor
        follows = bool(np.all(np.diff(pe) <= 0.5 * pe[:-1] + 1e-14))
        reported = bool(bad.reason.str.contains("ill-conditioned|LAPACK|max_iter").all())
        claims.append(Claim(
            kind="beyond",
            text=f"(stress test, flat obstacle, p={p}) an answer is accepted only while the "
                 "contact equation is solved to a backward error <= 1e-6, and there the "
                 "penalty error decreases with eps; beyond (cond * macheps -> 1) the run is "
                 "reported as ill-conditioned, never as converged",
            holds=bool(v["false_convergence"] == [] and follows and reported)
            if len(pe) >= 2 else None,
            evidence=("penalty error ||U - U_0||_S/||U_0||_S per C_eps: " + ", ".join(
                f"{c:g}: {e:.1e}{'' if a else ' (not accepted)'}"
                for c, e, a in zip(g.C_eps, g.penalty_error, g.accepted)) +
                f"; it reaches its floor at C_eps = {sat} (min "
                f"{v['min_penalty_error']:.1e}); LAPACK warns (rcond < macheps) from "
                f"C_eps = {v['first_lapack_warning']}; not accepted: {v['not_accepted']} ("
                + "; ".join(f"{c:g}: {r}" for c, r in zip(bad.C_eps, bad.reason)) +
                "). The displacement stays close to the limit even there (it is fixed by "
                "the constraint), but the pressure (1/eps) (U_n - g)_+ is a quotient of "
                "round-off: at C_eps = 1e-20 it is off by a factor ~2 (p = 1, n = 8, "
                "tests/contact/test_penalty_limits.py). err vs the limit 0.154398 saturates much "
                f"earlier, at the n = 16 discretisation error {g.err.iloc[-1]:.2e}.")))
    return claims


def tilted_claims(st_df: pd.DataFrame, summ: dict, accept_rel: float) -> list[Claim]:
    """Tilted obstacle: Newton converges for every C_eps; iterations grow as eps falls."""
    claims = []
    for prob, p, g in _groups(st_df, "tilted"):
        v = summ[(prob, p)]
        claims.append(Claim(
            kind="beyond",
            text=f"(stress test, tilted obstacle - partial contact, p={p}) the semismooth "
                 "Newton solver converges for every C_eps in the sweep",
            holds=bool(v["not_accepted"] == []),
            evidence=("Newton iterations " + ", ".join(
                f"{c:g}: {i}" for c, i in zip(g.C_eps, g.newton_iterations)) +
                f". Failures (converged=False): {v['failed']}; false convergence "
                f"(solver says converged, relative residual > {accept_rel:g}): "
                f"{v['false_convergence']}. Reasons: " + "; ".join(
                    f"{c:g}: {r}" for c, r, a in zip(g.C_eps, g.reason, g.accepted)
                    if not a) +
                ". solve_penalty stops when the residual is below tol times the force "
                "scale of the iterate, or when the Newton update is at round-off level "
                "(for small eps the residual floor cond * macheps * forces lies above "
                "tol); every run is also checked here by its backward error.")))
    for prob, p, g in _groups(st_df, "tilted"):
        acc = g[g.accepted]
        its = acc.newton_iterations.to_numpy()
        iid = f"iterations_{prob}_p{p}"
        claims.append(Claim(
            text=f"Thesis (line ~20685): smaller penalty parameters increase the number of "
                 f"Newton iterations [tilted obstacle, p={p}, accepted runs]",
            # fewer than two accepted runs: nothing to compare (undecided, not False)
            holds=bool(np.all(np.diff(its) >= 0) and its[-1] > its[0]) if len(its) >= 2
            else None,
            evidence="accepted runs: " + ", ".join(
                f"C_eps={c:g}: {i}" for c, i in zip(acc.C_eps, its)) +
                ". (flat obstacle: one Newton solve - the whole of Gamma_C is in contact "
                "from the first iterate, the problem is linear there - plus, for small "
                "eps, one step that finds the update at round-off level)", id=iid))
        if len(its) >= 3 and not claims[-1].holds:
            tau = float(pd.Series(-np.log10(acc.C_eps.to_numpy())).corr(
                pd.Series(its.astype(float)), method="kendall"))
            drops = [f"{a} -> {b} at C_eps={c:g}" for a, b, c in
                     zip(its[:-1], its[1:], acc.C_eps.to_numpy()[1:]) if b < a]
            claims.append(Claim(
                text=f"[tilted obstacle, p={p}] the thesis states a trend: the iteration "
                     "count grows with 1/eps, and the decreases are the run-to-run "
                     "variation of the active-set iteration",
                holds=bool(tau > 0.7 and its[-1] > its[0]),
                evidence=f"Kendall rank correlation of the iterations with log10(1/C_eps) "
                         f"over the accepted runs {tau:.2f}; {its[0]} -> {its[-1]} "
                         f"iterations; decreases: {', '.join(drops)}. A reading, not "
                         "derived: why the count drops there is not analysed.",
                kind="hypothesis", id=f"{iid}_trend", explains=(iid,)))
    return claims


def stability_figure(st_df: pd.DataFrame, prm: Params) -> Figure:
    fig = Figure(figsize=(10.0, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    for (prob, p), g in st_df.groupby(["problem", "p"], sort=False):
        g = g.sort_values("C_eps")
        ax1.loglog(g.C_eps, g.condition_number, "o-", label=f"{prob}, p={p}")
        bad = g[~g.accepted]
        ax1.loglog(bad.C_eps, bad.condition_number, "rx", ms=9)
        if prob == "flat":
            ax2.loglog(g.C_eps, g.penalty_error, "o-", label=f"||U-U_0||/||U_0||, p={p}")
            ax2.loglog(g.C_eps, g.err, "s--", label=f"err vs 0.154398, p={p}")
        else:
            ax2.loglog(g.C_eps, g.delta_U, "^:", label=f"delta_U tilted, p={p}")
    ax1.axhline(1 / MACHEPS, color="k", ls=":", lw=1, label="1/macheps")
    ax1.set_xlabel("C_eps (eps = C_eps h)")
    ax1.set_ylabel("cond(Newton matrix)")
    ax1.set_title(f"n = {prm.stability.n_per_side}; red x: not accepted")
    ax2.set_xlabel("C_eps")
    ax2.set_ylabel("error")
    for a in (ax1, ax2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize="x-small")
    return fig


def stability_result(prm: Params, jit_s: float) -> ArtefactResult:
    t_st = time.perf_counter()
    st_df = stability_sweep(prm)
    st_s = time.perf_counter() - t_st
    st_tab = st_df[["C_eps", "eps", "condition_number", "newton_iterations", "residual",
                    "err", "converged", "reason", "problem", "p", "n", "accepted",
                    "relative_residual", "backward_error", "cond_x_macheps", "lapack_warning",
                    "penalty_error", "delta_U", "norm_S", "wall_time_s"]].copy()
    summ = breakdown_summary(st_df)
    claims = (conditioning_claims(st_df) + flat_claims(st_df, summ)
              + tilted_claims(st_df, summ, prm.stability.accept_relative_residual))
    notes = (
        "err and penalty_error are NaN for the tilted obstacle (no reference limit; see "
        "delta_U), delta_U is NaN on the first C_eps of each sweep (allowed). "
        "wall_time_s = Newton only (S_hat assembled once per mesh). Choices: "
        + " ".join(STABILITY_CHOICES))
    meta = dict(jit_s=round(jit_s, 3), run_s=round(st_s, 3),
                n_per_side=prm.stability.n_per_side,
                breakdown={f"{k[0]}_p{k[1]}": v for k, v in summ.items()},
                max_condition_number=float(st_df.condition_number.max()),
                allow_nan_columns=["err", "penalty_error", "delta_U"])
    return ArtefactResult(name="figure_penalty_stability", table=st_tab.reset_index(drop=True),
                          figure=stability_figure(st_df, prm), claims=claims, notes=notes,
                          meta=meta)


# --------------------------------------------------------------------------- run
SCENE_RUNS = {"hp_rate": rate_result, "stability": stability_result}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """The artefacts of the scenes asked for (None: both; ``quick`` is unused:
    config/quick.yaml sets the sizes)."""
    prm = load_params(config)
    scenes = tuple(SCENES) if scenes is None else tuple(scenes)
    unknown = sorted(set(scenes) - set(SCENES))
    if unknown:
        raise ValueError(f"unknown scene(s) {unknown} of ch3_penalty_hp; known: "
                         f"{list(SCENES)}")
    t0 = time.perf_counter()
    square_body(2, prm.E, prm.nu, PLANE).S_hat     # compile / load the numba cache once
    jit_s = time.perf_counter() - t0
    return [SCENE_RUNS[name](prm, jit_s) for name in SCENES if name in scenes]
