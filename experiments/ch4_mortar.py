"""Table 4.1, Figures 4.17 and 4.18 (Section 4.3.4, thesis lines 19474-19625): hp-mortar
BEM for two-body contact with given (Tresca) friction, solved by the Dirichlet-to-Neumann
algorithm (Algorithm 4.3) with the Uzawa algorithm (Algorithm 4.4) and Polyak's
projected CG inside (:mod:`hpfebe.contact.mortar`), data transfer by the mortar
projection (4.87) and its adjoint (:mod:`hpfebe.coupling.mortar`).

Scene (thesis): body 1 with Gamma^1_D = [-1,1] x {2} (U = (0, -0.09)), Gamma^1_N the
vertical sides, Gamma^1_C the circular arc through (-1, 0.1), (0, 0), (1, 0.1); body 2
= [-1,1] x [-2,0], Gamma^2_C = [-1,1] x {0}, Gamma^2_D the rest (U = 0); E = 266926,
nu = 0.29, F = 0.1, rho = 1.0, TOL_DtN = TOL_U = 1e-6, L = 2.

Artefacts:
* table_4_1 - DtN iterations for omega_D, omega_N in {0.3, 0.5, 0.7, 0.9}, p = 2,
  16 elements on Gamma^1_C, 12 on Gamma^2_C; non-convergence detected and reported;
* figure_4_17 - the initial meshes and the deformed configuration (table 4.1 meshes);
* figure_4_18 - | ||U||_W,delta - ||U||_W,inf | against DOF for (p1, p2) = (1,1), (2,1),
  (2,2), h1 = L/4 ... L/64, h1 : h2 = 4 : 3 (element counts);
* figure_4_19 - global Uzawa (Algorithm 4.5) with Coulomb friction, p = 2,
  h1 : h2 = 41 : 25: deformed configuration and normal / tangential contact traction;
* figure_4_20 - meshes and polynomial degrees after 3, 6, 9 hp-adaptive steps (the
  indicator eta of Section 4.3.5, Algorithm 4.6 through hpfebe.adaptivity.adapt);
* figure_dtn_map (beyond the thesis) - DtN iteration count on a fine (omega_D, omega_N)
  grid with the non-convergence region;
* figure_uzawa_rho (beyond the thesis) - iterations of the global Uzawa against
  rho / rho_crit, rho_crit predicted from the spectrum of the condensed operators
  (Theorem 3.1.8), against the largest convergent rho measured.

* figure_solver_comparison (beyond the thesis) - DtN + Uzawa, global Uzawa and a
  monolithic semismooth Newton (primal-dual active set) on the Figure 4.17 problem with
  Tresca and Coulomb friction: iterations, wall time, mutual differences, and a
  work-precision plot (error against wall time over a tolerance sweep).

The choices where the thesis is silent are :data:`CHOICES`.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe.analysis.rates import aitken, fitted_rate
from hpfebe.adaptivity import adapt
from hpfebe.adaptivity import hp_refine, mortar_indicators
from hpfebe.contact.mortar import contact_from_meshes, model_meshes, model_problem
from hpfebe.constitutive.materials import lame_constants
from hpfebe.suite.params import from_config
from hpfebe.suite.results import CELLS_PREFIX, ArtefactResult, Claim, progress, rate_claim

ARTEFACTS = ("table_4_1", "figure_4_17", "figure_4_18", "figure_4_19", "figure_4_20",
             "figure_dtn_map", "figure_uzawa_rho", "figure_solver_comparison")
#: independent computations, one workflow job each (wall times of the full config, one
#: thread, measured: see the module's report): the damping sweep on the Table 4.1 mesh
#: (its consistent-reading runs give Figure 4.17's solution), the Figure 4.18 mesh
#: sweep, the global Uzawa solves (Algorithm 4.5), the DtN map and solver comparison
#: on the Table 4.1 mesh
SCENES = {"table": ("table_4_1", "figure_4_17"), "sweep": ("figure_4_18",),
          "uzawa": ("figure_4_19", "figure_4_20", "figure_uzawa_rho"),
          "beyond": ("figure_dtn_map", "figure_solver_comparison")}

log = logging.getLogger(__name__)

PUBLISHED_LIMIT = 6.110073
#: quick mode without a config value: 4 hp-adaptive steps, meshes after 1, 2, 4
QUICK_ADAPT = (4, (1, 2, 4))
PUBLISHED_RATES = {(1, 1): 0.63, (2, 2): 1.89}
PUBLISHED_TABLE = {(0.3, 0.3): 42, (0.3, 0.5): 30, (0.3, 0.7): 21, (0.3, 0.9): 16,
                   (0.5, 0.3): 30, (0.5, 0.5): 23, (0.5, 0.7): 17, (0.5, 0.9): 18,
                   (0.7, 0.3): 21, (0.7, 0.5): 17, (0.7, 0.7): 20, (0.7, 0.9): None,
                   (0.9, 0.3): 23, (0.9, 0.5): 18, (0.9, 0.7): None, (0.9, 0.9): None}

CHOICES = (
    "Table 4.1 reading (table_friction = coulomb, table_transfer = function; measured "
    "against the alternatives, see the table's claims and the 'iterations_tresca' column): "
    "F = 0.1 acts as a Coulomb coefficient inside the DtN loop (friction bound F p_n with "
    "the normal pressure p_n of the previous DtN iteration; the Tresca bound 0.1 in the "
    "thesis's units is 1e-5 of the contact pressure, i.e. frictionless, and gives no '-' "
    "cells) and the transfer of steps 5-6 is read literally with functions: R1 in X^1_hp "
    "the L2 representative D^-1 r1 of the residual, P = B^T D^-T R1 its coefficients in "
    "X^2_hp, and the load of (4.88) the L2 pairing <P, W^2> = M2 P. This reproduces 12 of "
    "the 13 published counts within +-1 and the three '-' cells; its fixed point is not "
    "the consistent discrete problem (action != reaction by M2 B^T D^-2 vs B^T D^-1), so "
    "Figures 4.17, 4.18 and the DtN map use the consistent reading (Tresca F, functional "
    "transfer, column iterations_tresca). Its '-' cells reach the cap table_max_dtn = 100: "
    "(0.9, 0.9) cycles with a constant increment, (0.7, 0.9) and (0.9, 0.7) still have "
    "relative increments 0.24 there (measured: -4.7 % per iteration), i.e. "
    "'no convergence observed' in the thesis's sense, not growth.",
    "Gamma^2_D: the whole vertical sides {-1,1} x [-2,0] and the bottom (the text's "
    "{-1,1} x [-1,0] read as the whole sides).",
    "Meshes: n1 elements of equal angle on the arc Gamma^1_C (h1 = L/n1), n2 equal "
    "elements on Gamma^2_C (h2 = L/n2), the other sides with ceil(length/h) elements; "
    "'h1:h2 = 4:3' read as the element counts n1:n2 = 4:3 as in Table 4.1 (16 and 12). "
    "The arc is represented by its polygon (nodes on the circle).",
    "Pairing of the two contact zones in the mortar integrals (4.87): by the x-coordinate "
    "(projection along the normal of the flat Gamma^2_C); integrals over Gamma^1_C with "
    "its arc length, exact Gauss quadrature on the common refinement in x.",
    "Constraints at the Gauss-Lobatto points of Gamma^1_C (= the GLL nodes of V^1_hp); "
    "normal n = radial direction of the circle, initial gap measured along it to "
    "Gamma^2_C (end points whose ray misses Gamma^2_C are unconstrained); friction "
    "functional by the Gauss-Lobatto rule (Tresca conditions pointwise at these points).",
    "Sign: P_k is the contact force on body 1 transferred to Gamma^2 (B^T D^-T R1 with "
    "R1 = S1 U1 - L1), body 2 carries -P_k, as in step 2 of Algorithm 4.3.",
    "Uzawa step: rho = 1.0 read relative to the Theorem 3.1.8 bound, rho_eff = rho * "
    "rho_crit / 2 with rho_crit = 2 / (F^2 lambda_max(W^1/2 C_tt W^1/2)) (C the condensed "
    "compliance at the contact nodes): the raw rho = 1 in the thesis's units (E = 266926, "
    "F = 0.1) makes a single Uzawa solve need > 2e4 iterations (measured: the 20000 cap "
    "was hit in every Table 4.1 run).",
    "Warm starts: the Uzawa multiplier and the projected-CG iterate are carried from one "
    "DtN iteration to the next; P_1 = 0, Q_0 = 0 as in Algorithm 4.3.",
    "Stopping rules from hpfebe.solvers.nonlinear.fixed_point: ||P_k+1 - P_k||_2 <= TOL "
    "||P_k+1||_2 (the thesis divides by ||P_k||); Uzawa the same in lambda; projected CG "
    "to a projected gradient <= 1e-11 max(||b||, ||A x||). Non-convergence = the DtN cap "
    "max_dtn (a period-2 cycle is what we observe), growth by 1e6 or NaN.",
    "Figure 4.19: Coulomb coefficient mu_f = 0.1 (the F of the model problem); the "
    "projection onto M_n,hp read as the positive part max(0, P_n) (the printed "
    "P_n sign(P_n) = |P_n| is taken as a typo); the traction pairing on Gamma^1_C by the "
    "Gauss-Lobatto rule (as the friction functional, so that Algorithm 4.5 with Tresca "
    "friction solves the DtN problem: measured agreement 6e-10 on the Table 4.1 mesh); "
    "rho = rho_global * rho_crit / 2 (rho_global = 1.5; 1.9 failed for Coulomb on "
    "the 8:6 mesh) of the linear response (rho_crit from its largest "
    "eigenvalue); stop by fixed_point (relative increment, >= 3 iterations) instead of "
    "||P_k - P_k-1|| <= TOL ||P_2 - P_1||. Tractions plotted = nodal values at the "
    "Gauss-Lobatto points of Gamma^1_C against x.",
    "Figure 4.20: initial meshes (n1, n2) = adapt_n = (8, 6) with p = 1 (not given in "
    "the thesis), global Uzawa with Coulomb friction (as Figure 4.19) on every mesh; "
    "marking eta_I >= q1 eta_max per body (q1 = 0.85), h-refinement (bisection) where "
    "eta_I >= q2 eta_max (q2 = 0.9), else p + 1; the arc stays the initial polygon "
    "(bisection nodes on the chords). Indicator: eta_S^2 in the derivative form "
    "(h_I/p_I) h_I ||d/ds (V Psi - (K + 1/2) U)||^2 of the Chapter 3 estimator; "
    "S_hat U evaluated pointwise as in Section 3.3.3; [P] = Psi^1 + Psi^2 and [U_n]_+ at "
    "points paired by x; datum on Gamma_C the nodal traction P interpolated in X^1_hp.",
    "Plane strain. ||U||_W = (<W U1,U1> + <W U2,U2>)^(1/2) over the whole boundaries with "
    "the Galerkin W of hpfebe.bem.lame. DOF = 2 (dim V^1_hp + dim V^2_hp), Dirichlet dofs "
    "included. The limit ||U||_W,inf is our own Aitken extrapolation of the last three "
    "(2,2) norms; rates = least-squares slope of the error against DOF.",
)


@dataclass(frozen=True)
class Params:
    E: float = 266926.0
    nu: float = 0.29
    plane: str = "strain"
    F: float = 0.1
    rho: float = 1.0
    rho_relative: bool = True
    tol_dtn: float = 1.0e-6
    tol_uzawa: float = 1.0e-6
    max_dtn: int = 200
    max_uzawa: int = 5000
    u_top: float = -0.09
    radius: float = 5.05
    geometry: str = "arc"
    side_depth: float = 2.0
    table_friction: str = "coulomb"
    table_max_dtn: int = 100
    table_transfer: str = "function"
    table_n: tuple[int, ...] = (16, 12)
    table_p: int = 2
    omegas: tuple[float, ...] = (0.3, 0.5, 0.7, 0.9)
    conv_n1: tuple[int, ...] = (4, 8, 16, 32, 64)
    conv_degrees: tuple[tuple[int, ...], ...] = ((1, 1), (2, 1), (2, 2))
    conv_omega: tuple[float, ...] = (0.7, 0.5)
    # Figure 4.18 also with the Table 4.1 reading: these degree pairs, the last (the
    # limit's) only for h1 >= L/n1_max (its (2,2) run at h1 = L/64 alone takes ~10 s:
    # the Coulomb bounds slow Uzawa down)
    conv_table_degrees: tuple[tuple[int, ...], ...] = ((1, 1), (2, 2))
    conv_table_n1_max: int = 32
    iteration_factor: float = 1.3
    magnification: float = 1.0
    coulomb_n: tuple[int, ...] = (41, 25)
    mu_f: float = 0.1
    rho_global: float = 1.5
    tol_global: float = 1.0e-6
    max_global: int = 50000
    map_omegas: tuple[float, ...] = tuple(round(0.1 + 0.05 * k, 2) for k in range(19))
    rho_ratios: tuple[float, ...] = (0.25, 0.5, 1.0, 1.5, 1.9, 2.1, 2.5, 4.0, 8.0)
    rho_n: tuple[int, ...] = (8, 6)
    max_rho_iter: int = 5000
    adapt_n: tuple[int, ...] = (8, 6)
    adapt_p: int = 1
    adapt_steps: int = 9
    adapt_q1: float = 0.85
    adapt_q2: float = 0.9
    adapt_show: tuple[int, ...] = (3, 6, 9)
    compare_tols: tuple[float, ...] = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)

    def __post_init__(self):
        for name in ("E", "rho", "tol_dtn", "tol_uzawa", "radius", "iteration_factor",
                     "magnification"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        for name, ok in (("table_friction", ("tresca", "coulomb")),
                         ("table_transfer", ("functional", "function")),
                         ("geometry", ("arc", "flat"))):
            if getattr(self, name) not in ok:
                raise ValueError(f"{name} must be one of {ok}, got {getattr(self, name)!r}")
        if any(not 0 < w <= 1 for w in self.omegas + self.conv_omega):
            raise ValueError("omegas and conv_omega must lie in (0, 1]")
        if any(n % 4 for n in self.conv_n1):
            raise ValueError(f"conv_n1 must be multiples of 4 (n2 = 3 n1 / 4), got "
                             f"{self.conv_n1!r}")


def _problem(prm: Params, n1, n2, p1, p2, bem_cache: dict | None = None, gap=None):
    return model_problem(n1=n1, n2=n2, p1=p1, p2=p2, E=prm.E, nu=prm.nu, F=prm.F,
                         u_top=(0.0, prm.u_top), radius=prm.radius, plane=prm.plane,
                         geometry=prm.geometry, side_depth=prm.side_depth,
                         bem_cache=bem_cache, gap=gap)


def _solve(pr, prm: Params, wD, wN, friction="tresca", transfer="functional"):
    return pr.dtn(wD, wN, rho=prm.rho, tol=prm.tol_dtn, tol_U=prm.tol_uzawa,
                  max_iter=prm.max_dtn, max_uzawa=prm.max_uzawa,
                  rho_relative=prm.rho_relative, friction=friction, transfer=transfer)


# --------------------------------------------------------------------------- table 4.1
def damping_sweep(prm: Params, pr):
    """Table 4.1's runs on ``pr`` (:func:`_table_problem`): (rows, the fastest converged
    run of the consistent reading with its dampings)."""
    rows, best = [], None
    capped = dataclasses.replace(prm, max_dtn=prm.table_max_dtn)
    for wD in progress(prm.omegas, desc="table_4_1"):
        for wN in prm.omegas:
            t = time.perf_counter()
            sol = _solve(pr, capped, wD, wN, prm.table_friction, prm.table_transfer)
            same = (prm.table_friction, prm.table_transfer) == ("tresca", "functional")
            alt = sol if same else _solve(pr, prm, wD, wN)   # consistent reading (Tresca F)
            pub = PUBLISHED_TABLE.get((wD, wN))
            ok = sol.info.converged
            rows.append(dict(omega_D=wD, omega_N=wN,
                             iterations=float(sol.info.iterations) if ok else np.nan,
                             published=float(pub) if pub else np.nan,
                             converged=ok, reason=sol.info.reason,
                             iterations_tresca=(float(alt.info.iterations)
                                                if alt.info.converged else np.nan),
                             reason_tresca=alt.info.reason,
                             dtn_steps_run=sol.info.iterations,
                             uzawa_total=int(sum(s.iterations for s in sol.info.steps)),
                             norm_W=pr.norm_W(sol.U1, sol.U2),
                             wall_time_s=time.perf_counter() - t))
            if alt.info.converged and (best is None or
                                       alt.info.iterations < best[0].info.iterations):
                best = (alt, wD, wN)
    return pd.DataFrame(rows), best


def table_4_1(prm: Params, pr, df, setup) -> ArtefactResult:
    both = df.dropna(subset=["iterations", "published"])
    ratio = both["iterations"] / both["published"]
    f = prm.iteration_factor
    off = both[(ratio > f) | (ratio < 1 / f)]
    pub_div = df["published"].isna()
    ours_div = ~df["converged"]
    div_cells = df.loc[ours_div, ["omega_D", "omega_N", "reason"]].values.tolist()
    reading = f"friction {prm.table_friction}, transfer {prm.table_transfer}"
    claims = [
        Claim(f"iteration counts within a factor {f} where both converge (reading: {reading})",
              bool(off.empty) if len(both) else None,
              f"ratios ours/published: min {ratio.min():.2f}, max {ratio.max():.2f}; outside: "
              + (", ".join(f"({r.omega_D}, {r.omega_N}) ours {r.iterations:.0f}, thesis "
                           f"{r.published:.0f}" for r in off.itertuples()) or "none"),
              id="counts"),
        Claim("no convergence exactly where omega_D + omega_N >= 1.6 (the '-' cells)",
              bool(np.all(pub_div == ours_div)),
              f"our non-converged cells: {div_cells or 'none'}; the thesis's: "
              f"{df.loc[pub_div, ['omega_D', 'omega_N']].values.tolist()}", id="no_convergence"),
    ]
    alt = df.dropna(subset=["iterations_tresca", "published"])
    ralt = alt["iterations_tresca"] / alt["published"]
    alt_div = df.loc[df["iterations_tresca"].isna(), ["omega_D", "omega_N"]].values.tolist()
    claims.append(Claim(
        "(other reading) Tresca bound F = 0.1 and functional transfer, the consistent "
        "discrete problem (4.55), converges in the thesis's '-' cells: the table is not of "
        "this reading", bool(df.loc[pub_div, "iterations_tresca"].notna().all()),
        f"ratios ours/published {ralt.min():.2f}-{ralt.max():.2f}; non-converged: "
        f"{alt_div or 'none'}", kind="beyond"))
    conv = df[df["converged"]]
    if len(conv):
        s = conv.loc[conv["iterations"].idxmin()]
        claims.append(Claim("fewest iterations when omega_D + omega_N in [1.2, 1.4]",
                            bool(1.2 - 1e-9 <= s.omega_D + s.omega_N <= 1.4 + 1e-9),
                            f"fewest: {int(s.iterations)} at ({s.omega_D}, {s.omega_N})",
                            id="fewest"))
    else:
        claims.append(Claim("fewest iterations when omega_D + omega_N in [1.2, 1.4]", None,
                            "no damping pair converged", id="fewest"))
    claims.append(_symmetry_claim(df, [(r.omega_D, r.omega_N) for r in off.itertuples()]))
    table = df.drop(columns=["published"])
    return ArtefactResult(
        "table_4_1", table, published="table_4_1_dtn_damping.csv",
        keys=("omega_D", "omega_N"), tolerances={"iterations": ("factor", f)},
        claims=claims, notes=" ".join(CHOICES),
        meta=dict(allow_nan_columns=["iterations", "iterations_tresca"], setup_s=setup,
                  dof=_dof(pr), run_s=float(df["wall_time_s"].sum() + setup),
                  reading=_reading(prm)))


def _reading(prm: Params) -> str:
    """Which reading of Algorithm 4.3 the column ``iterations`` of Table 4.1 is."""
    if (prm.table_friction, prm.table_transfer) == ("tresca", "functional"):
        return f"the consistent problem (4.55): Tresca bound F = {prm.F:g}, functional transfer"
    return (f"F = {prm.F:g} as {prm.table_friction} coefficient inside the DtN loop, "
            f"{prm.table_transfer} transfer (the consistent problem: column "
            "iterations_tresca)")


def _symmetry_claim(df, off_cells) -> Claim:
    """Table 4.1 against the (omega_D, omega_N) symmetry of the linearised DtN iteration:
    with the active set frozen, errors p_k, q_k of P and Q obey q_k = (1 - w_D) q_k-1 -
    w_D A p_k, p_k+1 = (1 - w_N) p_k + w_N C q_k, so every eigenvalue m of M = -C A gives
    the amplification factors mu of (mu - 1 + w_D)(mu - 1 + w_N) = w_D w_N m mu, an
    equation symmetric in (w_D, w_N): mirrored cells converge at the same asymptotic rate
    and differ only by the transient.

    An explanation of the cells ``off_cells`` (ours outside the factor of the published
    count): it holds if for each of them the published table breaks this symmetry
    (its mirror cell differs), our counts are symmetric there (within +-1) in both
    readings (columns iterations and iterations_tresca), and ours equals the published
    mirror count within +-1."""
    cols = {"iterations": "this reading", "iterations_tresca": "the consistent reading"}
    ours = {c: {(r.omega_D, r.omega_N): (None if np.isnan(getattr(r, c)) else
                                          int(getattr(r, c))) for r in df.itertuples()}
            for c in cols}

    def near(u, v):
        return (u is None and v is None) or (u is not None and v is not None and
                                             abs(u - v) <= 1)

    pairs = sorted((a, b) for (a, b) in PUBLISHED_TABLE if a < b and (b, a) in PUBLISHED_TABLE)
    sym = [(a, b) for a, b in pairs if PUBLISHED_TABLE[(a, b)] == PUBLISHED_TABLE[(b, a)]]
    spread = {c: max((abs(o[(a, b)] - o[(b, a)]) for a, b in pairs
                      if o.get((a, b)) is not None and o.get((b, a)) is not None), default=0)
              for c, o in ours.items()}
    tests, rows = [], []
    for a, b in off_cells:
        mirror = PUBLISHED_TABLE.get((b, a))
        u = {c: (o.get((a, b)), o.get((b, a))) for c, o in ours.items()}
        tests.append(mirror is not None and mirror != PUBLISHED_TABLE[(a, b)]
                     and all(near(*v) for v in u.values())
                     and u["iterations"][0] is not None and abs(u["iterations"][0] - mirror) <= 1)
        rows.append(f"({a}, {b}) / ({b}, {a}): thesis {PUBLISHED_TABLE[(a, b)]} / {mirror}, "
                    + ", ".join(f"{cols[c]} {v[0]} / {v[1]}" for c, v in u.items()))
    return Claim(
        "the off cells are where the published table breaks the (omega_D, omega_N) "
        "symmetry of the DtN iteration: there our counts are symmetric in both readings "
        "and equal the thesis's mirror cell", bool(all(tests)) if tests else None,
        f"{'; '.join(rows) or 'no off cell'}. Thesis: {len(sym)} of {len(pairs)} mirror pairs "
        "equal. Largest difference of mirrored counts over all pairs: "
        + ", ".join(f"{cols[c]} {v}" for c, v in spread.items()) + " (the linearised "
        "iteration fixes only the asymptotic rate symmetrically, the transient may differ). "
        "We do not tune to the published cell.", kind="explanation", id="symmetry",
        explains=(("counts",) + tuple(f"{CELLS_PREFIX}iterations[omega_D={a},omega_N={b}]"
                                      for a, b in off_cells)) if off_cells else ())


def _dof(pr) -> int:
    return int(pr.body1.n + pr.body2.n)


# --------------------------------------------------------------------------- fig 4.17
def _plot_bodies(ax, pr, sol, shift: float, reference: bool = False) -> list:
    """Boundary polygons and GLL nodes of both bodies displaced by shift * U (with the
    undeformed polygons dashed grey if ``reference``); returns the nodal table rows."""
    rows = []
    for body, bem, U, colour in ((1, pr.bem1, sol.U1, "C0"), (2, pr.bem2, sol.U2, "C3")):
        mesh = bem.mesh
        pts = pr._node_points(bem, np.arange(bem.V_space.ndof))
        disp = U.reshape(-1, 2)
        vert = bem.V_space.elem_dofs[:, 0]
        closed = np.r_[np.arange(len(vert)), 0]
        if reference:
            p0 = mesh.nodes[mesh.elements[:, 0]][closed]
            ax.plot(p0[:, 0], p0[:, 1], "--", color="0.6", lw=0.8,
                    label="undeformed" if body == 1 else None)
        p = (mesh.nodes[mesh.elements[:, 0]] + shift * disp[vert])[closed]
        ax.plot(p[:, 0], p[:, 1], "-", color=colour, lw=0.8, label=f"body {body}")
        q = pts + shift * disp
        ax.plot(q[:, 0], q[:, 1], ".", color=colour, ms=3)
        rows += [dict(body=body, dof=k, x=a, y=b, ux=u, uy=v)
                 for k, ((a, b), (u, v)) in enumerate(zip(pts, disp))]
    ax.set_aspect("equal")
    return rows


def figure_4_17(prm: Params, pr, best) -> ArtefactResult:
    sol, wD, wN = best
    fig = Figure(figsize=(10, 5))
    ax0, ax1 = fig.subplots(1, 2)
    _plot_bodies(ax0, pr, sol, 0.0)
    rows = _plot_bodies(ax1, pr, sol, prm.magnification, reference=True)
    ax1.legend(fontsize=7, loc="center", bbox_to_anchor=(0.5, 0.72))
    ax0.set_title(f"initial meshes (n1, n2) = {tuple(prm.table_n)}, p = {prm.table_p}")
    ax1.set_title(f"deformed (x{prm.magnification:g}), omega = ({wD}, {wN})")
    return ArtefactResult("figure_4_17", pd.DataFrame(rows), figure=fig,
                          notes=" ".join(CHOICES),
                          meta=dict(dtn_iterations=sol.info.iterations,
                                    norm_W=pr.norm_W(sol.U1, sol.U2)))


# --------------------------------------------------------------------------- fig 4.18
def convergence_sweep(prm: Params) -> pd.DataFrame:
    rows, bems = [], {}              # each body assembled once (shared by degree pairs)
    for p1, p2 in progress(prm.conv_degrees, desc="figure_4_18"):
        for n1 in prm.conv_n1:
            t = time.perf_counter()
            pr = _problem(prm, n1, 3 * n1 // 4, p1, p2, bems)
            sol = _solve(pr, prm, *prm.conv_omega)
            wall = time.perf_counter() - t
            table = None
            last = (p1, p2) == tuple(prm.conv_table_degrees[-1])
            if (p1, p2) in prm.conv_table_degrees and (not last or
                                                       n1 <= prm.conv_table_n1_max):
                table = _solve(pr, prm, *prm.conv_omega, friction=prm.table_friction,
                               transfer=prm.table_transfer)
            rows.append(dict(p1=p1, p2=p2, n1=n1, n2=3 * n1 // 4, h1=2.0 / n1, dof=_dof(pr),
                             norm_W=pr.norm_W(sol.U1, sol.U2),
                             norm_W1=float(np.sqrt(sol.U1 @ (pr.bem1.W @ sol.U1))),
                             norm_W2=float(np.sqrt(sol.U2 @ (pr.bem2.W @ sol.U2))),
                             converged=sol.info.converged,
                             dtn_iterations=sol.info.iterations,
                             wall_time_s=wall,
                             norm_W_table=np.nan if table is None else
                             pr.norm_W(table.U1, table.U2),
                             converged_table=table is not None and table.info.converged))
    return pd.DataFrame(rows)


#: the label of Figure 4.18's error (the thesis's axis says "W-err")
W_ERR = r"W-err $= |\,\|U\|_{W,\delta} - \|U\|_{W,\infty}|$"


def _plot_4_18(df: pd.DataFrame, limit: float, rates: dict) -> Figure:
    """Figure 4.18: W-err against DOF per degree pair, the thesis's rates as reference
    slopes, and the limit norm against the thesis's."""
    fig = Figure(figsize=(6.5, 5))
    ax = fig.subplots()
    for (p1, p2), g in df.groupby(["p1", "p2"]):
        ok = g[g["error"] > 0]
        line, = ax.loglog(ok["dof"], ok["error"], "o-",
                          label=f"(p1, p2) = ({p1}, {p2}): rate {rates[(p1, p2)]:.2f}")
        if (p1, p2) in PUBLISHED_RATES and len(ok):
            d = ok["dof"].values[[0, -1]].astype(float)
            r = PUBLISHED_RATES[(p1, p2)]
            ax.loglog(d, 0.5 * ok["error"].values[0] * (d / d[0]) ** -r, ":",
                      color=line.get_color(), label=f"thesis rate {r} for ({p1}, {p2})")
    ax.set_xlabel("DOF")
    ax.set_ylabel(W_ERR + r"  ($\|U\|_{W,\infty}$ ours)")
    ax.legend(fontsize=7, loc="upper right")
    ax.text(0.03, 0.03, f"$\\|U\\|_{{W,\\infty}}$: ours {limit:.6f} (Aitken), thesis "
            f"{PUBLISHED_LIMIT}\nours / thesis = {limit / PUBLISHED_LIMIT:.3f} "
            "(a factor 3, see the claims)", transform=ax.transAxes, fontsize=8,
            va="bottom", bbox=dict(boxstyle="round", fc="white", ec="0.7"))
    ax.set_title("Figure 4.18: convergence of the W-norm", fontsize=10)
    return fig


