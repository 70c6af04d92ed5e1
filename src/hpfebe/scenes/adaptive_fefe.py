"""The FE/FE frictional contact scene of Section 4.2.8 (thesis lines 14920-15080,
Figures 4.13-4.16): slave Omega_s = [-1/2, 1/2] x [0, 2] with its top fixed (u_s = 0),
master Omega_m = [-2, 2] x [-2, 0] with its bottom displaced by u_m = (0, 5e-4) (read as
upward, both components prescribed), all other boundary parts possible contact (in
practice the slave's bottom meets the master's top; the slave's sides and the rest of the
master's top stay open), E = 266926, nu = 0.29, Coulomb mu_f = 0.1; P1 triangles in both
bodies, penalty contact by :class:`hpfebe.contact.TwoBodyContact` (Algorithm 4.1).

The features where the refinement should concentrate: the contact segment and the
corners where the boundary conditions change (:func:`feature_distance`).

The study of Figures 4.13-4.16 (:class:`AdaptiveStudy`; the choices where the thesis is
silent: :data:`CHOICES`): the adaptive and the uniform refinement loops
(:func:`refinement_run`, :func:`adaptive_and_uniform`) with the indicator (3.100) of
each body, the concentration of the refinement at the features
(:func:`concentration_rows`, :func:`feature_concentration`, :func:`wider_radius`), the
displacement ranges and the VTU meshes of the last step.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..adaptivity import adapt, two_body_indicators
from ..analysis import fitted_rate
from ..checks import array, choice, instance, integer, real
from ..constitutive import PLANES
from ..contact import LINEAR_SOLVERS, ContactSettings, TwoBodyContact
from ..fem import (ElasticBody, cell_diameter, distance_to_set, is_conforming,
                   local_mesh_size, new_vertices, rectangle_mesh, refine_labelled,
                   refinement_concentration)
from ..io import fe_vtu
from .materials import FrictionalContactScene

BODIES = ("slave", "master")
BOX = {"slave": (-0.5, 0.5, 0.0, 2.0), "master": (-2.0, 2.0, -2.0, 0.0)}
#: possible contact boundary of each body (TwoBodyContact), the part that meets the
#: other body (contact datum of (3.100)) and the open, traction free rest
CONTACT_BOUNDARY = {"slave": ["bottom", "left", "right"], "master": ["top", "left", "right"]}
CONTACT = ("bottom", "top")
OPEN = (("left", "right"), ("left", "right"))
#: features of the concentration claims: the contact segment and the corners where the
#: boundary conditions change
CONTACT_SEGMENT = ((-0.5, 0.0), (0.5, 0.0))
FEATURE_POINTS = {
    "slave": [(-0.5, 0.0), (0.5, 0.0), (-0.5, 2.0), (0.5, 2.0)],
    "master": [(-0.5, 0.0), (0.5, 0.0), (-2.0, -2.0), (2.0, -2.0)],
}

#: the choices where the thesis is silent (the defaults of :class:`AdaptiveStudy` and the
#: readings of the claims); the notes of every artefact of Figures 4.13-4.16
CHOICES = (
    "Initial meshes: uniform triangulations with h = 1/4 (slave 4 x 8 cells, master 16 x 8 "
    "cells, each split into 2 triangles), config slave_cells, master_cells; with h = 1/2 "
    "the semismooth Newton cycles between two stick/slip states in the first load step.",
    "Load applied in load_steps = 5 equal increments; should Newton fail (max_iter) in an "
    "increment, it is halved and retried from the last converged state (at most "
    "load_retries cuts; the iteration counts in the tables show how many increments were "
    "used). No cure for the h = 1/2 cycle: the first load step starts from U = 0 and the "
    "penalty laws are positively homogeneous, so its Newton sequence does not depend on "
    "the size of the increment.",
    "Penalty parameters fixed over the refinement (so that all meshes approximate one "
    "penalised problem): 1/eps_n = 10 E, 1/eps_t = 5 E (within the range of Table 4.3, "
    "whose 1/eps_t is half of 1/eps_n).",
    "Plane strain (Coulomb friction is path dependent, hence increments); Newton tolerance "
    "||R|| <= 1e-10 max(||F||, ||R_0||).",
    "Newton systems (linear_solver = 'woodbury'): the stiffness of each body is "
    "factorised once per mesh and the contact terms of the active points enter by the "
    "Sherman-Morrison-Woodbury formula (hpfebe.contact.woodbury.WoodburySolver; each "
    "body by PARDISO's Cholesky with partial solves on the contact dofs where pypardiso "
    "is installed, else by SuperLU); the same Newton steps as a sparse LU of every "
    "Newton matrix ('lu') up to round-off, with the same iteration counts: a trial "
    "traction on the Coulomb bound to rounding slips (hpfebe.constitutive.laws), so the "
    "points that slipped in the last load step (their slip just committed) do not take "
    "a stick/slip state by rounding in the first iterate of the next (before: 931 "
    "Newton iterations, counts differing by up to 5 per refinement step between 'lu' "
    "and 'woodbury'; now 383, equal, the load steps after the first in one iteration; "
    "the same converged states, indicators, marked elements and meshes).",
    "The contact datum of (3.100) on Gamma_C ('P_n n + P_t t'): the discrete penalty "
    "traction at the slave contact points (p_n n_m - t_t t_m), interpolated linearly in x "
    "along the slave's bottom and evaluated at the facet quadrature points; the master's "
    "top carries its negative at the projections (x, 0) and zero traction outside "
    "|x| <= 1/2; the other non-Dirichlet sides are traction free (open contact boundary).",
    "The indicator of a body is (sum_K eta_K^2)^(1/2) over that body, plotted against the "
    "body's own DOF (2 x vertices, Dirichlet dofs included).",
    "Uniform reference: every triangle red-refined in both bodies, at least "
    "min_uniform_steps times and until each body's DOF exceeds that of the last adaptive "
    "step (at most max_uniform_steps).",
    "'Adaptive beats uniform at equal DOF': the uniform indicator is interpolated "
    "(log-log, piecewise linear) at the DOF of the last adaptive step of the same body.",
    "'Refinement concentrates at the contact zone and where boundary conditions change': "
    "features = the contact segment [-1/2, 1/2] x {0} (whose ends are the contact / no "
    "contact points), the no contact / Dirichlet corners (+-1/2, 2) of the slave and "
    "(+-2, -2) of the master. Two claims: 'concentrates' holds if in each body the "
    "density of the vertices added by the adaptive refinement within feature_radius = 1/4 "
    "of the features is at least enrichment = 2 times their mean density and every "
    "feature point is refined to a local h <= h0 / 8; 'most of the refinement happens "
    "there' (the thesis's words) holds if at least half of the new vertices of each body "
    "lie in that neighbourhood. The thresholds were fixed after a first look at the "
    "meshes; the table gives the shares after every shown step, so other readings can be "
    "checked.",
)


def _each(items, desc=""):
    return items


@dataclass(frozen=True)
class FEFEContactScene(FrictionalContactScene):
    """The scene's data: the master's bottom lifted by (0, u_master), penalty
    1/eps_n = eps_n_factor E, 1/eps_t = eps_t_factor E, initial meshes of slave_cells and
    master_cells rectangles (2 triangles each; h0 = 1/4)."""

    u_master: float = 5.0e-4              # master bottom lifted (0, u_master)
    eps_n_factor: float = 10.0            # 1/eps_n = eps_n_factor E
    eps_t_factor: float = 5.0             # 1/eps_t = eps_t_factor E
    slave_cells: tuple[int, ...] = (4, 8)       # h0 = 1/4, 2 triangles per cell
    master_cells: tuple[int, ...] = (16, 8)

    def __post_init__(self):
        choice("plane", self.plane, PLANES)
        for name in ("slave_cells", "master_cells"):
            v = array(name, getattr(self, name), shape=(2,), dtype=int)
            if v.min() < 1:
                raise ValueError(f"{name} must be two positive cell counts, got "
                                 f"{getattr(self, name)!r}")
        for name in ("E", "u_master", "eps_n_factor", "eps_t_factor"):
            real(name, getattr(self, name), positive=True)
        real("nu", self.nu, lo=-1.0, hi=0.5, lo_open=True, hi_open=True)
        real("mu_f", self.mu_f, nonnegative=True)

    def initial_meshes(self) -> tuple:
        """Labelled triangulations ("left", "right", "bottom", "top") of both
        rectangles."""
        return tuple(rectangle_mesh(*BOX[b], *cells, kind="tri")
                     for b, cells in zip(BODIES, (self.slave_cells, self.master_cells)))

    def solve(self, meshes, load_steps: int, settings: ContactSettings):
        """The two-body problem on the meshes (slave, master), the lift applied in
        ``load_steps`` equal increments: (problem, result)."""
        n = integer("load_steps", load_steps, lo=1)
        instance("settings", settings, ContactSettings)
        # P1 stiffness in closed form (scikit-fem's quadrature matrix to round-off)
        S, M = (ElasticBody(m, self.E, self.nu, self.plane, assembly="closed_form")
                for m in meshes)
        pr = TwoBodyContact(S, M, CONTACT_BOUNDARY["slave"], CONTACT_BOUNDARY["master"],
                            eps_n=1.0 / (self.eps_n_factor * self.E),
                            eps_t=1.0 / (self.eps_t_factor * self.E), mu_f=self.mu_f)
        fixed, is_y = pr.stamp_dofs()
        res = pr.solve(None, fixed, self.u_master * is_y,
                       load_factors=np.arange(1, n + 1) / n, settings=settings)
        return pr, res


def feature_distance(body: str):
    """Distance to the features of ``body`` (contact segment and corner points)."""
    return lambda p: distance_to_set(p, [CONTACT_SEGMENT], FEATURE_POINTS[body])


@dataclass(frozen=True)
class AdaptiveStudy(FEFEContactScene):
    """The scene's data and the study of Figures 4.13-4.16: ``n_refinements`` adaptive
    steps (Algorithm 3.2, maximum strategy ``theta``), the Newton settings of each solve
    (``load_steps`` increments, at most ``load_retries`` cuts, ``rtol``, ``max_newton``,
    ``linear_solver``), the uniform reference (``min_uniform_steps`` ..
    ``max_uniform_steps``), the steps drawn (``mesh_steps``) and the readings of the
    concentration claims (``feature_radius``, ``concentration_share``, ``enrichment``,
    ``feature_h_ratio``; :data:`CHOICES`)."""

    n_refinements: int = 42
    theta: float = 0.9
    load_steps: int = 5
    load_retries: int = 2                 # at most this many cuts of a failed increment
    rtol: float = 1e-10
    max_newton: int = 30
    max_uniform_steps: int = 5
    min_uniform_steps: int = 2
    mesh_steps: tuple[int, ...] = (0, 5, 10, 21, 36, 42)
    feature_radius: float = 0.25
    concentration_share: float = 0.5
    enrichment: float = 2.0
    feature_h_ratio: float = 0.125
    linear_solver: str = "woodbury"       # Newton systems (TwoBodyContact.solve)

    def __post_init__(self):
        super().__post_init__()
        for name in ("n_refinements", "load_steps", "max_newton", "max_uniform_steps"):
            integer(name, getattr(self, name), lo=1)
        for name in ("load_retries", "min_uniform_steps"):
            integer(name, getattr(self, name), lo=0)
        for name in ("rtol", "feature_radius", "enrichment", "feature_h_ratio"):
            real(name, getattr(self, name), positive=True)
        real("theta", self.theta, lo=0.0, hi=1.0, lo_open=True)
        real("concentration_share", self.concentration_share, lo=0.0, hi=1.0)
        for k in array("mesh_steps", self.mesh_steps, ndim=1, dtype=int):
            integer("mesh_steps entry (a refinement step)", k, lo=0)
        choice("linear_solver", self.linear_solver, LINEAR_SOLVERS)

    @property
    def settings(self) -> ContactSettings:
        """The Newton settings of every solve."""
        return ContactSettings(rtol=self.rtol, max_iter=self.max_newton,
                               max_cuts=self.load_retries, linear_solver=self.linear_solver)

    def shown_steps(self, n_meshes: int) -> list[int]:
        """The steps of ``mesh_steps`` that were computed, and the last one."""
        steps = [k for k in self.mesh_steps if k < n_meshes]
        return steps if n_meshes - 1 in steps else steps + [n_meshes - 1]


# --------------------------------------------------------------------------- the runs
def _solver_columns(pr, res) -> dict:
    its, states = res.iterations, res.state_names
    return dict(dof=pr.ndofs, newton_per_load_step=" ".join(str(i) for i in its),
                newton_total=int(sum(its)), newton_max=int(max(its)),
                newton_converged=bool(res.converged), n_stick=states.count("stick"),
                n_slip=states.count("slip"), n_open=states.count("open"))


def refinement_run(prm: AdaptiveStudy, mode: str, n_steps: int, stop=None,
                   progress=_each):
    """Solve, estimate (3.100) and refine both bodies ``n_steps`` times (``mode``
    "adaptive": maximum strategy per body, Algorithm 3.2; "uniform": everything), each
    body by its own indicator (:func:`hpfebe.adaptivity.two_body_indicators`) and
    marking, conforming red-green-blue refinement keeping the boundary labels.  Returns
    the rows (one per solved mesh pair: solver, sizes, indicators, marked cells, times)
    and the :class:`~hpfebe.adaptivity.AdaptiveHistory`."""
    choice("mode", mode, ("adaptive", "uniform"))
    solver = []

    def solve(meshes):
        pr, res = prm.solve(meshes, prm.load_steps, prm.settings)
        if not res.converged:
            raise RuntimeError(f"{mode} step {len(solver)}: Newton failed: {res.reason}")
        solver.append(_solver_columns(pr, res))
        return (pr, res), (pr.slave.ndofs, pr.master.ndofs)

    def estimate(meshes, state):
        return two_body_indicators(*state, contact=CONTACT, free=OPEN)

    hist = adapt(prm.initial_meshes(), solve, estimate, n_steps + 1, theta=prm.theta,
                 marking="max" if mode == "adaptive" else "uniform", refine=refine_labelled,
                 stop=stop, progress=lambda it: progress(it, desc=f"{mode} refinement"))
    rows = []
    for rec, sol, meshes in zip(hist.records, solver, hist.meshes):
        row = dict(mode=mode, step=rec["step"], **sol)
        for i, b in enumerate(BODIES):
            row.update({f"dof_{b}": rec["ndof"][i], f"elements_{b}": rec["n_elements"][i],
                        f"eta_{b}": rec["eta"][i],
                        f"h_min_{b}": float(cell_diameter(meshes[i]).min()),
                        # cells marked by the maximum strategy (none in the uniform run)
                        f"marked_{b}": rec["n_marked"][i] if mode == "adaptive" else 0})
        rows.append(dict(row, t_solve_s=rec["t_solve"], t_estimate_s=rec["t_estimate"]))
    return rows, hist


def adaptive_and_uniform(prm: AdaptiveStudy, progress=_each):
    """The adaptive run (``n_refinements`` steps) and the uniform reference: at least
    ``min_uniform_steps`` red refinements and until each body's DOF exceeds that of the
    last adaptive step (at most ``max_uniform_steps``).  Returns (rows, history) of the
    adaptive and of the uniform run and their meta (wall times, convergence, final
    DOF)."""
    t0 = time.perf_counter()
    ad, ad_hist = refinement_run(prm, "adaptive", prm.n_refinements, progress=progress)
    t1 = time.perf_counter()
    target = (int(ad[-1]["dof_slave"]), int(ad[-1]["dof_master"]))
    un, un_hist = refinement_run(
        prm, "uniform", prm.max_uniform_steps, progress=progress,
        stop=lambda rec: (rec["step"] >= prm.min_uniform_steps and
                          all(d > t for d, t in zip(rec["ndof"], target))))
    t2 = time.perf_counter()
    meta = dict(run_s=t2 - t0, adaptive_s=t1 - t0, uniform_s=t2 - t1,
                n_refinements=prm.n_refinements,
                newton_all_converged=all(r["newton_converged"] for r in ad + un),
                final_dof_slave=target[0], final_dof_master=target[1])
    return (ad, ad_hist), (un, un_hist), meta


def observed_rates(ad: list, un: list, body: str) -> tuple[float, float]:
    """Fitted slopes of log eta against log DOF of ``body`` (the rows of
    :func:`refinement_run`): adaptive over its last third (at least 3 steps), uniform
    over its last 3 meshes (NaN with fewer than 2 meshes)."""
    def rate(rows, last):
        dof, eta = [r[f"dof_{body}"] for r in rows], [r[f"eta_{body}"] for r in rows]
        return fitted_rate(dof, eta, last=last) if len(dof) >= 2 else math.nan

    return rate(ad, max(3, len(ad) // 3)), rate(un, 3)


# --------------------------------------------------------------------------- analysis
def concentration_rows(prm: AdaptiveStudy, hist, steps: list) -> list[dict]:
    """Figure 4.13's table: per shown step of the adaptive run ``hist`` the sizes and the
    share of the vertices added since the initial meshes within feature_radius of the
    features; conformity against the initial meshes."""
    rows, meshes = [], hist.meshes
    for k in steps:
        ndof = hist.records[k]["ndof"]
        row = dict(step=k, elements_slave=meshes[k][0].t.shape[1],
                   elements_master=meshes[k][1].t.shape[1],
                   dof_slave=int(ndof[0]), dof_master=int(ndof[1]),
                   h_min_slave=float(cell_diameter(meshes[k][0]).min()),
                   h_min_master=float(cell_diameter(meshes[k][1]).min()))
        for b, body in enumerate(BODIES):
            sh = (refinement_concentration(meshes[0][b], meshes[k][b],
                                           feature_distance(body), prm.feature_radius).share
                  if k else 0.0)
            row[f"new_near_features_{body}"] = 0.0 if math.isnan(sh) else sh
        row["conforming"] = all(is_conforming(meshes[k][b], meshes[0][b]) for b in (0, 1))
        rows.append(row)
    return rows


def feature_concentration(prm: AdaptiveStudy, meshes: list) -> dict:
    """Per body, the refinement from the first to the last of ``meshes`` near the
    features: {body: (Concentration within feature_radius, local h at the feature
    points, initial h0)}."""
    out = {}
    for b, body in enumerate(BODIES):
        c = refinement_concentration(meshes[0][b], meshes[-1][b], feature_distance(body),
                                     prm.feature_radius)
        local = local_mesh_size(meshes[-1][b], FEATURE_POINTS[body])
        out[body] = (c, local, float(cell_diameter(meshes[0][b]).max()))
    return out


def wider_radius(prm: AdaptiveStudy, meshes: list) -> dict:
    """Per body, r_half = the radius within which concentration_share of the new
    vertices lie and the Concentration within it: {body: (r_half, Concentration)}, None
    for a body without new vertices."""
    out = {}
    for b, body in enumerate(BODIES):
        new = new_vertices(meshes[0][b], meshes[-1][b])
        if not new.any():
            out[body] = None
            continue
        d = feature_distance(body)(meshes[-1][b].p[:, new])
        r_half = float(np.quantile(d, prm.concentration_share, method="higher"))
        out[body] = (r_half, refinement_concentration(meshes[0][b], meshes[-1][b],
                                                      feature_distance(body), r_half))
    return out


def notes(prm: AdaptiveStudy, ad: list, un: list) -> str:
    """The notes shared by the four artefacts of Figures 4.13-4.16: the method, the
    measured summary of the adaptive and uniform rows ``ad``, ``un``, :data:`CHOICES`."""
    a0, a1, u1 = ad[0], ad[-1], un[-1]
    return (
        f"FE/FE penalty contact, P1 triangles, 1/eps_n = {prm.eps_n_factor} E, 1/eps_t = "
        f"{prm.eps_t_factor} E (fixed over the refinement), mu_f = {prm.mu_f}, plane "
        f"{prm.plane}, {prm.load_steps} load increments, Newton rtol {prm.rtol}. Initial "
        f"meshes h = 1/4 (slave {list(prm.slave_cells)} cells, master "
        f"{list(prm.master_cells)} cells, 2 triangles each). Marking eta_K >= {prm.theta} "
        "max eta_K per body, conforming red-green-blue refinement (scikit-fem "
        "MeshTri.refined, boundary labels inherited), bodies refined independently. "
        f"Measured: final DOF slave {int(a1['dof_slave'])} / master "
        f"{int(a1['dof_master'])}; indicator slave {a0['eta_slave']:.4g} -> "
        f"{a1['eta_slave']:.4g}, master {a0['eta_master']:.4g} -> {a1['eta_master']:.4g} "
        f"(uniform: {u1['eta_slave']:.4g} / {u1['eta_master']:.4g} at DOF "
        f"{int(u1['dof_slave'])} / {int(u1['dof_master'])}). Choices where the thesis is "
        "silent: " + " ".join(CHOICES) + (f" Only {prm.n_refinements} adaptive refinement "
                                          "steps (thesis: 42)." if prm.n_refinements < 42
                                          else ""))


def displacement_rows(pr, res) -> list[dict]:
    """Figure 4.16's table: per body its DOF and the range of u_x and u_y."""
    rows = []
    for body, b, u in zip(BODIES, (pr.slave, pr.master), (res.u_slave, res.u_master)):
        un = b.nodal_displacement(u)
        rows.append(dict(body=body, dof=b.ndofs, ux_min=float(un[0].min()),
                         ux_max=float(un[0].max()), uy_min=float(un[1].min()),
                         uy_max=float(un[1].max())))
    return rows


def vtu_meshes(tag: str, pr, res, etas) -> dict:
    """{f"{tag}_{body}": meshio.Mesh} of both bodies with the displacement and the
    indicator (max over the elements at each vertex)."""
    out = {}
    for name, body, u, eta in zip(BODIES, (pr.slave, pr.master),
                                  (res.u_slave, res.u_master), etas):
        ev = np.zeros(body.mesh.p.shape[1])
        for i in range(3):
            np.maximum.at(ev, body.mesh.t[i], eta)
        out[f"{tag}_{name}"] = fe_vtu(body.mesh, {
            "displacement": body.nodal_displacement(u).T, "eta_max_adjacent": ev})
    return out
