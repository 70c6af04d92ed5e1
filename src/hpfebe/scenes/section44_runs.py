"""The runs of Section 4.4 (thesis lines 20355-20720) on the scene
:mod:`hpfebe.scenes.section44` and the numbers read off them.

* Penalty (Table 4.3, Figure 4.22): :func:`run_penalty` - Algorithm 4.1 (incremental
  loading, Newton with the consistent tangents (4.36)-(4.43)) on the FE/BE scene
  :func:`~hpfebe.scenes.section44.penalty_scene`, a :class:`PenaltyRun`;
  :func:`penalty_row` - its row of Table 4.3 (Newton iterations over the increments,
  ||([u_n] - g)_+||_L2(Gamma_C)); :func:`penetration_slope` - the scaling with eps_n.
* Mortar (Table 4.2, Figure 4.21): :func:`mortar_scene` (the FE mortar problem, stamp
  condensed once), :func:`dtn_run` (Algorithm 4.3 with the readings of its stopping
  rule, step 7), :func:`dtn_row` (one cell of Table 4.2), :func:`reading_counts`
  (the count of every reading), :func:`tangential_bound` (the lower bound that step 6
  puts on the printed rule), :func:`tolerance_scan` (the counts at other relative
  tolerances), :func:`mortar_variants` (the mortar solution per sensitivity variant).
* :data:`CHOICES` (penalty), :data:`MORTAR_CHOICES` (mortar): the choices where the
  thesis is silent, as the results' notes state them.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from ..contact import NeumannSettings
from .section44 import (READINGS, X_POINT, DtNReadings, Section44Scene, dtn_settings,
                        penalty_bodies, penalty_scene, penetration_l2, section44_scene,
                        sensitivity_variants, tangential_share)
from .stamping import touch

log = logging.getLogger(__name__)

__all__ = ["CHOICES", "MORTAR_CHOICES", "PenaltyRun", "bound_count", "dtn_row", "dtn_run",
           "first_below", "mortar_scene", "mortar_variants", "penalty_row",
           "penetration_slope", "reading_counts", "run_penalty", "tangential_bound",
           "tangential_contraction", "tangential_shares", "tolerance_scan"]

CHOICES = (
    "Meshes: uniform; work piece the mortar part's 61 x 31 Q1 cells (penalty_mesh = 'mortar'; "
    "62 x 32 = 1984 nodes: the thesis's 'DOF = 51 + 1984' counts nodes, as its mortar 'DOF = "
    "231 + 1984' - the same work piece in both methods, so the comparison of Figures 4.21/4.22 "
    "is on the same points), plain bilinear elements (penalty_formulation = 'full', the "
    "thesis's 'continuous piecewise bilinear basis functions' in both methods). Measured "
    "alternatives (Table 4.3 penetration at 20, 10, 5, 2.5 E, single pass): 61 x 31 full "
    "1.554e-6, 3.041e-6, 5.931e-6, 1.141e-5 (slope 0.96); 61 x 31 B-bar 1.510e-6 ... 1.128e-5; "
    "the former default 44 x 22 B-bar (h_work = 1/11) 1.828e-6 ... 1.131e-5 (slope 0.88); "
    "Newton iterations within 2 of each other; 1.7-2.1 s per run on 61 x 31 against 1.1-1.8 s "
    "on 44 x 22. BE stamp h_stamp = 0.1: 60 P1 nodes on the boundary, of which 51 lie off the "
    "interior of the fixed top, the thesis's 'DOF = 51' read as a node count like the mortar "
    "part's 231 = 11 x 21 (h_stamp = 0.25, 24 nodes, changes the penetration norms by 7 % or "
    "less).",
    "Plane strain with the full 3 x 3 stress; ||dev sigma|| is the Frobenius norm of the "
    "3 x 3 deviator (element means), whose yield value sqrt(2/3) sigma_Y = 3.266 lies just "
    "under the printed maximum 3.302 (hardening H = 450): the thesis plots this norm.",
    "Hardening isotropic (theta = 1; not stated in Section 4.4).",
    "Load path (Algorithm 4.1; the number of increments is not given): the bottom lift "
    "1e-4 in n_load equal increments, no unloading; 'Newton iterations' = total over the "
    "increments. Newton: Armijo line search, stop at ||R|| <= rtol x force scale + rtol "
    "sigma_Y width (stamping.touch), a failed increment halved at most max_cuts times. "
    "rtol = 1e-8, stricter than the thesis's TOL_N = 1e-4 (whose norm it does not define; "
    "measured with rtol = 1e-4: 14, 12, 11, 10 iterations, same penetration to 4 digits). "
    "Each increment starts from the secant extrapolation of the last two states, exact "
    "while the response is linear: such an increment needs 0 iterations.",
    "Contact treatment (two_pass = true): two passes (TwoBodyContact(two_pass=True)): "
    "the stamp's bottom is the slave against the work piece's top, and the work piece's "
    "top the slave against the stamp's bottom, each pass with 1/eps_n, 1/eps_t. Section "
    "4.4 makes the remaining boundary parts of both bodies contact boundaries (Gamma^s_C "
    "and Gamma^m_C) and names no master; Section 4.2's Algorithm 4.1 is written for one "
    "master-slave pass. The printed norms decide it: a single pass gives about twice "
    "them, and no single pass can print them with the force that the stamp's "
    "compression needs (Cauchy-Schwarz bound; passes claim, where the single-pass sweep "
    "runs as well, compare_passes). On this flat interface the two passes integrate the "
    "same points, so the two-pass problem is the single pass at eps/2 (TwoBodyContact "
    "doc). Penetration: ||(-g_n)_+||_L2(Gamma_C) with the first pass's quadrature (the "
    "stamp's bottom; Gamma_C counted once) at full lift; its scaling with eps_n is the "
    "least-squares slope of log penetration against log eps_n. The h_work_fine sweep "
    "(uniform 88 x 44, h = 1/22, same formulation) checks the mesh (slope claim; single "
    "pass measured within 0.6 % of 61 x 31 in every cell): the work piece mesh does not "
    "decide the norms.",
    "Figure 4.22 shows the run with 1/eps_n = figure_factor x E_m (the thesis does not say "
    "which); the BE stamp's interior displacement by the representation formula on a grid "
    "of cell size h_stamp/2. u_x, u_y colour ranges are nodal min/max.",
)

MORTAR_CHOICES = (
    "Mortar meshes: uniform Q1, stamp 10 x 20 cells (11 x 21 = 231 nodes) and work piece "
    "61 x 31 cells (62 x 32 = 1984 nodes): the thesis's 'DOF = 231 + 1984' counts nodes "
    "(the stamp's 231 = 11 x 21 is odd, so no count of vector dofs; its penalty 'DOF = "
    "51' is the 51 nodes of the stamp's non-Dirichlet boundary at h = 0.1). 1984 nodes "
    "on the 4 x 2 rectangle: 62 x 32 (cells 0.0656 x 0.0645, the nearest to square) or "
    "64 x 31 (0.0635 x 0.0667); we take 62 x 32.",
    "Work piece Q1 fully integrated ('full', the plain Q1 of the thesis) in the mortar "
    "runs, and so in the penalty runs; with B-bar the DtN converges on fewer damping "
    "pairs on this mesh (measured: (0.5, 0.7), (0.7, 0.5) end in divergence), and the "
    "colorbar ranges of both figures move by at most 6 % of the published spans, 'full' "
    "as near to the thesis as B-bar or nearer in all 8 u ranges (largest deviation of "
    "either end; formulation claim of figure_4_21).",
    "Gamma_C: the stamp's bottom (mortar side, Gauss-Lobatto = nodal constraints, lumped "
    "friction weights) against the work piece's top; the other free sides face nothing "
    "(traction free). Mortar projection (4.87) with test space X^1_h (D^-1 B).",
    "Step 2: one backward-Euler step from the virgin history (the DtN iterates are no load "
    "increments; nothing is committed), Newton with the consistent tangent and a line "
    "search, warm-started from the previous DtN iterate (the first from the elastic "
    "solution), ||R||_inf <= newton_tol x (force scale + sigma_Y h). newton_tol = 1e-8: "
    "with the thesis's TOL_N = 1e-4 in this norm the DtN increments stagnate at ~4e-5 "
    "and TOL_DtN = 1e-6 is never reached.",
    "Step 4: Uzawa with the absolute step rho = 8.264e5 (lambda += rho F (U_t - Q_t)) and "
    "Polyak's projected CG; lambda and the QP warm-started from the previous DtN "
    "iteration. DtN stop: ||P_k+1 - P_k||_2 <= TOL_DtN ||P_k+1||_2; 'converged' also "
    "needs ||Q_n - (pi U2)_n||_inf <= coupling_tol ||(pi U2)_n||_inf (a P that stops "
    "changing because the stamp lost contact is no solution); no convergence = increment "
    "growth by 1e6, a failed Newton/Uzawa solve (Newton capped at newton_max_iter = 15 "
    "iterations; the converged runs need at most 8 per DtN iteration, measured on the "
    "table's mesh), or max_dtn = 50 iterations (the converged runs need at most 41).",
    "Figure 4.21: the DtN solution at omega_D = 0.5, omega_N = 0.7 (the thesis's values); "
    "plastic region = elements with ||eps_p|| > 0. Mortar-penalty differences on common "
    "points: the penalty work piece's nodes (displacements) and element centroids "
    "(||dev sigma||, element means) - the mortar's own nodes and cells, the work piece "
    "mesh and formulation being the same in both methods (a mortar field is "
    "interpolated bilinearly only for the variant on another mesh) - and the penalty "
    "stamp's grid (BE representation formula against the FE stamp interpolated); "
    "relative difference ||a - b||_2 / ||a||_2 and max|a - b| / max|a| per body and "
    "component, a = mortar (rows quantity = mortar_vs_penalty of figure_4_21.csv, column "
    "variant; NaN there in the colorbar columns, and NaN published_min for ||dev sigma||, "
    "whose minimum is not compared).",
    "The split of the difference (variants, figure_4_21.csv): the thesis's comparison "
    "mixes the friction laws (Tresca F = 0.22 against Coulomb mu_f = 0.2, its own "
    "setup); 'frictionless' (F = 0 and mu_f = 0) isolates the method, 'friction_mortar' / "
    "'friction_penalty' show how far each friction law moves its own solution, eps_<f> "
    "the penalty parameter, penalty_bbar* the work piece formulation and mesh; "
    "'tresca_matched*' the penalty run with the mortar's Tresca F in the penalty law "
    "(stamping.ContactSettings F; penalty_law = 'tresca') at figure_factor and at the "
    "stiffest penalty: the friction law matched, the method's difference alone - the "
    "friction-matched comparison claim is checked at the stiffest penalty (the mortar "
    "enforces non-penetration exactly, the penalty solution tends to it as eps_n -> 0), "
    "the figure_factor run reported beside it.",
    "DtN stopping rule (step 7, thesis line ~19330): 'stop if ||P^k - P^k-1|| <= TOL_DtN "
    "||P^k-1||' - the quantity is the transferred traction P, relative to the previous "
    "iterate, the norm not named (the coefficient vector's l2 norm taken). The run stops "
    "by fixed_point's rule (relative to the new P^k): the thresholds differ by a factor "
    "1 + O(TOL_DtN), and the counts of both readings are equal in every converged cell "
    "(columns its_P_l2_prev, its_P_l2_new); the other readings (max-norm, L2(Gamma_C), "
    "the first iterate, the displacement U2 in l2 / max / energy norm / on Gamma_C) are "
    "recorded for comparison only (notes table below, readings claim).",
)


# --------------------------------------------------------------------------- penalty
@dataclass
class PenaltyRun:
    """One lift of the work piece against the BE stamp at 1/eps_n = factor E: the work
    piece (fe), the touch's :class:`~hpfebe.scenes.stamping.TouchResult` and the wall
    time."""

    factor: float
    fe: object
    result: object          # TouchResult
    wall_s: float

    @property
    def peak(self):
        return self.result.peak

    @property
    def penetration_l2(self) -> float:
        return penetration_l2(self.peak.result)

    def bodies(self, h_stamp: float) -> dict:
        """Nodal points, cells and displacement of both bodies at full lift
        (:func:`~hpfebe.scenes.section44.penalty_bodies`: the BE stamp's interior by the
        representation formula on a grid of cell size h_stamp / 2): computed once per
        grid and kept on the run - Figure 4.22, the comparison and its variants ask for
        the same run's fields."""
        cache = self.__dict__.setdefault("_bodies", {})
        if h_stamp not in cache:
            cache[h_stamp] = penalty_bodies(self.fe, self.peak, h_stamp)
        return cache[h_stamp]


