"""The runs of Section 4.2.7 (Figures 4.1-4.12) and their tables: the choices where the
thesis is silent (:data:`CHOICES`), the parameters (:class:`Params`, on the scene
:class:`hpfebe.scenes.plasticity.StampingScene`), every run of an example, the BE/BE
runs of Example 2 and their mesh study."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from hpfebe.scenes import element_areas, plastic_zone
from hpfebe.scenes import plasticity
from hpfebe.suite import progress

CHOICES = (
    "Material of the work piece (not given in Section 4.2.7): sigma_Y = 4.0 and hardening "
    "H = 450.0 of Section 4.4; E = 266926, nu = 0.29 in both bodies, plane strain with the "
    "full 3 x 3 stress and plastic strain. theta (isotropic share of the hardening) is not "
    "given: theta = 1 (isotropic) and theta = 0 (kinematic) are both run; figures of fields "
    "show the first of config 'thetas'.",
    "Friction and penalty (not given in Section 4.2.7): Coulomb mu_f = 0.2 and 1/eps_n = "
    "10 E, 1/eps_t = 5 E of Table 4.3 (Section 4.4).",
    "Work piece: Q1 with the mean-dilatation B-bar strain (locking free under isochoric "
    "plastic flow); fully integrated Q1 is shown beside it in figure_4_12. Stamp: Q1 (FE) "
    "or Galerkin BEM of degree be_degree (BE), mesh size h on both bodies.",
    "Load path (Example 1; the thesis does not describe it): touch 1 lifts the bottom from "
    "0 to 4.3e-3 in n_load equal increments and lowers it back to 0 in n_unload increments "
    "(the contact opens); the stamp is then moved to its second place (a new, undeformed "
    "stamp) and touch 2 repeats the lift. The work piece keeps its plastic history and its "
    "residual displacement, whose deformed top is the contact geometry of touch 2.",
    "Applied force = the vertical reaction at the work piece's bottom per unit thickness "
    "(sum of the internal force over its y dofs). ||dev sigma|| and ||eps_p|| at X are "
    "element means averaged over the elements touching X (one to four: Example 2's X = (1, "
    "-1.1) lies on an element edge for h = 0.2 and is a mesh vertex for h <= 0.1).",
    "Newton: each increment starts from the secant extrapolation of the last two converged "
    "states (at the first unloading increment: the work piece lowered rigidly, the stamp "
    "at rest), or from TwoBodyContact's bonded predictor when that lowers ||R||; Armijo "
    "line search on ||R||, stop at ||R|| <= rtol x force scale + rtol x the reference "
    "force (the work piece's width times the smaller of sigma_Y and the elastic stress of "
    "the lift: scenes.stamping.reference_force; sigma_Y in every thesis scene); a "
    "failed increment is halved (at most max_cuts times).",
    "Plastic zone = elements with mean ||eps_p|| > zone_tol.",
    "Newton systems with an FE body: SuperLU with minimum degree ordering on A^T + A and "
    "symmetric-mode (diagonal-preferring, threshold 0.01) pivoting (lu_ordering = "
    "'MMD_AT_PLUS_A'; ~1.7x faster per factorisation than SuperLU's default "
    "'COLAMD'). Only the round-off of each Newton step "
    "differs between the two (3e-13 relative), but this module's results are sensitive "
    "to it: the iteration counts of the unloading increments (whose forces are "
    "round-off), and whether a hard increment (touch 2, first lift, 30-100 iterations "
    "with step cuts) converges at once or is cut, which changes the load path of that "
    "run (||dev sigma|| at X up to 0.2 %, ||eps_p|| at X up to 3 % along the curve; "
    "peak values up to 6e-4, plastic area 4e-4). Measured against 'COLAMD' (the "
    "ordering before this choice): every claim keeps its verdict; ordering and machine "
    "(BLAS, CPU) move these digits alike. So do the BE bodies' p = 1 operators: their "
    "closed forms (lowest_order, to 7e-15 of the quadrature path's matrices) changed "
    "the Newton counts of figures 4.3-4.5, 4.8, 4.9, 4.12, one cut increment (83 "
    "iterations in 3 attempts -> 27 in 1) and eps_p_max by 6e-4 relative, exactly as a "
    "random 1e-15 relative perturbation of the quadrature path's V, K, W does; no claim "
    "changed its verdict.",
    "BE/BE (Example 2; the thesis gives no cells or step rule): the work piece's plastic "
    "strain is constant on cells of size bebe_h covering it, each grid square split into "
    "four triangles through its centre (bebe_cells = crossed: constant plastic strain on "
    "axis-parallel squares locks - its compatible isochoric fields are shears along the "
    "grid lines, measured 65/33/18 % too stiff on a punch with 4/8/16 squares per unit "
    "against 2 % with crossed triangles). The plastic strain is updated by backward "
    "Euler (return map of the cell strains solved with the boundary data, consistent "
    "tangent) instead of the thesis's forward Euler: with E / sigma_Y = 66700 a lift "
    "increment of 4.2e-4 is ~30 yield strains and the one-step-lagged plastic strain "
    "is stiff by the elastic predictor (measured, h = 0.4: stamp reaction 352 with 10 "
    "increments, 125 with 40, against 24.8 with backward Euler; first order, ~3000 "
    "increments for 5 %). Loading only (n_load "
    "increments, no unloading); every theta of thetas; the interior displacement "
    "(deformed grid) by the representation formula at the cell nodes. Compared with "
    "FE/FE on the same grid (bebe_h): ||dev sigma|| at X = mean over the cells touching "
    "X; ||eps_p|| as element means (the four cells of a square area-averaged). Measured "
    "beside the figures (theta = 1, 10 increments): at bebe_h = 0.2 (800 cells, 5.4-6.4 "
    "min per theta with one BLAS thread on a loaded machine, 7-8 min with two, dominated "
    "by ~800 dense LU factorisations of the 2400 x 2400 cell-strain Jacobian; above the "
    "5 min target, hence 0.4) BE/BE vs FE/FE h = 0.2 "
    "differs by 1.5 % in the force and 20.3 % in ||dev sigma|| at X (X is 0.1 below the "
    "stamp corner: the value is mesh dependent, FE/FE moves 15.6 % and 7.7 % between "
    "h = 0.2, 0.1, 0.05), and the BE/BE h = 0.2 curve lies within 1.5 % of FE/FE h = 0.1 "
    "and 6.3 % of h = 0.05; its top surface agrees except at the two outer corners "
    "(u_y 4.27e-3 vs 3.51e-3, 21.6 %).",
    "BE/BE mesh study (beyond the thesis, figure_4_12): BE/BE and FE/FE on the same "
    "meshes bebe_h_levels (default 1.0, 0.5, 0.4; the bebe_h run is reused), theta = "
    "thetas[0]; successive differences of the ||dev sigma|| curve at X, of the force "
    "curve and of the plastic zone area (cells / elements with ||eps_p|| > zone_tol at "
    "full lift), and the same per halving of h (divided by log2(h_i / h_i+1), as "
    "0.5 -> 0.4 is a smaller step than 1.0 -> 0.5; shrinking raw differences there would "
    "hold for almost any sequence). h = 0.25 (512 cells) is not in the study: measured "
    "104 s for theta = 1 at load 2 (one BLAS thread), ||dev sigma||_X 6.66 and force "
    "22.00 at full lift against 4.74 and 24.76 at h = 0.4.",
    "FE/FE refinement at X (figure_4_12's hypothesis 'converges'; measured beside the "
    "workflow, theta = 1, B-bar, one thread): the successive max differences of the "
    "||dev sigma|| curve at X are 15.6 %, 7.7 %, 1.2 % on h = 0.2, 0.1, 0.05, 0.025 (X a "
    "mesh vertex for h <= 0.1; h = 0.025 takes 87 s, as long as the rest of Example 2) "
    "but 19.2 %, 23.9 %, 10.6 % on h = 0.5, 0.25, 0.125, 0.0625 (X on an element edge): "
    "no common observed order (log2 of the ratios 1.0, 2.6 against -0.3, 1.2), so the "
    "convergence of the value at X stays a hypothesis; peak at full lift 6.03, 7.15, "
    "7.75, 7.73 against 4.47, 5.54, 7.27, 7.89.",
)


@dataclass(frozen=True)
class Params(plasticity.StampingScene):
    """The scene's data (:class:`hpfebe.scenes.plasticity.StampingScene`: material,
    penalty, Newton, load path) and the studies and claims of this module."""

    thetas: tuple[float, ...] = (1.0, 0.0)
    h_levels: tuple[float, ...] = (0.2, 0.1, 0.05)
    h_figure: float = 0.1
    magnification: float = 100.0
    zone_tol: float = 1e-4
    close_tol: float = 0.05          # curves "very close": max relative difference
    similar_tol: float = 0.2         # fields / zones "similar": relative difference
    locking_study: bool = True
    bebe: bool = True                # BE/BE of Example 2 (figures 4.10, 4.11, 4.12)
    bebe_h: float = 0.4              # its mesh and cell size
    bebe_h_levels: tuple[float, ...] = (1.0, 0.5, 0.4)   # BE/BE mesh study, thetas[0]

    def __post_init__(self):
        super().__post_init__()
        if not self.thetas or any(not 0 <= t <= 1 for t in self.thetas):
            raise ValueError(f"thetas must be values in [0, 1], got {self.thetas!r}")
        if not self.h_levels or any(not h > 0 for h in self.h_levels):
            raise ValueError(f"h_levels must be positive mesh sizes, got {self.h_levels!r}")
        if self.h_figure not in self.h_levels:
            raise ValueError(f"h_figure must be one of h_levels {self.h_levels!r}, got "
                             f"{self.h_figure!r}")
        for name in ("magnification", "close_tol", "similar_tol", "bebe_h"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        hs = self.bebe_h_levels
        if any(not h > 0 for h in hs) or any(b >= a for a, b in zip(hs, hs[1:])):
            raise ValueError(f"bebe_h_levels must be positive and decreasing, got {hs!r}")


def all_runs(prm: Params, examples=(1, 2)) -> dict:
    """{(example, stamp, theta, h, formulation): Run} of the given examples."""
    jobs = [(ex, st, th, h, "bbar") for ex in examples for th in prm.thetas
            for st in ("FE", "BE") for h in prm.h_levels]
    if prm.locking_study and 2 in examples:
        jobs += [(2, "FE", prm.thetas[0], h, "full") for h in prm.h_levels]
    return {j: prm.run_example(*j) for j in progress(jobs, desc="stamping runs")}


def bebe_runs(prm: Params, runs: dict | None = None) -> dict:
    """Example 2 with the BE work piece under a BE stamp (mesh bebe_h), for every theta
    of 'thetas', and FE/FE on the same mesh as a same-resolution reference (taken from
    ``runs`` when bebe_h is one of h_levels): {theta: {"BE/BE": Run, "FE/FE": Run}}."""
    if not prm.bebe:
        return {}
    return {th: bebe_pair(prm, th, prm.bebe_h, runs) for th in prm.thetas}


def bebe_pair(prm: Params, th: float, h: float, runs: dict | None) -> dict:
    """BE/BE of Example 2 on mesh h and FE/FE on the same mesh (from ``runs`` if there)."""
    bb = prm.run_bebe(th, h)
    fefe = (runs or {}).get((2, "FE", th, h, "bbar")) or prm.run_example(2, "FE", th, h)
    return {"BE/BE": bb, "FE/FE": fefe}


def bebe_mesh_study(prm: Params, runs: dict, bebe: dict) -> dict:
    """Beyond the thesis: BE/BE (and FE/FE on the same meshes) of Example 2 on every mesh
    of bebe_h_levels, theta = thetas[0]; the bebe_h run of :func:`bebe_runs` is reused:
    {h: {"BE/BE": Run, "FE/FE": Run}} ({} when bebe is off or fewer than two levels)."""
    th, hs = prm.thetas[0], prm.bebe_h_levels
    if not prm.bebe or len(hs) < 2:
        return {}
    return {h: bebe[th] if h == prm.bebe_h and th in bebe else bebe_pair(prm, th, h, runs)
            for h in progress(hs, desc="BE/BE mesh study")}


def curve_table(runs: dict, example: int) -> pd.DataFrame:
    rows = []
    for (ex, st, th, h, form), r in runs.items():
        if ex != example:
            continue
        for k, rec in enumerate(r.records):
            rows.append(dict(example=ex, coupling=f"FE/{st}" if st == "BE" else "FE/FE",
                             theta=th, h=h, formulation=form, increment=k + 1,
                             **asdict(rec)))
    return pd.DataFrame(rows)


def summary_table(prm: Params, runs: dict, example: int) -> pd.DataFrame:
    rows = []
    for (ex, st, th, h, form), r in runs.items():
        if ex != example:
            continue
        f = r.touches[-1].peak.fields if r.touches[-1].peak else r.fe.fields()
        zone = plastic_zone(r.fe, r.fe.fields()["eps_p_norm_mean"], prm.zone_tol)
        its = [rec.iterations for rec in r.records]
        rows.append(dict(example=ex, coupling="FE/BE" if st == "BE" else "FE/FE",
                         theta=th, h=h, formulation=form, dof_work=r.fe.ndofs,
                         converged=r.converged,
                         eps_p_max=float(r.fe.fields()["eps_p_norm_mean"].max()),
                         dev_sigma_max_peak=float(f["dev_sigma_norm"].max()),
                         plastic_area=float(element_areas(r.fe)[zone].sum()),
                         newton_total=int(sum(its)), newton_max=int(max(its, default=0)),
                         newton_mean=float(np.mean(its)) if its else float("nan"),
                         newton_per_increment=" ".join(map(str, its)),
                         wall_time_s=r.wall_s))
    return pd.DataFrame(rows)


def bebe_table(bebe: dict) -> pd.DataFrame:
    """Load records of BE/BE and its same-mesh FE/FE reference, every theta."""
    rows = []
    for pair in bebe.values():
        for name, r in pair.items():
            for k, rec in enumerate(r.records):
                rows.append(dict(example=2, coupling=name, theta=r.theta, h=r.h,
                                 formulation=r.formulation, increment=k + 1,
                                 **asdict(rec)))
    return pd.DataFrame(rows)
