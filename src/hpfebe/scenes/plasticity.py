"""The two stamping examples of Section 4.2.7 (thesis lines 14810-14920, Figures
4.1-4.12) as scenes: the work piece, the stamp positions, the characteristic points X
and the runs of one example (all its touches with one stamp discretisation, hardening
theta and mesh size) on :func:`hpfebe.scenes.stamping.touch` / :func:`touch_be`.

Example 1: the stamp (slave, elastic) at [0.2, 1.2] x [-1, 1] for the first touch and at
[-1.8, -0.8] x [-1, 1] for the second, its top fixed; work piece (master,
elastoplastic) [-2, 2] x [-3, -1], its bottom lifted by 4.3e-3 in increments;
X = (-0.9, -1.1).  Example 2: one touch of the stamp [-1, 1] x [-1, 0], lift 4.2e-3;
X = (1, -1.1); BE/BE: the plastic BE work piece of Section 4.2.4 under a BE stamp.

The study of Figures 4.1-4.12 (:class:`StampingStudy`, the choices where the thesis is
silent in :data:`CHOICES`): every run of an example (:func:`all_runs`: FE and BE stamps,
every theta and mesh, fully integrated Q1 beside B-bar), the BE/BE runs of Example 2
(:func:`bebe_runs`) and their mesh study (:func:`bebe_mesh_study`), the rows of the
figures' tables.  The fields compared and drawn: :mod:`.plasticity_fields`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass

import numpy as np

from ..checks import array, choice, integer, real
from ..constitutive.j2 import J2Material
from ..contact import LU_ORDERINGS, ContactSettings
from .materials import E, H, NU, SIGMA_Y
from .stamping import (StampContact, be_work_piece, curve_difference, element_areas,
                       plastic_zone, stamp_body, touch, touch_be, work_piece)

WORK = (-2.0, 2.0, -3.0, -1.0)
STAMPS = {1: ((0.2, 1.2, -1.0, 1.0), (-1.8, -0.8, -1.0, 1.0)), 2: ((-1.0, 1.0, -1.0, 0.0),)}
POINT = {1: (-0.9, -1.1), 2: (1.0, -1.1)}

log = logging.getLogger(__name__)

#: the choices where the thesis is silent (the defaults of :class:`StampingStudy` and
#: what was measured to settle them); the notes of every artefact of Figures 4.1-4.12
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
    "states (at the first unloading increment, and after an increment that ended with "
    "the contact open: the work piece moved rigidly, the stamp at rest, no predictor "
    "while no point is in contact), or from TwoBodyContact's bonded predictor when that "
    "lowers ||R|| (tried in the first two increments of a touch only; the first step "
    "from it with the work piece's secant stiffness, secant_start: the algorithmic "
    "tangent at that elastic state is about H/(3 mu) soft along the flow direction); "
    "Armijo line search on ||R|| (an accepted step below 1 halved further "
    "while ||R|| decreases, ls_refine = 3 times at most; at most max_newton = 60 "
    "iterations), stop at ||R|| <= rtol x force scale + rtol x the reference "
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


def _each(items, desc=""):
    return items


@dataclass
class Run:
    """All touches of one example: the stamp discretisation ("FE", "BE" or "BE/BE"),
    theta, h, the work piece's formulation (or BE/BE cells), the work piece itself
    (its committed state after the last touch), the
    :class:`~hpfebe.scenes.stamping.TouchResult` of every touch and the wall time."""

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

    @property
    def iterations(self) -> list[int]:
        """Newton iterations of every converged increment."""
        return [r.iterations for r in self.records]

    def curve(self, touch_id=None) -> np.ndarray:
        """||dev sigma|| at X of every record (of touch ``touch_id``)."""
        return np.array([r.dev_sigma_X for r in self.records
                         if touch_id is None or r.touch == touch_id])

    def load_curve(self, attr: str = "dev_sigma_X") -> np.ndarray:
        """``attr`` of the loading records (the unloading ones left out)."""
        return np.array([getattr(r, attr) for r in self.records if r.phase == "load"])

    def branch(self, touch_id: int) -> tuple[np.ndarray, np.ndarray]:
        """The loading branch of touch ``touch_id`` in the (applied force, ||dev sigma||
        at X) plane of Figures 4.5, 4.12: the state it starts from (the end of the
        previous touch, the origin for the first) and its loading increments."""
        before = [r for r in self.records if r.touch == touch_id - 1][-1:]
        load = [r for r in self.records if r.touch == touch_id and r.phase == "load"]
        pts = [(r.force, r.dev_sigma_X) for r in before] or [(0.0, 0.0)]
        pts += [(r.force, r.dev_sigma_X) for r in load]
        return np.array([p[0] for p in pts]), np.array([p[1] for p in pts])


def run_difference(a: Run, b: Run, curve=None) -> float | None:
    """curve_difference of two runs' curves (``curve``: default all records of
    ||dev sigma|| at X), None unless both runs converged (their records differ in
    length otherwise)."""
    curve = curve or Run.curve
    return curve_difference(curve(a), curve(b)) if a.converged and b.converged else None


def successive_differences(runs: list) -> list[float | None]:
    """:func:`run_difference` of each run of a mesh sequence against the one before."""
    return [run_difference(b, a) for a, b in zip(runs, runs[1:])]


@dataclass(frozen=True)
class StampingScene:
    """The data of both examples: the material (E, nu, sigma_Y, H of Sections 4.2-4.4),
    penalty and friction (1/eps = factor x E, Coulomb mu_f), the Newton settings of a
    touch, the load path (n_load increments up, n_unload down; lifts ex1_u, ex2_u), the
    BE stamp's degree, the BE/BE cells and the sparse LU ordering."""

    E: float = E
    nu: float = NU
    sigma_Y: float = SIGMA_Y
    H: float = H
    mu_f: float = 0.2
    eps_n_factor: float = 10.0
    eps_t_factor: float = 5.0
    rtol: float = 1e-8
    max_newton: int = 60
    max_cuts: int = 4
    predictor: bool = True               # bonded predictor of TwoBodyContact per increment
    n_load: int = 10
    n_unload: int = 2
    ex1_u: float = 4.3e-3
    ex2_u: float = 4.2e-3
    be_degree: int = 1
    bebe_cells: str = "crossed"
    lu_ordering: str = "MMD_AT_PLUS_A"   # sparse LU ordering (ContactSettings)
    ls_refine: int = 3                   # line search refinement (ContactSettings)
    secant_start: bool = True            # secant first step from the predictor (ContactSettings)

    def __post_init__(self):
        choice("lu_ordering", self.lu_ordering, LU_ORDERINGS)
        choice("bebe_cells", self.bebe_cells, ("quad", "crossed"))
        for name in ("ex1_u", "ex2_u"):
            real(name, getattr(self, name), positive=True)
        integer("n_load", self.n_load, lo=1)
        integer("n_unload", self.n_unload, lo=0)
        integer("be_degree", self.be_degree, lo=1)
        # the material (every theta) and the contact settings are checked now, not at
        # the first run
        self.material(1.0)
        self.settings  # noqa: B018 (validates mu_f, the penalty and Newton settings)

    @property
    def settings(self) -> StampContact:
        """The penalty contact and Newton settings of every touch."""
        return StampContact(self.eps_n_factor, self.eps_t_factor, self.mu_f,
                            solver=ContactSettings(
                                rtol=self.rtol, max_iter=self.max_newton,
                                max_cuts=self.max_cuts, line_search=True,
                                predictor=self.predictor, lu_ordering=self.lu_ordering,
                                ls_refine=self.ls_refine,
                                secant_start=self.secant_start))

    def material(self, theta: float) -> J2Material:
        return J2Material(self.E, self.nu, self.sigma_Y, self.H, theta)

    def lift(self, example: int) -> float:
        return self.ex1_u if example == 1 else self.ex2_u

    def run_example(self, example: int, stamp: str, theta: float, h: float,
                    formulation: str = "bbar") -> Run:
        """All touches of one example with one stamp discretisation, theta and mesh
        size; a failed touch ends the run (with a warning)."""
        t0 = time.perf_counter()
        fe = work_piece(WORK, h, self.material(theta), formulation)
        touches, offset = [], None
        for k, box in enumerate(STAMPS[example], start=1):
            body = stamp_body(stamp, box, h, self.E, self.nu, p=self.be_degree)
            tr = touch(body, fe, self.lift(example), self.n_load, self.n_unload,
                       POINT[example], self.settings, offset=offset, touch_id=k)
            touches.append(tr)
            if not tr.converged:
                log.warning("example %d %s theta=%g h=%g: %s", example, stamp, theta, h,
                            tr.reason)
                break
            offset = tr.u_work
        return Run(example, stamp, theta, h, formulation, fe, touches,
                   time.perf_counter() - t0)

    def run_bebe(self, theta: float, h: float) -> Run:
        """Example 2 with the BE work piece (cells of size h) under a BE stamp
        (degree 1), loading only."""
        t0 = time.perf_counter()
        be = be_work_piece(WORK, h, self.material(theta), self.bebe_cells)
        body = stamp_body("BE", STAMPS[2][0], h, self.E, self.nu, p=1)
        tr = touch_be(body, be, self.ex2_u, self.n_load, POINT[2], self.settings)
        if not tr.converged:
            log.warning("BE/BE theta=%g h=%g: %s", theta, h, tr.reason)
        return Run(2, "BE/BE", theta, h, self.bebe_cells, be, [tr],
                   time.perf_counter() - t0)