def figure_4_18(prm: Params, df: pd.DataFrame) -> ArtefactResult:
    ref = df[(df.p1 == prm.conv_degrees[-1][0]) & (df.p2 == prm.conv_degrees[-1][1])]
    limit = aitken(*ref["norm_W"].values[-3:]) if len(ref) >= 3 else float(ref["norm_W"].iloc[-1])
    df = df.assign(error=np.abs(df["norm_W"] - limit))
    claims, rates = [], {}
    for (p1, p2), g in df.groupby(["p1", "p2"]):
        ok = g[g["error"] > 0]
        rates[(p1, p2)] = -fitted_rate(ok["dof"], ok["error"]) if len(ok) >= 2 else np.nan
        if (p1, p2) in PUBLISHED_RATES:
            claims.append(dataclasses.replace(
                rate_claim(f"rate of | ||U||_W - ||U||_W,inf | for ({p1},{p2}) about "
                           f"{PUBLISHED_RATES[(p1, p2)]}", rates[(p1, p2)],
                           PUBLISHED_RATES[(p1, p2)], 0.25), id=f"rate_{p1}{p2}"))
    fig = _plot_4_18(df, limit, rates)
    claims.append(Claim(f"||U||_W,inf = {PUBLISHED_LIMIT}", bool(abs(limit - PUBLISHED_LIMIT)
                                                                 <= 1e-3 * PUBLISHED_LIMIT),
                        f"ours {limit:.6f}, ratio ours/thesis {limit / PUBLISHED_LIMIT:.4f} "
                        f"(sqrt 2 = 1.4142: not the Table 3.1 factor)", id="limit"))
    last = ref.iloc[-1]
    table_ref = ref["norm_W_table"].dropna()
    one_body = [last.norm_W1, last.norm_W2]
    claims.append(Claim(
        f"the thesis's {PUBLISHED_LIMIT} is the W-norm of one body only",
        bool(any(abs(v - PUBLISHED_LIMIT) <= 1e-3 * PUBLISHED_LIMIT for v in one_body)),
        f"finest ({prm.conv_degrees[-1][0]},{prm.conv_degrees[-1][1]}) mesh: body 1 "
        f"{last.norm_W1:.4f} (ratio {last.norm_W1 / PUBLISHED_LIMIT:.3f}), body 2 "
        f"{last.norm_W2:.4f} (ratio {last.norm_W2 / PUBLISHED_LIMIT:.3f}), both "
        f"{last.norm_W:.4f}; none is {PUBLISHED_LIMIT}. Measured separately on the Table "
        "4.1 mesh (both bodies, plane strain 18.21): plane stress 17.48, flat Gamma_C with "
        "the arc as gap 18.24, U zeroed on Gamma_D 45.7; the Table 4.1 reading "
        "(other-reading claim) "
        + (f"{table_ref.iloc[-1]:.4f} on its finest mesh (n1 = "
           f"{int(ref.loc[table_ref.index[-1], 'n1'])})" if len(table_ref) else "not run")
        + "; 6.11 would need u_top ~ -0.033 (u_top = -0.03 gives 5.54)",
        kind="explanation", id="one_body", explains=("limit",)))
    fine = df[df.n1 == df.n1.max()].set_index(["p1", "p2"])["norm_W"]
    if len(ref) >= 2 and len(fine) >= 2:
        spread = float(fine.max() - fine.min())
        step = float(abs(ref["norm_W"].iloc[-1] - ref["norm_W"].iloc[-2]))
        claims.append(Claim(
            "the error is common to all degrees: on the finest mesh the norms of all "
            "(p1, p2) differ by less than the last h-halving changes them (the arc's "
            "polygon changes with h, a geometry error O(h^2)), so every (p1, p2) shows "
            "the same rate", bool(spread < step),
            f"at n1 = {int(df.n1.max())} the norms of all degrees differ by "
            f"{spread:.2e}, while the last h-halving changes the ({prm.conv_degrees[-1][0]},"
            f"{prm.conv_degrees[-1][1]}) norm by {step:.2e}. This does not explain the "
            "thesis's p = 1 rate: with fixed geometry (geometry = 'flat', the arc only as "
            "initial gap; measured separately with this sweep) the rates are (1,1) 1.84, "
            "(2,1) 1.72, (2,2) not monotone (its norm changes by < 3e-4 from n1 = 16 on). "
            "Of the readings tried only the Table 4.1 reading (other-reading claim) "
            "separates the degrees.", kind="beyond"))
    claims.append(_table_reading_rates_claim(prm, df))
    claims.append(_norm_scale_claim(prm, limit))
    notes = " ".join(CHOICES) + (
        " W-err (the thesis's axis label) = | ||U||_W,delta - ||U||_W,inf |, the limit our "
        "own extrapolation (about 3 times the thesis's 6.110073, see the claims)."
        " Columns norm_W_table / converged_table: the same mesh solved with the Table 4.1 "
        "reading (other-reading claim); NaN / False where not run (degree pairs outside "
        "conv_table_degrees; the last of them for h1 < L / conv_table_n1_max).")
    return ArtefactResult("figure_4_18", df, figure=fig, claims=claims, notes=notes,
                          meta=dict(allow_nan_columns=["norm_W_table"], limit=limit,
                                    limit_over_sqrt_4pi_1mnu=float(
                                        limit / np.sqrt(4.0 * np.pi * (1.0 - prm.nu))),
                                    rates={f"{k[0]}{k[1]}": v for k, v in rates.items()},
                                    run_s=float(df["wall_time_s"].sum())))