def run_penalty(prm: Section44Scene, factor: float) -> PenaltyRun:
    """The lift of the work piece against the BE stamp with 1/eps_n = factor x E."""
    t0 = time.perf_counter()
    stamp, fe = penalty_scene(prm.penalty_cells, prm.h_stamp, prm.material(),
                              prm.penalty_formulation, prm.be_degree)
    tr = touch(stamp, fe, prm.lift, prm.n_load, 0, X_POINT, prm.settings(factor))
    if not tr.converged:
        log.warning("1/eps_n = %g E: %s", factor, tr.reason)
    return PenaltyRun(factor, fe, tr, time.perf_counter() - t0)


def penalty_row(prm: Section44Scene, r: PenaltyRun) -> dict:
    """The row of Table 4.3 of the run ``r``: Newton iterations (total over the
    increments, and per increment), the penetration norm, dofs, max ||dev sigma||, the
    contact force, the wall time (NaN columns where the run failed)."""
    its = [rec.iterations for rec in r.result.records]
    ok = r.result.converged and r.peak is not None
    nan = float("nan")
    return dict(
        inv_eps_n_over_E=r.factor, inv_eps_t_over_E=prm.eps_t_ratio * r.factor,
        newton_iterations=int(sum(its)), penetration_l2=r.penetration_l2 if ok else nan,
        converged=bool(ok), n_increments=len(its),
        newton_per_increment=" ".join(map(str, its)),
        dof_be=int(r.peak.u_stamp.size) if ok else 0, dof_fe=int(r.fe.ndofs),
        max_dev_sigma=float(r.peak.fields["dev_sigma_norm"].max()) if ok else nan,
        contact_force=r.peak.result.total_forces()[0] if ok else nan, wall_time_s=r.wall_s)