@dataclass(frozen=True)
class StampingStudy(StampingScene):
    """The scene's data (:class:`StampingScene`: material, penalty, Newton, load path) and
    the studies of Figures 4.1-4.12: the hardening shares ``thetas``, the meshes
    ``h_levels`` (``h_figure`` drawn), the tolerances of the claims (``zone_tol``: plastic
    zone; ``close_tol``: curves very close; ``similar_tol``: fields similar), the
    locking study (fully integrated Q1), BE/BE on mesh ``bebe_h`` and its mesh study
    ``bebe_h_levels``."""

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
        for t in array("thetas", self.thetas, ndim=1, min_size=1):
            real("thetas entry", t, lo=0.0, hi=1.0)
        for h in array("h_levels", self.h_levels, ndim=1, min_size=1):
            real("h_levels entry (a mesh size)", h, positive=True)
        if self.h_figure not in self.h_levels:
            raise ValueError(f"h_figure must be one of h_levels {self.h_levels!r}, got "
                             f"{self.h_figure!r}")
        for name in ("magnification", "close_tol", "similar_tol", "bebe_h"):
            real(name, getattr(self, name), positive=True)
        real("zone_tol", self.zone_tol, nonnegative=True)
        hs = array("bebe_h_levels", self.bebe_h_levels, ndim=1)
        if np.any(hs <= 0) or np.any(np.diff(hs) >= 0):
            raise ValueError(f"bebe_h_levels must be positive and decreasing, got "
                             f"{self.bebe_h_levels!r}")