def _table_reading_rates_claim(prm: Params, df: pd.DataFrame) -> Claim:
    """Figure 4.18 with the DtN of Table 4.1's reading (``table_friction``,
    ``table_transfer``: Coulomb F inside the loop, the function transfer whose fixed point
    is consistent only in the limit h -> 0): the same damping and meshes, the degree
    pairs ``conv_table_degrees``, the last of them up to h1 = L/``conv_table_n1_max``;
    errors against the extrapolated limit of that last pair (Aitken, its last three
    meshes), rates over all meshes and over h1 <= L/8."""
    p_ref = prm.conv_table_degrees[-1]
    df = df[np.isfinite(df["norm_W_table"])]
    ref = df[(df.p1 == p_ref[0]) & (df.p2 == p_ref[1])]["norm_W_table"].values
    text = (f"(other reading) Figure 4.18 with the DtN of Table 4.1's reading "
            f"(friction {prm.table_friction}, transfer {prm.table_transfer}) gives both "
            f"published rates (0.63 for p = 1, 1.89 for p = 2) over one fitted range")
    link = dict(kind="hypothesis", id="table_reading", explains=("rate_11",))
    if len(ref) < 3:
        return Claim(text, None, f"needs three meshes of ({p_ref[0]},{p_ref[1]})", **link)
    limit = aitken(*ref[-3:])

    def rate(dof, err):
        ok = err > 0
        return -fitted_rate(dof[ok], err[ok]) if ok.sum() >= 2 else np.nan

    items, rates = [], {}            # rates[range][(p1, p2)]
    for (p1, p2), g in df.groupby(["p1", "p2"]):
        dof, err = g["dof"].values, np.abs(g["norm_W_table"].values - limit)
        tail = g["n1"].values >= 8
        for k, sel in (("all", slice(None)), ("h1 <= L/8", tail)):
            rates.setdefault(k, {})[(p1, p2)] = rate(dof[sel], err[sel])
        items.append(f"({p1},{p2}) errors " + ", ".join(f"{e:.2e}" for e in err)
                     + f": rate {rates['all'][(p1, p2)]:.2f} over all, "
                     f"{rates['h1 <= L/8'][(p1, p2)]:.2f} for h1 <= L/8")
    fits = [all(abs(r.get(k, np.nan) - v) <= 0.25 for k, v in PUBLISHED_RATES.items())
            for r in rates.values()]
    decidable = all(k in r for r in rates.values() for k in PUBLISHED_RATES)
    return Claim(
        text, bool(any(fits)) if decidable else None,
        f"limit {limit:.6f} (Aitken, ({p_ref[0]},{p_ref[1]})); " + "; ".join(items)
        + f"; converged: {int(df['converged_table'].sum())} of {len(df)}. The function "
        "transfer's action and reaction differ (M2 B^T D^-2 against B^T D^-1), an "
        "inconsistency that vanishes only as h -> 0 (for p1 = p2). The rates move with "
        "the fitted range; neither reading gives both published rates: the consistent one "
        "(our figure) gives the thesis's p = 2 rate for every degree, this one a p = 1 "
        "rate near 0.63 only over part of the range (and p = 2 far above 1.89).", **link)