def penetration_slope(factors, penetration, converged) -> float:
    """Least-squares slope of log penetration against log eps_n = -log(1/eps_n) over
    the converged runs (NaN with fewer than two)."""
    ok = np.asarray(converged, dtype=bool)
    if ok.sum() < 2:
        return float("nan")
    f, p = np.asarray(factors, dtype=float)[ok], np.asarray(penetration, dtype=float)[ok]
    return float(np.polyfit(-np.log(f), np.log(p), 1)[0])


# --------------------------------------------------------------------------- mortar
def mortar_scene(q: Section44Scene, formulation: str | None = None):
    """The mortar contact problem of ``q`` (stamp condensed once, reused by every DtN
    run); ``formulation``: the work piece's, replacing ``q.mortar_formulation``."""
    return section44_scene(q.stamp_cells, q.work_cells, q.E, q.nu, q.sigma_Y, q.H,
                           q.theta, q.F, q.lift, formulation or q.mortar_formulation)


def dtn_run(pr, prm: Section44Scene, wD: float, wN: float, F: float | None = None):
    """Algorithm 4.3 on the mortar problem ``pr`` at the damping pair (wD, wN) with the
    tolerances of ``prm`` (``F``: a friction bound replacing the scene's, e.g. 0:
    frictionless); the readings of its stopping rule
    (:class:`~hpfebe.scenes.section44.DtNReadings`) in ``extra["readings"]``."""
    readings = DtNReadings(pr)
    settings = dtn_settings(wD, wN, prm.tol_dtn, prm.max_dtn, prm.tol_uzawa, prm.max_uzawa,
                            prm.rho)
    sol = pr.dtn(settings, NeumannSettings(prm.newton_tol, prm.newton_max_iter),
                 prm.coupling_tol, F, readings)
    sol.extra["readings"] = readings.values
    return sol