def all_runs(prm: StampingStudy, examples=(1, 2), progress=_each) -> dict:
    """{(example, stamp, theta, h, formulation): Run} of the given examples: FE and BE
    stamps, every theta and mesh of h_levels (B-bar); Example 2 also fully integrated
    Q1 at thetas[0] (locking study)."""
    jobs = [(ex, st, th, h, "bbar") for ex in examples for th in prm.thetas
            for st in ("FE", "BE") for h in prm.h_levels]
    if prm.locking_study and 2 in examples:
        jobs += [(2, "FE", prm.thetas[0], h, "full") for h in prm.h_levels]
    return {j: prm.run_example(*j) for j in progress(jobs, desc="stamping runs")}


def bebe_pair(prm: StampingStudy, th: float, h: float, runs: dict | None) -> dict:
    """BE/BE of Example 2 on mesh h and FE/FE on the same mesh (from ``runs`` if there)."""
    bb = prm.run_bebe(th, h)
    fefe = (runs or {}).get((2, "FE", th, h, "bbar")) or prm.run_example(2, "FE", th, h)
    return {"BE/BE": bb, "FE/FE": fefe}


def bebe_runs(prm: StampingStudy, runs: dict | None = None) -> dict:
    """Example 2 with the BE work piece under a BE stamp (mesh bebe_h), for every theta
    of 'thetas', and FE/FE on the same mesh as a same-resolution reference (taken from
    ``runs`` when bebe_h is one of h_levels): {theta: {"BE/BE": Run, "FE/FE": Run}}."""
    if not prm.bebe:
        return {}
    return {th: bebe_pair(prm, th, prm.bebe_h, runs) for th in prm.thetas}