def _norm_scale_claim(prm: Params, limit: float) -> Claim:
    """The one natural constant found to match the ratio ours / thesis of
    ||U||_W,inf: 4 pi (1 - nu) (the denominator of the plane-strain Kelvin traction
    kernel) in the squared norm - a numerical hypothesis, not a derivation."""
    r2 = (limit / PUBLISHED_LIMIT) ** 2
    cands = {"4 pi (1 - nu)": 4.0 * np.pi * (1.0 - prm.nu), "9": 9.0,
             "2 pi / (1 - nu)": 2.0 * np.pi / (1.0 - prm.nu), "2 (Table 3.1)": 2.0}
    off = {k: np.sqrt(r2 / c) - 1.0 for k, c in cands.items()}
    c = cands["4 pi (1 - nu)"]
    return Claim(
        "the thesis's W-norm is ours divided by sqrt(4 pi (1 - nu)), i.e. the W of its "
        "norm carries an extra factor 1/(4 pi (1 - nu)) (numerical only, not derived)",
        bool(abs(off["4 pi (1 - nu)"]) <= 1e-3),
        f"(ours / thesis)^2 = {r2:.4f} against 4 pi (1 - nu) = {c:.4f} (nu = {prm.nu}); "
        f"ours / sqrt(4 pi (1 - nu)) = {limit / np.sqrt(c):.6f} vs {PUBLISHED_LIMIT}. "
        "Relative norm mismatch left by each candidate factor: " +
        ", ".join(f"{k}: {v:+.2%}" for k, v in off.items()) + ". The norm itself is "
        "the thesis's: its <W U^i, U^i>_Sigma^i lives on Sigma = Gamma_N u Gamma_C "
        "(thesis line 4158), i.e. on U^1 - U_D, which vanishes on Gamma^1_D; W kills the "
        "translation U_D = (0, -0.09), so that equals our whole-boundary <W U^1, U^1> "
        "(measured: 14.298455692786 both on the Table 4.1 mesh). Readings tested on the "
        "Table 4.1 mesh change the norm by < 4 % (plane stress 17.48, Gamma^2_D = "
        "{-1,1} x [-1,0] 18.21, flat Gamma_C 18.24, per body 14.30 / 11.27), none by 3. "
        "A scaling of the thesis's solver operators themselves is excluded: it would "
        "scale the contact tractions by the same factor (1/8.9), while Figure 4.19's "
        "axis (8e4) lies 7x above our traction (reached only by the corner value of the "
        "gap-free reading, figure_4_19); only a norm evaluated with a differently "
        "normalised W fits. The thesis's code is not available to decide.",
        kind="hypothesis", id="norm_scale", explains=("limit",))