def first_below(increments, tol: float) -> float:
    """The first DtN iteration (1-based) whose recorded relative increment is <= tol
    (NaN if none is)."""
    k = np.flatnonzero(np.asarray(increments, dtype=float) <= tol)
    return float(k[0] + 1) if k.size else np.nan


def reading_counts(prm: Section44Scene, sol) -> dict:
    """Per reading of the stopping rule (:data:`~hpfebe.scenes.section44.READINGS`) the
    first DtN iteration whose relative increment is <= tol_dtn (``its_<reading>``; NaN
    if the run did not converge or the reading was not met before the run stopped - it
    stops by the fixed_point rule, reading P_l2_new), and the tail contraction rate
    (geometric mean of the last 5 ratios of successive P increments)."""
    ok = sol.info.converged
    rd = sol.extra.get("readings", {})
    out = {f"its_{name}": first_below(rd.get(name, []), prm.tol_dtn) if ok else np.nan
           for name in READINGS}
    inc = np.asarray(rd.get("P_l2_new", []), dtype=float)[-6:]
    out["tail_rate"] = float(np.exp(np.mean(np.log(inc[1:] / inc[:-1])))) if ok and \
        inc.size >= 3 and np.all(inc > 0) else np.nan
    return out


def dtn_row(prm: Section44Scene, pr, wD: float, wN: float):
    """One cell of Table 4.2: Algorithm 4.3 at (wD, wN) on ``pr``; returns (row, the
    solution).  The row: DtN iterations and the Uzawa iterations of the first DtN
    iteration (NaN: no convergence, ``reason``), the count at alt_tol_dtn, the largest
    Uzawa count after the first iteration, Newton iterations in all, the coupling error,
    max ||dev sigma||, the wall time and :func:`reading_counts`."""
    t0 = time.perf_counter()
    sol = dtn_run(pr, prm, float(wD), float(wN))
    wall = time.perf_counter() - t0
    info = sol.info
    ok = info.converged
    later = [st.counts.get("uzawa", 0) for st in info.steps[1:]]
    return dict(
        omega_D=float(wD), omega_N=float(wN),
        dtn_iterations=float(info.iterations) if ok else np.nan,
        uzawa_iterations_first_dtn=float(info.counts["uzawa_first"]) if ok else np.nan,
        converged=ok, reason=info.reason, dtn_steps_run=info.iterations,
        dtn_iterations_alt_tol=first_below(info.counts["relative_increments"],
                                           prm.alt_tol_dtn) if ok else np.nan,
        uzawa_first_run=info.counts["uzawa_first"], uzawa_max_later=int(max(later, default=0)),
        newton_total=info.counts["newton_total"], coupling_error=info.backward_error,
        max_dev_sigma=float(sol.extra["fields"]["dev_sigma_norm_mean"].max()) if ok
        else np.nan, wall_time_s=wall, **reading_counts(prm, sol)), sol