def bebe_mesh_study(prm: StampingStudy, runs: dict, bebe: dict, progress=_each) -> dict:
    """Beyond the thesis: BE/BE (and FE/FE on the same meshes) of Example 2 on every mesh
    of bebe_h_levels, theta = thetas[0]; the bebe_h run of :func:`bebe_runs` is reused:
    {h: {"BE/BE": Run, "FE/FE": Run}} ({} when bebe is off or fewer than two levels)."""
    th, hs = prm.thetas[0], prm.bebe_h_levels
    if not prm.bebe or len(hs) < 2:
        return {}
    return {h: bebe[th] if h == prm.bebe_h and th in bebe else bebe_pair(prm, th, h, runs)
            for h in progress(hs, desc="BE/BE mesh study")}


@dataclass
class ExampleRuns:
    """Every run of one example (:func:`example_runs`): ``runs`` of :func:`all_runs`,
    Example 2's BE/BE pairs ``bebe`` and mesh study ``study`` ({} in Example 1), the
    artefacts' notes (:data:`CHOICES`, failed touches) and meta (wall time, Newton
    statistics; ``meta_study`` with the mesh study's)."""

    runs: dict
    bebe: dict
    study: dict
    notes: str
    meta: dict
    meta_study: dict


def example_runs(prm: StampingStudy, example: int, progress=_each) -> ExampleRuns:
    """Every run of ``example``: FE and BE stamps on every theta and mesh
    (:func:`all_runs`); in Example 2 also BE/BE (:func:`bebe_runs`) and its mesh study
    (:func:`bebe_mesh_study`)."""
    t0 = time.perf_counter()
    runs = all_runs(prm, (example,), progress)
    bebe = bebe_runs(prm, runs) if example == 2 else {}
    t1 = time.perf_counter()
    study = bebe_mesh_study(prm, runs, bebe, progress) if example == 2 else {}
    t_study = time.perf_counter() - t1
    others = bebe_labelled(prm, bebe, study)
    meta = dict(run_s=time.perf_counter() - t0, **run_statistics(runs, others))
    meta_study = meta
    if example == 2:
        stats, study_stats = bebe_statistics(bebe, study)
        meta.update(stats)
        meta_study = dict(meta, bebe_study_s=t_study if study else None, **study_stats)
    return ExampleRuns(runs, bebe, study, notes(runs, others), meta, meta_study)


# --------------------------------------------------------------------------- tables
def curve_rows(runs: dict, example: int) -> list[dict]:
    """The load records of every run of ``example`` (Figures 4.5, 4.12): one row per
    converged increment."""
    return [dict(example=ex, coupling=f"FE/{st}" if st == "BE" else "FE/FE", theta=th,
                 h=h, formulation=form, increment=k + 1, **asdict(rec))
            for (ex, st, th, h, form), r in runs.items() if ex == example
            for k, rec in enumerate(r.records)]