# --------------------------------------------------------------------------- fig 4.19
def _plot_4_19(prm: Params, pr, sol) -> Figure:
    """Figure 4.19: the deformed bodies, a zoom on Gamma_C (where the gap closes) and the
    contact tractions against x."""
    pn, pt = sol.extra["pn"], sol.extra["pt"]
    x = pr.points[:, 0]
    order = np.argsort(x)
    on = x[pn > 1e-8 * pn.max()]
    fig = Figure(figsize=(14, 4.8), layout="constrained")
    ax0, ax1, ax2 = fig.subplots(1, 3, width_ratios=(0.8, 1.4, 1.4))
    n1, n2 = prm.coulomb_n
    _plot_bodies(ax0, pr, sol, prm.magnification, reference=True)
    ax0.set_title(f"deformed (x{prm.magnification:g}), h1:h2 = {n1}:{n2}, p = 2", fontsize=9)
    ax0.legend(fontsize=7, loc="center", bbox_to_anchor=(0.5, 0.72))
    _plot_bodies(ax1, pr, sol, prm.magnification, reference=True)
    ax1.set_aspect("auto")
    ax1.set_ylim(prm.u_top - 0.02, 0.12)
    ax1.set_xlim(-1.05, 1.05)
    ax1.axvspan(on.min(), on.max(), color="C2", alpha=0.12, label="contact (p_n > 0)")
    ax1.set_title("zoom on Gamma_C (y stretched): the gap closes over the contact zone",
                  fontsize=9)
    ax1.set_xlabel("x")
    ax1.legend(fontsize=7, loc="upper center", ncol=4)
    ax2.plot(x[order], pn[order], "o-", ms=3, label="normal contact traction")
    ax2.plot(x[order], pt[order], "s-", ms=3, label="tangential contact traction")
    ax2.axhline(0.0, color="0.6", lw=0.5)
    ax2.set_xlabel("x on Gamma_C")
    ax2.set_ylabel("contact traction")
    ax2.legend(fontsize=8, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2,
               frameon=False)
    return fig