def tolerance_scan(sols: list, tols) -> list[np.ndarray]:
    """Per relative tolerance of ``tols`` the DtN counts of the runs ``sols`` stopped
    there (their recorded relative increments of P; NaN where never met)."""
    return [np.array([first_below(s.info.counts["relative_increments"], t) for s in sols])
            for t in tols]


# --------------------------------------------------------------------------- step 6 bound
def tangential_contraction(sol, wN: float) -> float:
    """Largest |a_k+1 / a_k - (1 - omega_N)| of the absolute tangential increments
    a_k = ||(P^k - P^k-1)_t|| from the second DtN iteration on (while a_k is above
    round-off: the increments are differences of P, so a_k > 1e-9 ||P^k-1||)."""
    t = np.asarray(sol.extra["readings"]["P_t_l2_prev"], dtype=float)[1:]
    a = (t * np.asarray(sol.info.counts["P_norms"], dtype=float)[: t.size])[t > 1e-9]
    return float(np.abs(a[1:] / a[:-1] - (1.0 - wN)).max()) if a.size > 2 else np.nan


def bound_count(share: float, wN: float, tol: float) -> int:
    """The lower bound of the printed rule from a solution's tangential share
    ``share`` = ||T|| / ||P|| alone: the first DtN iteration k >= 2 whose tangential
    increment omega_N (1 - omega_N)^(k-1) ||T|| is <= tol ||P|| (k < 100000; 2 if
    none is).  The first 200 candidates first: the same numbers, the whole range only
    when none of them is met (Table 4.2's claims ask 40 times)."""
    for k in (np.arange(2, 200), np.arange(2, 100_000)):
        met = wN * (1.0 - wN) ** (k - 1) * share <= tol
        if met.any():
            return int(k[np.argmax(met)])
    return 2