def summary_rows(prm: StampingStudy, runs: dict, example: int) -> list[dict]:
    """One row per run of ``example`` (Figures 4.1-4.4, 4.6-4.9): sizes, the fields'
    maxima after the last touch (||dev sigma|| at its peak), the plastic zone's area,
    Newton statistics and the wall time."""
    rows = []
    for (ex, st, th, h, form), r in runs.items():
        if ex != example:
            continue
        f = r.touches[-1].peak.fields if r.touches[-1].peak else r.fe.fields()
        its = r.iterations
        rows.append(dict(example=ex, coupling="FE/BE" if st == "BE" else "FE/FE",
                         theta=th, h=h, formulation=form, dof_work=r.fe.ndofs,
                         converged=r.converged,
                         eps_p_max=float(r.fe.fields()["eps_p_norm_mean"].max()),
                         dev_sigma_max_peak=float(f["dev_sigma_norm"].max()),
                         plastic_area=plastic_area(r, prm.zone_tol),
                         newton_total=int(sum(its)), newton_max=int(max(its, default=0)),
                         newton_mean=float(np.mean(its)) if its else float("nan"),
                         newton_per_increment=" ".join(map(str, its)),
                         wall_time_s=r.wall_s))
    return rows


def bebe_rows(bebe: dict) -> list[dict]:
    """Load records of BE/BE and its same-mesh FE/FE reference, every theta."""
    return [dict(example=2, coupling=name, theta=r.theta, h=r.h, formulation=r.formulation,
                 increment=k + 1, **asdict(rec))
            for pair in bebe.values() for name, r in pair.items()
            for k, rec in enumerate(r.records)]


def plastic_area(run: Run, zone_tol: float) -> float:
    """Area of the FE work piece's plastic zone after the last touch: the elements with
    mean ||eps_p|| > zone_tol."""
    zone = plastic_zone(run.fe, run.fe.fields()["eps_p_norm_mean"], zone_tol)
    return float(element_areas(run.fe)[zone].sum())


def bebe_labelled(prm: StampingStudy, bebe: dict, study: dict) -> list[tuple[str, Run]]:
    """The BE/BE runs by label: every theta of ``bebe``, the other meshes of ``study``."""
    return [(f"BE/BE theta={th:g}", p["BE/BE"]) for th, p in bebe.items()] + [
        (f"BE/BE study h={h:g}", p["BE/BE"]) for h, p in study.items() if h != prm.bebe_h]


def run_statistics(runs: dict, others=()) -> dict:
    """The runs of a scene in numbers: how many, whether they and the labelled runs
    ``others`` (BE/BE, :func:`bebe_labelled`) all converged, Newton iterations per
    increment of ``runs`` (total, max, mean)."""
    its = [i for r in runs.values() for i in r.iterations]
    every = [*runs.values(), *(r for _, r in others)]
    return dict(runs=len(runs), all_converged=all(r.converged for r in every),
                newton_total=int(sum(its)), newton_max_per_increment=int(max(its)),
                newton_mean_per_increment=float(np.mean(its)))


def bebe_statistics(bebe: dict, study: dict) -> tuple[dict, dict]:
    """Wall times and Newton iterations per increment of the BE/BE runs (per theta) and
    of the BE/BE mesh study (per h)."""
    def its(runs):
        return "; ".join(f"{k}: " + " ".join(map(str, r.iterations)) for k, r in runs)

    bb = [(f"theta={th:g}", p["BE/BE"]) for th, p in bebe.items()]
    st = [(f"h={h:g}", p["BE/BE"]) for h, p in study.items()]
    return (dict(bebe_s=sum(r.wall_s for _, r in bb) if bebe else None,
                 bebe_s_per_theta={f"{th:g}": p["BE/BE"].wall_s for th, p in bebe.items()},
                 bebe_newton_per_increment=its(bb) if bebe else None),
            dict(bebe_study_s_per_h={f"{h:g}": p["BE/BE"].wall_s for h, p in study.items()},
                 bebe_study_newton_per_increment=its(st) if study else None))


def notes(runs: dict, others=()) -> str:
    """:data:`CHOICES` and the touches that failed (``others``: labelled BE/BE runs)."""
    failed = [f"{k}: {t.reason}" for k, r in [*runs.items(), *others]
              for t in r.touches if not t.converged]
    return " ".join(CHOICES) + (" FAILED RUNS: " + "; ".join(failed) if failed else "")