def figure_4_19(prm: Params) -> ArtefactResult:
    t = time.perf_counter()
    n1, n2 = prm.coulomb_n
    bems = {}                        # the BE bodies, shared with the gap-free reading
    pr = _problem(prm, n1, n2, 2, 2, bems)
    sol = pr.global_uzawa(rho=prm.rho_global, tol=prm.tol_global, max_iter=prm.max_global,
                          friction="coulomb", mu_f=prm.mu_f)
    run_s = time.perf_counter() - t
    pn, pt = sol.extra["pn"], sol.extra["pt"]
    order = np.argsort(pr.points[:, 0])
    fig = _plot_4_19(prm, pr, sol)
    table = pd.DataFrame(dict(x=pr.points[order, 0], y=pr.points[order, 1], p_n=pn[order],
                              p_t=pt[order], lam=sol.lam[order]))
    peak = float(pn.max())
    claims = [Claim("normal contact traction reaches about 8e4 (the thesis's axis)",
                    bool(4e4 <= peak <= 1.2e5), f"our peak {peak:.4g} "
                    f"(ratio {peak / 8e4:.3f} to 8e4)", id="peak"),
              _traction_claim(prm, pr, sol, bems),
              _gapless_claim(prm, pn, bems),
              Claim("global Uzawa (Algorithm 4.5) converges", bool(sol.info.converged),
                    f"{sol.info.reason} after {sol.info.iterations} iterations, rho = "
                    f"{sol.info.counts.get('rho', np.nan):.4g}", id="converges")]
    return ArtefactResult("figure_4_19", table, figure=fig, claims=claims,
                          notes=" ".join(CHOICES),
                          meta=dict(run_s=run_s, iterations=sol.info.iterations,
                                    dof=_dof(pr), peak_pn=peak))


