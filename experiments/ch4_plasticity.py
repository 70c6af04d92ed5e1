"""Figures 4.1-4.12 (Section 4.2.7, thesis lines 14810-14920): an elastic stamp pressed
onto an elastoplastic work piece, frictional penalty contact, Algorithm 4.1 (incremental
loading, Newton), J2 flow theory with mixed hardening (4.21)-(4.22), radial return and
its algorithmic tangent (4.38)-(4.43).

Example 1 (figure_4_1 ... figure_4_5): the stamp (slave, elastic) at [0.2, 1.2] x [-1, 1]
for the first touch and at [-1.8, -0.8] x [-1, 1] for the second, its top fixed; work
piece (master, elastoplastic) [-2, 2] x [-3, -1], its bottom lifted by 4.3e-3 in
increments; FE/FE and FE/BE (stamp by the Galerkin BEM, S_hat); deformed meshes (x100),
||eps_p|| and ||dev sigma|| against the applied force at X = (-0.9, -1.1).
Example 2 (figure_4_6 ... figure_4_12): one touch of the stamp [-1, 1] x [-1, 0], lift
4.2e-3; ||dev sigma|| at X = (1, -1.1).  BE/BE (figure_4_10, figure_4_11 and the BE/BE
curve of figure_4_12): the plastic BE work piece of Section 4.2.4
(:mod:`hpfebe.bodies.plastic_be`: Newton potentials of a cell-wise constant plastic strain,
backward Euler update) under a BE stamp, every theta of 'thetas' (the figures show the
first), mesh bebe_h.

Scenes (:data:`SCENES`, one workflow job each): ``ex1`` (figures 4.1-4.5) and ``ex2``
(figures 4.6-4.12 with the locking study, BE/BE and its mesh study).

Core: :mod:`hpfebe.constitutive.j2` (return map), :mod:`hpfebe.fem.plastic_body` (B-bar
Q1 work piece), :mod:`hpfebe.scenes.stamping` (touches through
:class:`hpfebe.contact.two_body.TwoBodyContact`).  The choices where the thesis is silent
are :data:`CHOICES`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass

import meshio
import numpy as np
import pandas as pd
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from hpfebe.contact.loading import LU_ORDERINGS
from hpfebe.io.vtu import fe_vtu
from hpfebe.constitutive.j2 import J2Material
from hpfebe.scenes import (ContactSettings, be_work_piece, curve_difference,
                           element_areas, field_difference, plastic_zone,
                           stamp_body, stamp_interior, touch, touch_be, work_piece,
                           zone_mismatch)
from hpfebe.suite.params import from_config
from hpfebe.suite.results import ArtefactResult, Claim, progress

ARTEFACTS = ("figure_4_1", "figure_4_2", "figure_4_3", "figure_4_4", "figure_4_5",
             "figure_4_6", "figure_4_7", "figure_4_8", "figure_4_9", "figure_4_10",
             "figure_4_11", "figure_4_12")
#: the two examples are independent computations, one workflow job each.  Example 2's
#: artefacts stay together: figure_4_6 ... figure_4_9 tabulate every Example 2 run (the
#: fully integrated Q1 ones included) and figure_4_12 needs them all, the BE/BE runs of
#: figures 4.10-4.11 and the BE/BE mesh study.  CPU time of the full config, one thread
#: (measured on a loaded machine): ex1 91 s, ex2 72 s (meta scene_s: the wall time).
SCENES = {"ex1": ("figure_4_1", "figure_4_2", "figure_4_3", "figure_4_4", "figure_4_5"),
          "ex2": ("figure_4_6", "figure_4_7", "figure_4_8", "figure_4_9", "figure_4_10",
                  "figure_4_11", "figure_4_12")}

log = logging.getLogger(__name__)

WORK = (-2.0, 2.0, -3.0, -1.0)
STAMPS = {1: ((0.2, 1.2, -1.0, 1.0), (-1.8, -0.8, -1.0, 1.0)), 2: ((-1.0, 1.0, -1.0, 0.0),)}
POINT = {1: (-0.9, -1.1), 2: (1.0, -1.1)}

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
    "line search on ||R||, stop at ||R|| <= rtol x force scale + rtol sigma_Y width; a "
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
class Params:
    E: float = 266926.0
    nu: float = 0.29
    sigma_Y: float = 4.0
    H: float = 450.0
    thetas: tuple[float, ...] = (1.0, 0.0)
    mu_f: float = 0.2
    eps_n_factor: float = 10.0
    eps_t_factor: float = 5.0
    rtol: float = 1e-8
    max_newton: int = 40
    max_cuts: int = 4
    predictor: bool = True               # bonded predictor of TwoBodyContact per increment
    h_levels: tuple[float, ...] = (0.2, 0.1, 0.05)
    h_figure: float = 0.1
    n_load: int = 10
    n_unload: int = 2
    ex1_u: float = 4.3e-3
    ex2_u: float = 4.2e-3
    be_degree: int = 1
    magnification: float = 100.0
    zone_tol: float = 1e-4
    close_tol: float = 0.05          # curves "very close": max relative difference
    similar_tol: float = 0.2         # fields / zones "similar": relative difference
    locking_study: bool = True
    bebe: bool = True                # BE/BE of Example 2 (figures 4.10, 4.11, 4.12)
    bebe_h: float = 0.4              # its mesh and cell size
    bebe_cells: str = "crossed"
    bebe_h_levels: tuple[float, ...] = (1.0, 0.5, 0.4)   # BE/BE mesh study, thetas[0]
    lu_ordering: str = "MMD_AT_PLUS_A"   # sparse LU ordering (ContactSettings; CHOICES)

    def __post_init__(self):
        if not self.thetas or any(not 0 <= t <= 1 for t in self.thetas):
            raise ValueError(f"thetas must be values in [0, 1], got {self.thetas!r}")
        if self.h_figure not in self.h_levels:
            raise ValueError(f"h_figure must be one of h_levels {self.h_levels!r}, got "
                             f"{self.h_figure!r}")
        if self.lu_ordering not in LU_ORDERINGS:
            raise ValueError(f"lu_ordering must be one of {LU_ORDERINGS}, got "
                             f"{self.lu_ordering!r}")
        if self.bebe_cells not in ("quad", "crossed"):
            raise ValueError(f"bebe_cells must be 'quad' or 'crossed', got {self.bebe_cells!r}")
        for name in ("ex1_u", "ex2_u", "magnification", "close_tol", "similar_tol",
                     "bebe_h"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        hs = self.bebe_h_levels
        if any(not h > 0 for h in hs) or any(b >= a for a, b in zip(hs, hs[1:])):
            raise ValueError(f"bebe_h_levels must be positive and decreasing, got {hs!r}")

    @property
    def settings(self) -> ContactSettings:
        return ContactSettings(self.eps_n_factor, self.eps_t_factor, self.mu_f, self.rtol,
                               self.max_newton, self.max_cuts, self.predictor,
                               lu_ordering=self.lu_ordering)


@dataclass
class Run:
    example: int
    stamp: str
    theta: float
    h: float
    formulation: str
    fe: object
    touches: list
    wall_s: float

    @property
    def converged(self) -> bool:
        return all(t.converged for t in self.touches)

    @property
    def records(self) -> list:
        return [r for t in self.touches for r in t.records]


# --------------------------------------------------------------------------- computation
def run_example(prm: Params, example: int, stamp: str, theta: float, h: float,
                formulation: str = "bbar") -> Run:
    """All touches of one example with one stamp discretisation, theta and mesh size."""
    t0 = time.perf_counter()
    mat = J2Material(prm.E, prm.nu, prm.sigma_Y, prm.H, theta)
    fe = work_piece(WORK, h, mat, formulation)
    u_total = prm.ex1_u if example == 1 else prm.ex2_u
    touches, offset = [], None
    for k, box in enumerate(STAMPS[example], start=1):
        body = stamp_body(stamp, box, h, prm.E, prm.nu, p=prm.be_degree)
        tr = touch(body, fe, u_total, prm.n_load, prm.n_unload, POINT[example],
                   prm.settings, offset=offset, touch_id=k)
        touches.append(tr)
        if not tr.converged:
            log.warning("example %d %s theta=%g h=%g: %s", example, stamp, theta, h,
                        tr.reason)
            break
        offset = tr.u_work
    return Run(example, stamp, theta, h, formulation, fe, touches, time.perf_counter() - t0)


def all_runs(prm: Params, examples=(1, 2)) -> dict:
    """{(example, stamp, theta, h, formulation): Run} of the given examples."""
    jobs = [(ex, st, th, h, "bbar") for ex in examples for th in prm.thetas
            for st in ("FE", "BE") for h in prm.h_levels]
    if prm.locking_study and 2 in examples:
        jobs += [(2, "FE", prm.thetas[0], h, "full") for h in prm.h_levels]
    return {j: run_example(prm, *j) for j in progress(jobs, desc="stamping runs")}


def bebe_runs(prm: Params, runs: dict | None = None) -> dict:
    """Example 2 with the BE work piece under a BE stamp (mesh bebe_h), for every theta
    of 'thetas', and FE/FE on the same mesh as a same-resolution reference (taken from
    ``runs`` when bebe_h is one of h_levels): {theta: {"BE/BE": Run, "FE/FE": Run}}."""
    if not prm.bebe:
        return {}
    return {th: _bebe_pair(prm, th, prm.bebe_h, runs) for th in prm.thetas}


def _bebe_pair(prm: Params, th: float, h: float, runs: dict | None) -> dict:
    """BE/BE of Example 2 on mesh h and FE/FE on the same mesh (from ``runs`` if there)."""
    t0 = time.perf_counter()
    mat = J2Material(prm.E, prm.nu, prm.sigma_Y, prm.H, th)
    be = be_work_piece(WORK, h, mat, prm.bebe_cells)
    body = stamp_body("BE", STAMPS[2][0], h, prm.E, prm.nu, p=1)
    tr = touch_be(body, be, prm.ex2_u, prm.n_load, POINT[2], prm.settings)
    if not tr.converged:
        log.warning("BE/BE theta=%g h=%g: %s", th, h, tr.reason)
    bb = Run(2, "BE/BE", th, h, prm.bebe_cells, be, [tr], time.perf_counter() - t0)
    fefe = (runs or {}).get((2, "FE", th, h, "bbar")) or run_example(prm, 2, "FE", th, h)
    return {"BE/BE": bb, "FE/FE": fefe}


def bebe_mesh_study(prm: Params, runs: dict, bebe: dict) -> dict:
    """Beyond the thesis: BE/BE (and FE/FE on the same meshes) of Example 2 on every mesh
    of bebe_h_levels, theta = thetas[0]; the bebe_h run of :func:`bebe_runs` is reused:
    {h: {"BE/BE": Run, "FE/FE": Run}} ({} when bebe is off or fewer than two levels)."""
    th, hs = prm.thetas[0], prm.bebe_h_levels
    if not prm.bebe or len(hs) < 2:
        return {}
    return {h: bebe[th] if h == prm.bebe_h and th in bebe else _bebe_pair(prm, th, h, runs)
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


# --------------------------------------------------------------------------- comparisons
def _curve(run: Run, touch_id=None) -> np.ndarray:
    return np.array([r.dev_sigma_X for r in run.records
                     if touch_id is None or r.touch == touch_id])


def _curve_difference(a: Run, b: Run, curve=None) -> float | None:
    """curve_difference of two runs' curves (``curve``: default all records of
    ||dev sigma|| at X), None unless both runs converged (their records differ in
    length otherwise)."""
    curve = curve or _curve
    return curve_difference(curve(a), curve(b)) if a.converged and b.converged else None


def _pct(v: float | None) -> str:
    return "not converged" if v is None else f"{v:.2%}"


def coupling_claim(prm: Params, runs: dict, example: int) -> Claim:
    """FE/FE and FE/BE curves of ||dev sigma|| at X very close (max relative difference
    along the load path, at h_figure and on every mesh), beside the mesh differences."""
    parts, ev = [], []
    for th in prm.thetas:
        d = {h: _curve_difference(runs[(example, "FE", th, h, "bbar")],
                                  runs[(example, "BE", th, h, "bbar")])
             for h in prm.h_levels}
        hs = prm.h_levels
        mesh = [_curve_difference(runs[(example, "FE", th, hs[i + 1], "bbar")],
                                  runs[(example, "FE", th, hs[i], "bbar")])
                for i in range(len(hs) - 1)]
        v = d[prm.h_figure]
        parts.append(None if v is None else v <= prm.close_tol)
        ev.append(f"theta={th:g}: max rel. difference FE/FE vs FE/BE "
                  + ", ".join(f"h={h:g}: {_pct(v)}" for h, v in d.items())
                  + "; FE/FE between successive meshes "
                  + ", ".join(_pct(v) for v in mesh))
    return Claim(f"FE/FE and FE/BE curves of ||dev sigma|| at X = {POINT[example]} are very "
                 f"close (max relative difference <= {prm.close_tol:.0%} at h = "
                 f"{prm.h_figure:g})", _all_hold(parts), "; ".join(ev), id="close")


def zone_claim(prm: Params, runs: dict, example: int) -> Claim:
    """Similar plastic deformation in FE/FE and FE/BE: L2 difference of ||eps_p|| and
    mismatch of the plastic zones (same work piece mesh) after the last touch."""
    ok, ev = [], []
    for th in prm.thetas:
        for h in prm.h_levels:
            a, b = runs[(example, "FE", th, h, "bbar")], runs[(example, "BE", th, h, "bbar")]
            if not (a.converged and b.converged):
                if h == prm.h_figure:
                    ok.append(None)
                ev.append(f"theta={th:g} h={h:g}: not converged")
                continue
            fa = a.fe.fields()["eps_p_norm_mean"]
            fb = b.fe.fields()["eps_p_norm_mean"]
            diff = field_difference(a.fe, fa, fb)
            mis = zone_mismatch(a.fe, plastic_zone(a.fe, fa, prm.zone_tol),
                                plastic_zone(b.fe, fb, prm.zone_tol))
            if h == prm.h_figure:
                ok.append(diff <= prm.similar_tol and mis <= prm.similar_tol)
            ev.append(f"theta={th:g} h={h:g}: ||eps_p|| L2 difference {diff:.2%}, zone "
                      f"mismatch {mis:.2%}")
    return Claim(f"similar plastic deformations in the work piece for FE and BE stamps "
                 f"(L2 difference of ||eps_p|| and plastic zone mismatch <= "
                 f"{prm.similar_tol:.0%} at h = {prm.h_figure:g})", _all_hold(ok),
                 "; ".join(ev), id="similar")


def dent_claim(prm: Params, run: Run) -> Claim:
    """The stamp leaves a permanent dent: residual top displacement under each stamp
    after unloading, relative to the lift."""
    fe, ev, ok = run.fe, [], []
    u_total = prm.ex1_u if run.example == 1 else prm.ex2_u
    top = fe.elastic.boundary_vertices("top")
    x = fe.mesh.p[0, top]
    for tr, box in zip(run.touches, STAMPS[run.example]):
        uy = fe.elastic.nodal_displacement(tr.u_work)[1, top]
        under = (x >= box[0]) & (x <= box[1])
        dent = float(-uy[under].mean())
        ok.append(dent > 0.5 * u_total)
        ev.append(f"touch {tr.records[0].touch}: mean residual depth under the stamp "
                  f"{dent:.3e} ({dent / u_total:.0%} of the lift), deepest "
                  f"{-uy[under].min():.3e}")
    if not run.converged:
        ev.append(f"not converged: {run.touches[-1].reason}")
    return Claim("the stamp leaves a permanent (plastic) dent in the work piece at each "
                 "touch (mean residual depth under the stamp > 50 % of the lift)",
                 bool(all(ok)) if run.converged else None, "; ".join(ev), id="dent")


def mesh_claims(prm: Params, runs: dict) -> list[Claim]:
    """Beyond the thesis, Example 2 FE/FE at thetas[0] on h_levels: the hypothesis that
    the B-bar curve of ||dev sigma|| at X converges (its successive differences shrink;
    two differences are no rate and a second mesh family does not contract, CHOICES),
    and the locking of fully integrated Q1 (its distance to the B-bar curve on the same
    mesh grows under refinement instead of shrinking)."""
    th, hs = prm.thetas[0], prm.h_levels
    bb = [runs[(2, "FE", th, h, "bbar")] for h in hs]
    d = [_curve_difference(bb[i + 1], bb[i]) for i in range(len(hs) - 1)]
    shrink = (None if len(d) < 2 or None in d else
              all(d[i + 1] < d[i] for i in range(len(d) - 1)))
    areas = [float(element_areas(r.fe)[plastic_zone(r.fe, r.fe.fields()["eps_p_norm_mean"],
                                                     prm.zone_tol)].sum()) for r in bb]
    claims = [Claim(
        "the ||dev sigma|| curve at X converges under mesh refinement (differences "
        "between successive meshes of h_levels shrink; not a rate: a second mesh family, "
        "measured beside, does not contract, see the notes)", shrink,
        "B-bar, successive meshes: " + ", ".join(map(_pct, d)) + "; plastic zone area "
        + ", ".join(f"h={h:g}: {a:.3f}" for h, a in zip(hs, areas)),
        kind="hypothesis", id="converges")]
    if prm.locking_study:
        full = [_curve_difference(r, runs[(2, "FE", th, h, "full")]) for r, h in zip(bb, hs)]
        grows = None if len(full) < 2 or None in full else all(
            b > a for a, b in zip(full, full[1:]))
        claims.append(Claim(
            "(beyond the thesis) fully integrated Q1 locks: its ||dev sigma|| curve at X "
            "departs further from the B-bar curve on the same mesh as h decreases",
            grows, "fully integrated Q1 vs B-bar on the same mesh: " + ", ".join(
                f"h={h:g}: {_pct(v)}" for h, v in zip(hs, full)) + "; B-bar between "
            "successive meshes: " + ", ".join(map(_pct, d)), kind="beyond", id="locking"))
    return claims


def _load_curve(run: Run, attr: str = "dev_sigma_X") -> np.ndarray:
    return np.array([getattr(r, attr) for r in run.records if r.phase == "load"])


def _all_hold(parts: list) -> bool | None:
    """True when every part holds, None when one is undecided, else False."""
    return None if any(p is None for p in parts) else bool(all(parts))


def bebe_curve_claim(prm: Params, runs: dict, bebe: dict) -> Claim:
    """BE/BE ||dev sigma|| at X (and the applied force) along the load path against
    FE/FE on the same mesh, FE/FE and FE/BE at h_figure: max relative differences, for
    every theta (``bebe`` from :func:`bebe_runs`)."""
    text = "the BE/BE curve shows qualitatively similar behaviour"
    if not bebe:
        return Claim(text, None, "BE/BE not run (bebe = false)", id="bebe")
    ok, ev = [], []
    force = lambda r: _load_curve(r, "force")                  # noqa: E731
    for th, pair in bebe.items():
        bb = pair["BE/BE"]
        if not bb.converged:
            ok.append(None)                   # undecided: no converged BE/BE curve
            ev.append(f"theta={th:g}: BE/BE did not converge: {bb.touches[0].reason}")
            continue
        refs = {f"FE/FE h={bb.h:g}": pair["FE/FE"],
                f"FE/FE h={prm.h_figure:g}": runs[(2, "FE", th, prm.h_figure, "bbar")],
                f"FE/BE h={prm.h_figure:g}": runs[(2, "BE", th, prm.h_figure, "bbar")]}
        ds = {k: _curve_difference(r, bb, _load_curve) for k, r in refs.items()}
        df = {k: _curve_difference(r, bb, force) for k, r in refs.items()}
        same = ds[f"FE/FE h={bb.h:g}"]
        ok.append(None if same is None else same <= prm.similar_tol)
        ev.append(f"theta={th:g}: max rel. difference of ||dev sigma|| at X, BE/BE vs " +
                  ", ".join(f"{k}: {_pct(v)}" for k, v in ds.items()) +
                  "; of the applied force: " + ", ".join(f"{k}: {_pct(v)}"
                                                         for k, v in df.items()))
    return Claim(f"{text} (max relative difference of ||dev sigma|| at X to FE/FE on the "
                 f"same mesh <= {prm.similar_tol:.0%}; theta = "
                 f"{', '.join(f'{t:g}' for t in bebe)}, h = {prm.bebe_h:g}; the finer FE "
                 f"curves show the mesh dependence of the value at X)", _all_hold(ok),
                 "; ".join(ev), id="bebe")


def _plastic_area(run: Run, zone_tol: float) -> float:
    """Area of the plastic zone at the peak of the first touch: BE/BE cells or FE
    elements with (mean) ||eps_p|| > zone_tol."""
    eps = run.touches[0].peak.fields["eps_p_norm"]
    areas = run.fe.cells.areas if run.stamp == "BE/BE" else element_areas(run.fe)
    return float(areas[eps > zone_tol].sum())


def _successive(prm: Params, study: dict, name: str) -> dict:
    """Successive differences of one discretisation over the meshes of ``study``: max
    relative difference of the ||dev sigma|| and force curves (relative to the finer
    mesh's peak), relative difference of the plastic zone area, and the same divided by
    log2(h_i / h_i+1) (per halving of h: the meshes are not refined by a constant ratio;
    a sequence converging at any positive order has shrinking scaled differences)."""
    hs, rs = list(study), [study[h][name] for h in study]
    area = [_plastic_area(r, prm.zone_tol) for r in rs]
    d = {"dev": [curve_difference(_load_curve(rs[i + 1]), _load_curve(rs[i]))
                 for i in range(len(hs) - 1)],
         "force": [curve_difference(_load_curve(rs[i + 1], "force"),
                                    _load_curve(rs[i], "force")) for i in range(len(hs) - 1)],
         "zone": [abs(area[i + 1] - area[i]) / max(area[i + 1], 1e-300)
                  for i in range(len(hs) - 1)]}
    per = [np.log2(hs[i] / hs[i + 1]) for i in range(len(hs) - 1)]
    return dict(raw=d, scaled={k: [v / q for v, q in zip(x, per)] for k, x in d.items()},
                area=area, peak_dev=[float(_load_curve(r)[-1]) for r in rs],
                peak_force=[float(_load_curve(r, "force")[-1]) for r in rs])


def _shrinks(x: list) -> bool:
    return all(b < a or b == 0 for a, b in zip(x, x[1:]))


def bebe_mesh_claim(prm: Params, runs: dict, study: dict) -> Claim:
    """Beyond the thesis: BE/BE under mesh refinement (bebe_h_levels, thetas[0]): the
    successive differences (per halving of h) of the ||dev sigma|| curve at X, of the
    applied force and of the plastic zone area shrink; beside them FE/FE on the same
    meshes, FE/FE on h_levels and BE/BE vs FE/FE on each mesh (``study`` from
    :func:`bebe_mesh_study`)."""
    hs = list(study) or list(prm.bebe_h_levels)
    text = ("(beyond the thesis) BE/BE converges under mesh refinement, h = "
            + ", ".join(f"{h:g}" for h in hs) + f", theta = {prm.thetas[0]:g}: the "
            "successive differences of ||dev sigma|| at X along the load path, of the "
            "applied force and of the plastic zone area, per halving of h (difference / "
            "log2(h_i / h_i+1)), shrink")
    if not study:
        return Claim(text, None, "BE/BE mesh study not run (bebe = false or fewer than "
                                 "two bebe_h_levels)", kind="beyond", id="bebe_study")
    bad = [f"{k} h={h:g}: {r.touches[-1].reason}" for h, p in study.items()
           for k, r in p.items() if not r.converged or r.touches[0].peak is None]
    if bad:
        return Claim(text, None, "did not converge: " + "; ".join(bad), kind="beyond",
                     id="bebe_study")
    bb, ff = _successive(prm, study, "BE/BE"), _successive(prm, study, "FE/FE")
    pct = lambda x: ", ".join(f"{v:.2%}" for v in x)            # noqa: E731
    num = lambda x: ", ".join(f"{v:.4g}" for v in x)            # noqa: E731
    ev = []
    for name, r in (("BE/BE", bb), ("FE/FE same meshes", ff)):
        ev.append(f"{name}: successive differences (raw / per halving) ||dev sigma|| at X "
                  f"{pct(r['raw']['dev'])} / {pct(r['scaled']['dev'])}, force "
                  f"{pct(r['raw']['force'])} / {pct(r['scaled']['force'])}, plastic zone "
                  f"area {pct(r['raw']['zone'])} / {pct(r['scaled']['zone'])}; at full "
                  f"lift ||dev sigma||_X {num(r['peak_dev'])}, force "
                  f"{num(r['peak_force'])}, zone area {num(r['area'])}")
    same = [(curve_difference(_load_curve(p["FE/FE"]), _load_curve(p["BE/BE"])),
             curve_difference(_load_curve(p["FE/FE"], "force"),
                              _load_curve(p["BE/BE"], "force"))) for p in study.values()]
    ev.append("BE/BE vs FE/FE on the same mesh (||dev sigma|| / force): " + ", ".join(
        f"h={h:g}: {a:.2%} / {b:.2%}" for h, (a, b) in zip(hs, same)))
    th, fh = prm.thetas[0], prm.h_levels
    fe = [runs[(2, "FE", th, h, "bbar")] for h in fh]
    ev.append("FE/FE on h_levels " + ", ".join(f"{h:g}" for h in fh) + ": successive "
              "||dev sigma|| differences " + ", ".join(
                  _pct(_curve_difference(fe[i + 1], fe[i])) for i in range(len(fh) - 1)))
    holds = None if len(hs) < 3 else bool(all(_shrinks(bb["scaled"][k])
                                              for k in ("dev", "force", "zone")))
    return Claim(text, holds, "; ".join(ev), kind="beyond", id="bebe_study")


def _bebe_vs_fe(bebe: dict):
    """BE/BE fields and top displacement against FE/FE on the same grid at the peak:
    (FE element areas, BE ||eps_p|| averaged over the cells in each FE element (area
    weights; every cell lies in one element), FE element mean ||eps_p||, BE top u_y,
    FE top u_y)."""
    be, fe = bebe["BE/BE"].fe, bebe["FE/FE"].fe
    el = np.array([fe.elements_at(c)[0] for c in be.cells.centroids])
    sb, sf = bebe["BE/BE"].touches[0].peak, bebe["FE/FE"].touches[0].peak
    w = np.bincount(el, be.cells.areas, minlength=fe.nel)
    eb = np.bincount(el, be.cells.areas * sb.fields["eps_p_norm"], minlength=fe.nel) / w
    ef = sf.fields["eps_p_norm"]
    nodes = be.cells.nodes
    top = np.flatnonzero(np.isclose(nodes[:, 1], WORK[3]))
    xf = fe.mesh.p[:, fe.elastic.boundary_vertices("top")]
    uf = fe.elastic.nodal_displacement(sf.u_work)[1, fe.elastic.boundary_vertices("top")]
    ufe = np.interp(nodes[top, 0], xf[0][np.argsort(xf[0])], uf[np.argsort(xf[0])])
    return w, eb, ef, sb.fields["node_u"][top, 1], ufe


def bebe_field_claims(prm: Params, bebe: dict) -> tuple[Claim, Claim]:
    """Deformed top surface and plastic strain of BE/BE against FE/FE on the same grid
    at full lift, for every theta (``bebe`` from :func:`bebe_runs`)."""
    t_mesh = (f"BE/BE deformed mesh qualitatively as FE/FE (top surface u_y at full lift "
              f"within {prm.similar_tol:.0%} of FE/FE on the same mesh)")
    t_eps = (f"BE/BE ||eps_p|| qualitatively as FE/FE (L2 difference and plastic zone "
             f"mismatch <= {prm.similar_tol:.0%} against FE/FE on the same mesh)")
    if not bebe:
        return (Claim(t_mesh, None, "BE/BE not run", id="bebe_mesh"),
                Claim(t_eps, None, "BE/BE not run", id="bebe_eps"))
    ok_u, ok_e, ev_u, ev_e = [], [], [], []
    for th, pair in bebe.items():
        bb, ff = pair["BE/BE"], pair["FE/FE"]
        if not (bb.converged and ff.converged):         # undecided: nothing to compare
            why = "; ".join(f"theta={th:g}: {k} failed: {r.touches[-1].reason}"
                            for k, r in pair.items() if not r.converged)
            ok_u.append(None), ok_e.append(None), ev_u.append(why), ev_e.append(why)
            continue
        w, eb, ef, ub, uf = _bebe_vs_fe(pair)
        du = float(np.abs(ub - uf).max() / np.abs(uf).max())
        l2 = float(np.sqrt(w @ (eb - ef) ** 2 / (w @ ef ** 2)))
        zb, zf = eb > prm.zone_tol, ef > prm.zone_tol
        mis = float(w[zb ^ zf].sum() / max(w[zb | zf].sum(), 1e-300))
        ok_u.append(du <= prm.similar_tol)
        ok_e.append(l2 <= prm.similar_tol and mis <= prm.similar_tol)
        ev_u.append(f"theta={th:g}, h = {bb.h:g}: max |u_y(BE/BE) - u_y(FE/FE)| / "
                    f"max |u_y(FE/FE)| on the top surface = {du:.2%}")
        ev_e.append(f"theta={th:g}, h = {bb.h:g}, element means: ||eps_p|| L2 difference "
                    f"{l2:.2%}, zone mismatch {mis:.2%}, max ||eps_p|| BE/BE {eb.max():.3e} "
                    f"vs FE/FE {ef.max():.3e}")
    return (Claim(t_mesh, _all_hold(ok_u), "; ".join(ev_u), id="bebe_mesh"),
            Claim(t_eps, _all_hold(ok_e), "; ".join(ev_e), id="bebe_eps"))


def bebe_exports(bebe: dict) -> dict:
    """The BE/BE work piece at full lift on its cell grid, for every theta: node
    displacement (representation formula) and the cell fields."""
    out = {}
    for th, pair in bebe.items():
        snap = pair["BE/BE"].touches[0].peak
        if snap is None:
            continue
        cx = pair["BE/BE"].fe.cells
        z = np.zeros((len(cx.nodes), 1))
        kind = "triangle" if cx.cells.shape[1] == 3 else "quad"
        cells = {k: [np.asarray(v, dtype=float)] for k, v in snap.fields.items()
                 if k != "node_u"}
        out[f"BEBE_theta{th:g}_touch1_work"] = meshio.Mesh(
            np.hstack([cx.nodes, z]), [(kind, np.asarray(cx.cells))],
            point_data={"u": np.hstack([snap.fields["node_u"], z])}, cell_data=cells)
    return out


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


# --------------------------------------------------------------------------- plots
def _polys(p: np.ndarray, cells: np.ndarray) -> np.ndarray:
    return p[cells]                                        # (ncells, nv, 2)


def _draw(ax, prm: Params, snap, fe, field: str | None, vmax: float):
    """Deformed (x magnification) work piece and stamp; cells coloured by ``field``."""
    mag = prm.magnification
    pw = fe.mesh.p.T + mag * fe.elastic.nodal_displacement(snap.u_work).T
    ps, us, cs = stamp_interior(snap.stamp, snap.u_stamp, *_grid(snap.stamp, prm))
    kw = dict(edgecolors="k", linewidths=0.2)
    if field is None:
        ax.add_collection(PolyCollection(_polys(pw, fe.mesh.t.T), facecolors="lightsteelblue",
                                         **kw))
        ax.add_collection(PolyCollection(_polys(ps + mag * us, cs), facecolors="wheat", **kw))
        pc = None
    else:
        pc = PolyCollection(_polys(pw, fe.mesh.t.T), array=snap.fields[field],
                            cmap="jet", **kw)
        pc.set_clim(0.0, vmax)
        ax.add_collection(pc)
        st = PolyCollection(_polys(ps + mag * us, cs), array=np.zeros(len(cs)), cmap="jet",
                            **kw)
        st.set_clim(0.0, vmax)
        ax.add_collection(st)
    _frame(ax, pw, ps + mag * us)
    return pc


def _frame(ax, *points):
    """Equal-aspect limits holding every deformed body (the magnified displacement moves
    the work piece's sides beyond its box) with a margin."""
    p = np.vstack(points)
    lo, hi = p.min(axis=0), p.max(axis=0)
    pad = 0.05 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")


def _grid(stamp, prm: Params):
    """Cells of the auxiliary FE-like grid of a BE stamp (mesh size h_figure)."""
    if hasattr(stamp, "mesh") and hasattr(stamp.mesh, "a"):
        lo, hi = stamp.mesh.a.min(axis=0), stamp.mesh.a.max(axis=0)
        return (max(1, int(round((hi[0] - lo[0]) / prm.h_figure))),
                max(1, int(round((hi[1] - lo[1]) / prm.h_figure))))
    return (0, 0)


def field_figure(prm: Params, run: Run, field: str | None, title: str) -> Figure:
    snaps = [t.peak for t in run.touches if t.peak is not None]
    fig = Figure(figsize=(5.0 * len(snaps), 3.9))
    axes = fig.subplots(1, len(snaps), squeeze=False)[0]
    vmax = max(float(s.fields["eps_p_norm"].max()) for s in snaps) if field else 0.0
    for ax, s in zip(axes, snaps):
        pc = _draw(ax, prm, s, run.fe, field, vmax or 1.0)
        ax.set_title(f"{title}, touch {s.touch} at full lift (x{prm.magnification:g})",
                     fontsize=9)
    if pc is not None:
        fig.colorbar(pc, ax=axes.tolist(), shrink=0.7, label="||eps_p||")
    return fig


def bebe_figure(prm: Params, bebe: dict, field: str | None, title: str) -> Figure:
    """BE/BE at full lift: the work piece's cell grid deformed by the displacement at its
    nodes (representation formula, x magnification), the BE stamp on its auxiliary grid;
    cells coloured by ``field``; ``bebe``: one theta's {"BE/BE": Run, "FE/FE": Run}."""
    snap = bebe["BE/BE"].touches[0].peak if bebe else None
    if snap is None:
        return missing_figure("BE/BE: no converged state (see the claims)")
    be, mag = bebe["BE/BE"].fe, prm.magnification
    fig = Figure(figsize=(5.5, 4.0))
    ax = fig.subplots()
    pw = be.cells.nodes + mag * snap.fields["node_u"]
    ps, us, cs = stamp_interior(snap.stamp, snap.u_stamp, *_grid(snap.stamp, prm))
    kw = dict(edgecolors="k", linewidths=0.2)
    if field is None:
        ax.add_collection(PolyCollection(pw[be.cells.cells], facecolors="lightsteelblue",
                                         **kw))
        ax.add_collection(PolyCollection(ps[cs] + mag * us[cs], facecolors="wheat", **kw))
    else:
        vals = snap.fields[field]
        pc = PolyCollection(pw[be.cells.cells], array=vals, cmap="jet", **kw)
        pc.set_clim(0.0, float(vals.max()) or 1.0)
        ax.add_collection(pc)
        ax.add_collection(PolyCollection(ps[cs] + mag * us[cs], facecolors="white", **kw))
        fig.colorbar(pc, ax=ax, shrink=0.7,
                     label="||" + field.removesuffix("_norm") + "||")
    _frame(ax, pw, ps + mag * us)
    ax.set_title(f"{title}, h = {bebe['BE/BE'].h:g}, full lift (x{mag:g})", fontsize=9)
    return fig


def curve_figure(prm: Params, runs: dict, example: int, bebe: dict | None = None,
                 study: dict | None = None) -> Figure:
    """||dev sigma|| at X against the applied force: FE/FE, FE/BE (and BE/BE) per theta;
    last panel: the FE/FE mesh study (B-bar, full Q1) and the BE/BE mesh study."""
    th0 = prm.thetas
    ncol = len(th0) + 1
    fig = Figure(figsize=(4.8 * ncol, 4.2))
    axes = fig.subplots(1, ncol)
    for ax, th in zip(axes, th0):
        for st, style, kw in (("FE", "-o", dict(ms=6, mfc="none")), ("BE", "--s",
                                                                      dict(ms=3))):
            r = runs[(example, st, th, prm.h_figure, "bbar")]
            start = (0.0, 0.0)
            for t in r.touches:
                load = [x for x in t.records if x.phase == "load"]
                ax.plot([start[0]] + [x.force for x in load],
                        [start[1]] + [x.dev_sigma_X for x in load], style, **kw,
                        label=f"FE/{st}, touch {t.records[0].touch}" if t.records else None)
                if t.records:
                    start = (t.records[-1].force, t.records[-1].dev_sigma_X)
        if bebe and th in bebe and bebe[th]["BE/BE"].records:
            r = bebe[th]["BE/BE"]
            ax.plot([0.0, *_load_curve(r, "force")], [0.0, *_load_curve(r)], ":^", ms=3,
                    label=f"BE/BE (h = {r.h:g})")
            f = bebe[th]["FE/FE"]
            ax.plot([0.0, *_load_curve(f, "force")], [0.0, *_load_curve(f)], "-", lw=0.8,
                    color="grey", label=f"FE/FE (h = {f.h:g}, same mesh as BE/BE)")
        ax.set_title(f"theta = {th:g}, h = {prm.h_figure:g}", fontsize=9)
        ax.set_xlabel("applied force (bottom reaction)")
        ax.set_ylabel(f"||dev sigma|| at X = {POINT[example]}")
        ax.legend(fontsize=7)
    ax = axes[-1]
    last = len(STAMPS[example])
    for i, h in enumerate(prm.h_levels):
        forms = ("bbar", "full") if example == 2 and prm.locking_study else ("bbar",)
        for form, style in zip(forms, ("-", ":")):
            recs = runs[(example, "FE", th0[0], h, form)].records
            start = [x for x in recs if x.touch == last - 1][-1:] or [None]
            load = [x for x in recs if x.touch == last and x.phase == "load"]
            f0, s0 = (0.0, 0.0) if start[0] is None else (start[0].force, start[0].dev_sigma_X)
            ax.plot([f0] + [x.force for x in load], [s0] + [x.dev_sigma_X for x in load],
                    style, color=f"C{i}",
                    label=f"FE/FE {'B-bar' if form == 'bbar' else 'full Q1'} h={h:g}")
    for i, (h, pair) in enumerate((study or {}).items()):
        r = pair["BE/BE"]
        if r.records:
            ax.plot([0.0, *_load_curve(r, "force")], [0.0, *_load_curve(r)], "-.^", ms=2,
                    color=f"C{len(prm.h_levels) + i}", label=f"BE/BE h={h:.3g}")
    ax.set_title(f"mesh study, theta = {th0[0]:g}, touch {last}", fontsize=9)
    ax.set_xlabel("applied force")
    ax.set_ylabel(f"||dev sigma|| at X = {POINT[example]}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def vtu_exports(prm: Params, run: Run, tag: str) -> dict:
    """Work piece (displacement, element fields ||eps_p||, ||dev sigma||, alpha) and stamp
    (displacement; a BE stamp on its auxiliary grid) at the peak of every touch."""
    out = {}
    for t in run.touches:
        if t.peak is None:
            continue
        s = t.peak
        wp = fe_vtu(run.fe.mesh, {"u": run.fe.elastic.nodal_displacement(s.u_work).T})
        wp.cell_data = {k: [np.asarray(v, dtype=float)] for k, v in s.fields.items()}
        out[f"{tag}_touch{s.touch}_work"] = wp
        pts, disp, cells = stamp_interior(s.stamp, s.u_stamp, *_grid(s.stamp, prm))
        z = np.zeros((len(pts), 1))
        out[f"{tag}_touch{s.touch}_stamp"] = meshio.Mesh(
            np.hstack([pts, z]), [("quad", np.asarray(cells))],
            point_data={"u": np.hstack([disp, z])})
    return out


def missing_figure(text: str) -> Figure:
    fig = Figure(figsize=(6, 2))
    ax = fig.subplots()
    ax.axis("off")
    ax.text(0.5, 0.5, text, ha="center", va="center", wrap=True, fontsize=9)
    return fig


# --------------------------------------------------------------------------- artefacts
def field_artefacts(prm, runs, example, ids, notes, meta) -> list[ArtefactResult]:
    """Deformed mesh and ||eps_p|| artefacts of FE/FE and FE/BE (ids in that order)."""
    th = prm.thetas[0]
    out = []
    summ = summary_table(prm, runs, example)
    for k, st in enumerate(("FE", "BE")):
        run = runs[(example, st, th, prm.h_figure, "bbar")]
        label = "FE/FE" if st == "FE" else "FE/BE"
        claims_mesh = [dent_claim(prm, run)]
        claims_eps = [zone_claim(prm, runs, example)] if st == "BE" else [Claim(
            "plastic deformation under every touch of the stamp", bool(
                all(t.peak is not None and t.peak.fields["eps_p_norm"].max() > prm.zone_tol
                    for t in run.touches)) if run.converged else None,
            "max ||eps_p|| at the peak of each touch: " + ", ".join(
                f"{t.peak.fields['eps_p_norm'].max():.3e}" for t in run.touches if t.peak)
            + ("" if run.converged else f"; not converged: {run.touches[-1].reason}"),
            id="plastic")]
        tab = summ[summ.coupling == label].reset_index(drop=True)
        out.append(ArtefactResult(ids[2 * k], tab, field_figure(prm, run, None,
                                  f"{label} deformed mesh"), claims=claims_mesh,
                                  notes=notes, meta=meta))
        out.append(ArtefactResult(ids[2 * k + 1], tab, field_figure(
            prm, run, "eps_p_norm", f"{label} ||eps_p||"), claims=claims_eps, notes=notes,
            meta=meta, exports=vtu_exports(prm, run, label.replace("/", ""))))
    return out


def _scene_notes(runs: dict, bb_runs: list) -> str:
    failed = [f"{k}: {t.reason}" for k, r in [*runs.items(), *bb_runs]
              for t in r.touches if not t.converged]
    return " ".join(CHOICES) + (" FAILED RUNS: " + "; ".join(failed) if failed else "")


def _scene_meta(runs: dict, bb_runs: list, t0: float) -> dict:
    """Timing and Newton statistics of one scene's runs (bb_runs: (label, Run) of BE/BE)."""
    its = [rec.iterations for r in runs.values() for rec in r.records]
    return dict(run_s=time.perf_counter() - t0, runs=len(runs),
                all_converged=all(r.converged for r in [*runs.values(),
                                                         *(r for _, r in bb_runs)]),
                newton_total=int(sum(its)), newton_max_per_increment=int(max(its)),
                newton_mean_per_increment=float(np.mean(its)))


def example1(prm: Params) -> list[ArtefactResult]:
    """Scene ex1: figures 4.1-4.5 (both touches, FE and BE stamps, every theta and h)."""
    t0 = time.perf_counter()
    runs = all_runs(prm, (1,))
    notes, meta = _scene_notes(runs, []), _scene_meta(runs, [], t0)
    fig5 = ArtefactResult("figure_4_5", curve_table(runs, 1), curve_figure(prm, runs, 1),
                          claims=[coupling_claim(prm, runs, 1)], notes=notes, meta=meta)
    return field_artefacts(prm, runs, 1, ARTEFACTS[0:4], notes, meta) + [fig5]


def example2(prm: Params) -> list[ArtefactResult]:
    """Scene ex2: figures 4.6-4.12 (FE/FE, FE/BE with the locking study, BE/BE and its
    mesh study)."""
    t0 = time.perf_counter()
    runs = all_runs(prm, (2,))
    bebe = bebe_runs(prm, runs)
    t_study = time.perf_counter()
    study = bebe_mesh_study(prm, runs, bebe)
    t_study = time.perf_counter() - t_study
    bb_runs = [(f"BE/BE theta={th:g}", pair["BE/BE"]) for th, pair in bebe.items()]
    st_runs = [(f"BE/BE study h={h:g}", p["BE/BE"]) for h, p in study.items()
               if h != prm.bebe_h]
    notes = _scene_notes(runs, bb_runs + st_runs)
    meta = dict(_scene_meta(runs, bb_runs + st_runs, t0),
                bebe_s=sum(r.wall_s for _, r in bb_runs) if bebe else None,
                bebe_s_per_theta={f"{r.theta:g}": r.wall_s for _, r in bb_runs},
                bebe_newton_per_increment="; ".join(
                    f"theta={r.theta:g}: " + " ".join(str(x.iterations) for x in r.records)
                    for _, r in bb_runs) if bebe else None)
    meta12 = dict(meta, bebe_study_s=t_study if study else None,
                  bebe_study_s_per_h={f"{h:g}": p["BE/BE"].wall_s for h, p in study.items()},
                  bebe_study_newton_per_increment="; ".join(
                      f"h={h:g}: " + " ".join(str(x.iterations) for x in p["BE/BE"].records)
                      for h, p in study.items()) if study else None)
    ex2 = field_artefacts(prm, runs, 2, ARTEFACTS[5:9], notes, meta)
    tab = bebe_table(bebe) if bebe else pd.DataFrame({"coupling": ["BE/BE"],
                                                      "computed": [False]})
    first = bebe.get(prm.thetas[0], {})
    c_mesh, c_eps = bebe_field_claims(prm, bebe)
    bb = [ArtefactResult("figure_4_10", tab, bebe_figure(prm, first, None,
                                                         "BE/BE deformed mesh"),
                         claims=[c_mesh], notes=notes, meta=meta),
          ArtefactResult("figure_4_11", tab, bebe_figure(prm, first, "eps_p_norm",
                                                         "BE/BE ||eps_p||"),
                         claims=[c_eps], notes=notes, meta=meta,
                         exports=bebe_exports(bebe))]
    c2 = pd.concat([curve_table(runs, 2), bebe_table(bebe)]).drop_duplicates(
        ignore_index=True) if bebe else curve_table(runs, 2)     # FE/FE bebe_h may be in both
    c2 = pd.concat([c2, bebe_table(study)]).drop_duplicates(ignore_index=True) \
        if study else c2                                  # BE/BE mesh study: new meshes only
    fig12 = ArtefactResult("figure_4_12", c2, curve_figure(prm, runs, 2, bebe, study),
                           claims=[coupling_claim(prm, runs, 2),
                                   bebe_curve_claim(prm, runs, bebe),
                                   *mesh_claims(prm, runs),
                                   bebe_mesh_claim(prm, runs, study)],
                           notes=notes, meta=meta12)
    return ex2 + bb + [fig12]


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """Figures 4.1-4.12 (config/quick.yaml sets the sizes); scenes: names of
    :data:`SCENES` to compute (None: all)."""
    prm = from_config(Params, config, scene="ch4_plasticity")
    scenes = tuple(SCENES) if scenes is None else tuple(scenes)
    unknown = sorted(set(scenes) - set(SCENES))
    if unknown:
        raise ValueError(f"unknown scenes {unknown}; ch4_plasticity has {list(SCENES)}")
    out = []
    for name, scene in (("ex1", example1), ("ex2", example2)):
        if name in scenes:
            t0 = time.perf_counter()
            res = scene(prm)
            for r in res:
                r.meta["scene_s"] = time.perf_counter() - t0
            out += res
    return out