def tangential_bound(sol, n_thesis: int, bound: float) -> tuple[bool, float]:
    """(the thesis's count ``n_thesis`` lies below the run's bound ``bound`` - the
    first iteration whose tangential increment alone is <= TOL_DtN ||P^k-1||, NaN:
    beyond the run -, the tangential increment at n_thesis relative to ||P^k-1||)."""
    t = np.asarray(sol.extra["readings"]["P_t_l2_prev"], dtype=float)
    over = t[int(n_thesis) - 1] if int(n_thesis) <= t.size else np.nan
    return not n_thesis >= bound, over


def tangential_shares(prm: Section44Scene, pr) -> dict:
    """||T|| / ||P|| (the tangential part of the transferred traction P against P) of
    the monolithic solution per mortar sensitivity variant (:func:`sensitivity_variants`
    whose meshes differ from each other; None where it failed); ``pr``: the problem of
    ``prm`` itself."""
    out, seen = {}, set()
    for name, q in sensitivity_variants(prm).items():
        cells = (q.stamp_cells, q.work_cells)
        if cells in seen:
            continue
        seen.add(cells)
        sc = pr if cells == (prm.stamp_cells, prm.work_cells) else mortar_scene(q)
        mono = sc.monolithic()
        out[name] = tangential_share(sc, mono) if mono.info.converged else None
    return out


def mortar_variants(prm: Section44Scene, pr, sol, variants: dict) -> dict:
    """(scene, solution) of the mortar problem per sensitivity variant: the figure's
    DtN solution where the variant leaves the mortar problem as it is (the table, load
    steps), else the monolithic solution of the changed scene (the same discrete
    problem as the DtN's: table_4_2's monolithic claim); solution None if it failed."""
    out = {}
    for name, q in variants.items():
        if (q.stamp_cells, q.work_cells) == (prm.stamp_cells, prm.work_cells):
            out[name] = (pr, sol)
            continue
        sc = mortar_scene(q)
        mono = sc.monolithic()
        if not mono.info.converged:
            log.warning("sensitivity variant %s (mortar): %s", name, mono.info.reason)
        out[name] = (sc, mono if mono.info.converged else None)
    return out