def _traction_claim(prm: Params, pr, sol, bems: dict) -> Claim:
    """Evidence on the traction scale: the resultant contact force (equilibrium) beside
    a one-dimensional estimate (body 1 in uniaxial plane strain, modulus E', in series
    with the laterally confined body 2, modulus lambda + 2 mu, both of height 2, width
    2, the gap ignored), on the figure's mesh and on the mesh with half as many elements
    (the force must not depend on h).  ``bems``: the BE bodies' cache."""
    lam, mu = lame_constants(prm.E, prm.nu, prm.plane)
    E1 = 4.0 * mu * (lam + mu) / (lam + 2.0 * mu)
    est = 2.0 * abs(prm.u_top) / (2.0 / E1 + 2.0 / (lam + 2.0 * mu))
    n1, n2 = (max(1, n // 2) for n in prm.coulomb_n)
    pr_h = _problem(prm, n1, n2, 2, 2, bems)
    sol_h = pr_h.global_uzawa(rho=prm.rho_global, tol=prm.tol_global, max_iter=prm.max_global,
                              friction="coulomb", mu_f=prm.mu_f)
    tests, rows = [], []
    for q, s, mesh in ((pr, sol, prm.coulomb_n), (pr_h, sol_h, (n1, n2))):
        pn, pt = s.extra["pn"], s.extra["pt"]
        Fy = abs(float(np.sum(q.w * (pn * q.n[:, 1] + pt * q.t[:, 1]))))
        width = float(np.ptp(q.points[pn > 1e-8 * pn.max(), 0]))
        scaled = Fy * 8e4 / pn.max()   # our profile scaled to the thesis's peak
        tests.append(s.info.converged and 0.5 <= Fy / est <= 2.0 and scaled > 2.0 * est)
        rows.append(f"h1:h2 = {mesh[0]}:{mesh[1]}: resultant vertical contact force on body "
                    f"1 {Fy:.4g} over a contact width {width:.3f} (mean pressure "
                    f"{Fy / max(width, 1e-12):.4g}, peak {pn.max():.4g}), the profile scaled "
                    f"to the peak 8e4 carries {scaled:.4g} ({scaled / est:.1f} x the estimate)")
    return Claim(
        "the thesis's traction axis (8e4) does not fit E, nu and U = (0, -0.09): the "
        "contact force is fixed by the prescribed displacement (our resultant agrees with "
        "a one-dimensional estimate within a factor 2 on two meshes), and a traction "
        "peaking at 8e4 would carry more than twice that force", bool(all(tests)),
        "; ".join(rows) + f". One-dimensional estimate (E' = {E1:.4g} in series with "
        f"lambda + 2 mu = {lam + 2 * mu:.4g}, gap ignored) {est:.4g}. Readings "
        "tested (h1:h2 = 41:25 as element counts or as sizes, plane stress, Gamma^2_D = "
        "{-1,1} x [-1,0], flat Gamma_C) give peaks 9.9e3 - 1.09e4; nodal forces (P "
        "times the Gauss-Lobatto weights) peak at 3.5e2. The one reading that reaches the "
        "axis is the gap-free step 3 (next claim).", kind="explanation", id="force",
        explains=("peak",))


def _gapless_claim(prm: Params, pn_ours: np.ndarray, bems: dict) -> Claim:
    """Algorithm 4.5, step 3, as printed: P <- Pi_M(P - rho (U^1 - B^-1 D U^2)), without
    the initial gap g.  The arc is then pressed flat onto Gamma^2_C and the traction is
    singular at the corners x = +-1 (where Gamma^2_C meets body 2's Dirichlet sides):
    solved on the figure's mesh and on the mesh with half as many elements, to show that
    the corner peak depends on h while the interior traction does not.  ``bems``: the
    figure's BE bodies (assembled once, :func:`model_problem`'s cache)."""
    rows, peak = [], np.nan
    for k in (2, 1):                 # k = 1 (last): the figure's mesh
        n1, n2 = (max(1, n // k) for n in prm.coulomb_n)
        pr = _problem(prm, n1, n2, 2, 2, bems, gap=lambda x: np.zeros(len(x)))
        sol = pr.global_uzawa(rho=prm.rho_global, tol=prm.tol_global,
                              max_iter=prm.max_global, friction="coulomb", mu_f=prm.mu_f)
        pn, x = sol.extra["pn"], pr.points[:, 0]
        inner = np.abs(x) <= 0.9
        peak = float(pn.max()) if sol.info.converged else np.nan
        rows.append(f"h1:h2 = {n1}:{n2}: {sol.info.reason}, corner peak {pn.max():.3g} at "
                    f"x = {x[np.argmax(pn)]:+.2f}, |x| <= 0.9: {pn[inner].min():.3g} - "
                    f"{pn[inner].max():.3g}")
    return Claim(
        "(other reading) Algorithm 4.5's step 3 as printed, U^1 - B^-1 D U^2 without the "
        "initial gap: a corner traction on the scale of the thesis's axis (8e4)",
        None if np.isnan(peak) else bool(4e4 <= peak <= 1.2e5),
        "; ".join(rows) + f". With the gap (our figure) the peak is {pn_ours.max():.3g} "
        "near x = 0. Without it the traction is singular at x = +-1, so its peak grows "
        "under refinement and its printed height says nothing about the solution; the "
        "thesis's axis (ticks 0 - 80000) is reached only by such a corner value. "
        "Our figure keeps the gap (the model problem of Section 4.3.4 starts with the arc "
        "touching at one point); the thesis's plot cannot be read to decide.",
        kind="hypothesis", id="gap_free", explains=("peak",))


# --------------------------------------------------------------------------- fig 4.20
def hp_adaptive_run(prm: Params):
    """Algorithm 4.6 on both bodies via hpfebe.adaptivity.adapt: (history, h/p counts)."""
    m1, m2, normal = model_meshes(prm.adapt_n[0], prm.adapt_n[1], prm.adapt_p, prm.adapt_p,
                                  prm.radius)
    store, counts = {}, []

    def solve(meshes):
        pr = contact_from_meshes(meshes[0], meshes[1], normal, prm.E, prm.nu, prm.F,
                                 (0.0, prm.u_top), prm.plane)
        sol = pr.global_uzawa(rho=prm.rho_global, tol=prm.tol_global,
                              max_iter=prm.max_global, friction="coulomb", mu_f=prm.mu_f)
        if not sol.info.converged:
            raise RuntimeError(f"figure_4_20: global Uzawa failed: {sol.info.reason}")
        return (pr, sol), (pr.body1.n, pr.body2.n)

    def estimate(meshes, state):
        store["eta"] = mortar_indicators(*state)
        return store["eta"]

    def refiner(k):
        def refine(mesh, marked):
            eta = store["eta"][k]
            nh = int(np.sum(marked & (eta >= prm.adapt_q2 * eta.max())))
            counts.append(dict(body=k + 1, n_h=nh, n_p=int(marked.sum()) - nh))
            return hp_refine(mesh, marked, eta, prm.adapt_q2)
        return refine

    hist = adapt((m1, m2), solve, estimate, n_steps=prm.adapt_steps + 1, theta=prm.adapt_q1,
                 marking="max", refine=[refiner(0), refiner(1)])
    return hist, counts


def _plot_hp_mesh(ax, meshes, title):
    import matplotlib as mpl

    cmap = mpl.colormaps["viridis"]
    for mesh in meshes:
        for k in range(mesh.n_elements):
            a, b = mesh.a[k], mesh.b[k]
            c = cmap((mesh.degrees[k] - 1) / 4.0)
            ax.plot([a[0], b[0]], [a[1], b[1]], "-", color=c, lw=1 + mesh.degrees[k])
        ax.plot(mesh.a[:, 0], mesh.a[:, 1], "k.", ms=2)
    degs = sorted(set(int(d) for m in meshes for d in m.degrees))
    for d in degs:
        ax.plot([], [], "-", color=cmap((d - 1) / 4.0), lw=1 + d, label=f"p = {d}")
    ax.legend(fontsize=7, loc="center")
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)


def figure_4_20(prm: Params) -> ArtefactResult:
    t = time.perf_counter()
    hist, counts = hp_adaptive_run(prm)
    run_s = time.perf_counter() - t
    rows = []
    for rec, meshes in zip(hist.records, hist.meshes):
        rows.append(dict(step=rec["step"], dof_1=rec["ndof"][0], dof_2=rec["ndof"][1],
                         eta_1=rec["eta"][0], eta_2=rec["eta"][1], eta=rec["eta_total"],
                         elements_1=meshes[0].n_elements, elements_2=meshes[1].n_elements,
                         p_max_1=int(meshes[0].degrees.max()),
                         p_max_2=int(meshes[1].degrees.max()),
                         n_marked_1=rec["n_marked"][0], n_marked_2=rec["n_marked"][1]))
    df = pd.DataFrame(rows)
    show = [k for k in prm.adapt_show if k < len(hist.meshes)]
    fig = Figure(figsize=(4 * (len(show) + 1), 5))
    axes = np.atleast_1d(fig.subplots(1, len(show) + 1))
    for ax, k in zip(axes, [0] + show):
        _plot_hp_mesh(ax, hist.meshes[k], f"step {k}: DOF {sum(hist.records[k]['ndof'])}, "
                      f"p_max {max(int(m.degrees.max()) for m in hist.meshes[k])}")
    ct = pd.DataFrame(counts)
    n_h = int(ct["n_h"].sum()) if len(ct) else 0
    n_p = int(ct["n_p"].sum()) if len(ct) else 0
    claims = [Claim("the hp-adaptive algorithm uses both h- and p-refinement", bool(n_h and n_p),
                    f"{n_h} bisections and {n_p} degree raises over {len(hist.records) - 1} "
                    "steps"),
              Claim("the indicator decreases along the adaptive steps",
                    bool(df["eta"].iloc[-1] < df["eta"].iloc[0]),
                    f"eta {df['eta'].iloc[0]:.4g} -> {df['eta'].iloc[-1]:.4g} (the thesis "
                    "shows the meshes only)", kind="beyond")]
    return ArtefactResult("figure_4_20", df, figure=fig, claims=claims,
                          notes=" ".join(CHOICES), meta=dict(run_s=run_s, n_h=n_h, n_p=n_p))


# --------------------------------------------------------------------------- beyond
def _map_panel(fig, ax, df, om, title):
    grid = df.pivot(index="omega_D", columns="omega_N", values="iterations")
    im = ax.pcolormesh(grid.columns, grid.index, grid.values, shading="nearest",
                       vmin=0, vmax=np.nanmax(df["iterations"].values))
    fig.colorbar(im, ax=ax, label="DtN iterations (blank: not converged)")
    bad = df[~df["converged"]]
    ax.plot(bad["omega_N"], bad["omega_D"], "kx", ms=4, label="not converged")
    ax.plot(om, 1.6 - om, "r--", lw=1, label="omega_D + omega_N = 1.6")
    ax.set_xlim(om.min() - 0.03, om.max() + 0.03)
    ax.set_ylim(om.min() - 0.03, om.max() + 0.03)
    ax.set_xlabel("omega_N (Aitken: its start value)" if "Aitken" in title else "omega_N")
    ax.set_ylabel("omega_D")
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=7,
              frameon=False)             # outside: inside it hid the omega_D = 0.1 row


def figure_dtn_map(prm: Params, pr) -> ArtefactResult:
    """DtN iteration count on a fine damping grid, plain (Algorithm 4.3) and with Aitken's
    dynamic relaxation of omega_N (beyond the thesis)."""
    t = time.perf_counter()
    om = np.asarray(prm.map_omegas, dtype=float)
    rows = []
    for method in ("dtn", "dtn_aitken"):
        for wD in progress(om, desc=f"figure_dtn_map {method}"):
            for wN in om:
                sol = pr.dtn(float(wD), float(wN), rho=prm.rho, tol=prm.tol_dtn,
                             tol_U=prm.tol_uzawa, max_iter=prm.max_dtn,
                             max_uzawa=prm.max_uzawa, rho_relative=prm.rho_relative,
                             aitken=method == "dtn_aitken")
                ok = sol.info.converged
                rows.append(dict(method=method, omega_D=float(wD), omega_N=float(wN),
                                 iterations=float(sol.info.iterations) if ok else np.nan,
                                 converged=ok, reason=sol.info.reason))
    df = pd.DataFrame(rows)
    fig = Figure(figsize=(12, 5.5), layout="constrained")
    axes = fig.subplots(1, 2)
    plain, ait = df[df.method == "dtn"], df[df.method == "dtn_aitken"]
    _map_panel(fig, axes[0], plain, om, "Algorithm 4.3 (fixed damping)")
    _map_panel(fig, axes[1], ait, om, "Aitken relaxation of omega_N (ours)")
    thesis_best = min(v for v in PUBLISHED_TABLE.values() if v)
    ok, ok_a = plain[plain.converged], ait[ait.converged]
    claims = [Claim("on a fine grid (the consistent reading) the fewest DtN iterations lie at "
                    "omega_D + omega_N in [1.2, 1.4]", None, "no cell converged", kind="beyond"),
              Claim(f"Aitken relaxation: fewer iterations than the best thesis cell "
                    f"({thesis_best}) and convergence in every cell with omega_D >= 0.5, "
                    "including those where fixed damping fails", None, "no cell converged",
                    kind="beyond")]
    if len(ok):
        best = ok.sort_values("iterations").iloc[0]
        claims[0] = dataclasses.replace(
            claims[0], holds=bool(1.2 - 1e-9 <= best.omega_D + best.omega_N <= 1.4 + 1e-9),
            evidence=f"fewest {int(best.iterations)} at ({best.omega_D}, {best.omega_N}); "
                     f"{int((~plain.converged).sum())} of {len(plain)} cells not converged")
    if len(ok_a):
        best_a = ok_a.sort_values("iterations").iloc[0]
        claims[1] = dataclasses.replace(
            claims[1], holds=bool(best_a.iterations < thesis_best and
                                  ait[ait.omega_D >= 0.5 - 1e-9].converged.all()),
            evidence=f"Aitken: fewest {int(best_a.iterations)} at omega_D = {best_a.omega_D}; "
                     f"not converged: {int((~ait.converged).sum())} cells, all with omega_D = "
                     f"{sorted(set(ait[~ait.converged].omega_D))} (Aitken relaxes only the "
                     "Neumann side; a small omega_D keeps a slow memory in Q); median "
                     f"{ait.iterations.median():.0f} vs {plain.iterations.median():.0f} "
                     "(fixed)")
    return ArtefactResult("figure_dtn_map", df, figure=fig, claims=claims,
                          notes=" ".join(CHOICES) + " Aitken: w_k clipped to [1e-3, 2].",
                          meta=dict(allow_nan_columns=["iterations"],
                                    run_s=time.perf_counter() - t))


def figure_uzawa_rho(prm: Params) -> ArtefactResult:
    """Global Uzawa iterations against rho / rho_crit (beyond the thesis): the predicted
    bound rho < rho_crit of Theorem 3.1.8 (linear response, largest eigenvalue) against
    the largest convergent step measured."""
    t = time.perf_counter()
    pr = _problem(prm, prm.rho_n[0], prm.rho_n[1], 2, 2)
    rows = []
    for law in ("tresca", "coulomb"):
        for r in progress(prm.rho_ratios, desc=f"figure_uzawa_rho {law}"):
            sol = pr.global_uzawa(rho=2.0 * r, tol=prm.tol_global, max_iter=prm.max_rho_iter,
                                  friction=law, mu_f=prm.mu_f)
            rows.append(dict(friction=law, rho_over_crit=float(r),
                             rho=float(sol.info.counts["rho"]),
                             rho_crit=float(sol.info.counts["rho_crit"]),
                             iterations=sol.info.iterations, converged=sol.info.converged,
                             reason=sol.info.reason))
    df = pd.DataFrame(rows)
    fig = Figure(figsize=(6, 4.5))
    ax = fig.subplots()
    for law, g in df.groupby("friction"):
        ok = g[g["converged"]]
        ax.semilogy(ok["rho_over_crit"], ok["iterations"], "o-", label=f"{law} (converged)")
        nc = g[~g["converged"]]
        ax.semilogy(nc["rho_over_crit"], nc["iterations"], "x", ms=8, label=f"{law} (not)")
    ax.axvline(1.0, color="r", ls="--", label="predicted bound rho_crit")
    ax.set_xlabel("rho / rho_crit")
    ax.set_ylabel("Uzawa iterations")
    ax.legend(fontsize=7)
    largest = df[df["converged"]].groupby("friction")["rho_over_crit"].max().to_dict()
    smallest_bad = df[~df["converged"]].groupby("friction")["rho_over_crit"].min().to_dict()
    below = df[df["rho_over_crit"] < 1.0]
    claims = [Claim("Theorem 3.1.8: Uzawa converges for every rho < rho_crit (spectral "
                    "bound of the linear response)",
                    bool(below["converged"].all()) if len(below) else None,
                    f"largest convergent rho/rho_crit measured {largest}, smallest failing "
                    f"{smallest_bad or 'none'} (the bound is sufficient, not sharp: with the "
                    "tangential part projected to +-F the relevant operator is smaller)",
                    kind="beyond")]
    return ArtefactResult("figure_uzawa_rho", df, figure=fig, claims=claims,
                          notes=" ".join(CHOICES), meta=dict(run_s=time.perf_counter() - t))


def _timed(f, repeats: int = 3):
    """f() and its wall time, the minimum of ``repeats`` calls (single calls of ~1 ms
    scatter by tens of per cent)."""
    walls = []
    for _ in range(repeats):
        t = time.perf_counter()
        sol = f()
        walls.append(time.perf_counter() - t)
    return sol, min(walls)


def _plot_solver_comparison(df: pd.DataFrame) -> Figure:
    """Work-precision per friction law: differences to the reference against wall time;
    differences that are exactly 0 (the run returned the reference bit for bit) as
    open triangles on the lower edge, not at a made-up floor."""
    from matplotlib.transforms import blended_transform_factory

    pos = df.loc[df["rel_difference"] > 0, "rel_difference"]
    fig = Figure(figsize=(11, 5), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for ax, (law, g) in zip(axes, df.groupby("friction", sort=False)):
        edge = blended_transform_factory(ax.transData, ax.transAxes)
        for k, (name, h) in enumerate(g.groupby("method", sort=False)):
            nz, zero = h[h["rel_difference"] > 0], h[h["rel_difference"] == 0]
            colour = f"C{k}"
            ax.loglog(nz["wall_time_s"], nz["rel_difference"], "o-", color=colour,
                      label=name if len(nz) else None)
            if len(zero):
                ax.plot(zero["wall_time_s"], np.full(len(zero), 0.03), "v", mfc="none",
                        color=colour, ms=7, transform=edge,
                        label=f"{name}: difference exactly 0 ({len(zero)} tolerances)")
                ax.text(zero["wall_time_s"].max() * 1.3, 0.03, "exactly 0 (not to scale)",
                        color=colour, fontsize=7, va="center", transform=edge)
        ax.set_xlabel("wall time [s] (minimum of 3 runs)")
        ax.set_title(f"{law} friction (reference: semismooth Newton, tol 1e-13)", fontsize=9)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2,
                  frameon=False)
    if len(pos):
        axes[0].set_ylim(pos.min() / 30, pos.max() * 10)
    axes[0].set_ylabel("max |U - U_ref| / max |U_ref|")
    return fig


def figure_solver_comparison(prm: Params, pr) -> ArtefactResult:
    """The three solvers on one discrete problem (beyond the thesis)."""
    t0 = time.perf_counter()
    rows = []
    for law in ("tresca", "coulomb"):
        ref = pr.semismooth_newton(tol=1e-13, friction=law, mu_f=prm.mu_f)
        scale = max(np.abs(ref.U1).max(), np.abs(ref.U2).max())
        runs = {
            "semismooth Newton": lambda tol: pr.semismooth_newton(tol=tol, friction=law,
                                                                  mu_f=prm.mu_f),
            "global Uzawa": lambda tol: pr.global_uzawa(
                rho=prm.rho_global, tol=tol, max_iter=prm.max_global, friction=law,
                mu_f=prm.mu_f)}
        if law == "tresca":
            runs["DtN + Uzawa"] = lambda tol: pr.dtn(
                *prm.conv_omega, rho=prm.rho, tol=tol, tol_U=min(tol, prm.tol_uzawa),
                max_iter=prm.max_dtn, max_uzawa=prm.max_uzawa, rho_relative=prm.rho_relative)
        for name, f in runs.items():
            for tol in prm.compare_tols:
                sol, wall = _timed(lambda: f(tol))
                err = max(np.abs(sol.U1 - ref.U1).max(), np.abs(sol.U2 - ref.U2).max()) / scale
                rows.append(dict(friction=law, method=name, tol=tol, iterations=sol.info.iterations,
                                 converged=sol.info.converged, wall_time_s=wall,
                                 rel_difference=err, reason=sol.info.reason))
    df = pd.DataFrame(rows)
    fig = _plot_solver_comparison(df)
    tight = df[df["tol"] == min(prm.compare_tols)]
    worst = float(tight["rel_difference"].max())
    claims = [Claim("the solvers agree on the discrete problem at the tightest tolerance",
                    bool(tight["converged"].all() and worst <= 1e-6),
                    f"largest relative difference {worst:.2e}; iterations " +
                    ", ".join(f"{r.friction}/{r.method}: {r.iterations}"
                              for r in tight.itertuples()), kind="beyond")]
    return ArtefactResult("figure_solver_comparison", df, figure=fig, claims=claims,
                          notes=" ".join(CHOICES) + " rel_difference = 0: the run returned "
                          "the reference solution bit for bit.",
                          meta=dict(run_s=time.perf_counter() - t0))


def _table_problem(prm: Params):
    """The Table 4.1 problem (p = table_p on the table_n meshes), shared by the DtN
    artefacts on that mesh, and its set-up time."""
    t = time.perf_counter()
    pr = _problem(prm, prm.table_n[0], prm.table_n[1], prm.table_p, prm.table_p)
    return pr, time.perf_counter() - t


def _scene_table(prm: Params, table) -> list[ArtefactResult]:
    pr, setup = table
    df, best = damping_sweep(prm, pr)
    if best is None:
        raise RuntimeError("table_4_1: no damping pair converged, nothing to plot")
    return [table_4_1(prm, pr, df, setup), figure_4_17(prm, pr, best)]


def _scene_sweep(prm: Params, table) -> list[ArtefactResult]:
    return [figure_4_18(prm, convergence_sweep(prm))]


def _scene_uzawa(prm: Params, table) -> list[ArtefactResult]:
    return [figure_4_19(prm), figure_4_20(prm), figure_uzawa_rho(prm)]


def _scene_beyond(prm: Params, table) -> list[ArtefactResult]:
    return [figure_dtn_map(prm, table[0]), figure_solver_comparison(prm, table[0])]


#: the computation of each scene of :data:`SCENES`; those on the Table 4.1 mesh get
#: ``table`` = (problem, set-up time) of :func:`_table_problem` (assembled once per run)
_SCENE_RUNS = {"table": (_scene_table, True), "sweep": (_scene_sweep, False),
               "uzawa": (_scene_uzawa, False), "beyond": (_scene_beyond, True)}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """scenes: names of :data:`SCENES` to compute (None: all)."""
    prm = from_config(Params, config, "ch4_mortar")
    if quick and "adapt_steps" not in (config or {}):
        prm = dataclasses.replace(prm, adapt_steps=QUICK_ADAPT[0], adapt_show=QUICK_ADAPT[1])
    scenes = tuple(SCENES) if scenes is None else tuple(scenes)
    unknown = [s for s in scenes if s not in SCENES]
    if unknown:
        raise ValueError(f"ch4_mortar: unknown scenes {unknown}; known: {list(SCENES)}")
    table, out = None, []
    for name in SCENES:              # in the order of SCENES, whatever the order asked
        if name not in scenes:
            continue
        f, on_table_mesh = _SCENE_RUNS[name]
        if on_table_mesh and table is None:
            table = _table_problem(prm)
        out += f(prm, table)
    return out
