"""The scene of Section 4.4 (thesis lines 20355-20720): mortar against penalty for
frictional contact between an elastic stamp and an elastoplastic work piece.

Elastic Omega_s = [-1/2, 1/2] x [0, 2] (:data:`STAMP`, top fixed) on the J2
elastoplastic (4.21)-(4.22) Omega_m = [-2, 2] x [-2, 0] (:data:`WORK`) whose bottom is
lifted by 1e-4; E = 266926, nu = 0.29, sigma_Y = 4.0, H = 450.0
(:mod:`hpfebe.scenes.materials`), plane strain.

* :func:`section44_scene` - the mortar problem (Table 4.2, Figure 4.21): Q1 in both
  bodies, Tresca friction F = 0.22 on the stamp's bottom,
  :class:`hpfebe.contact.mortar_fe.FEMortarContact`; :func:`dtn_settings` - Algorithm
  4.3 as the section runs it (rho = 8.264e5, TOL_DtN = TOL_U = 1e-6).
* :func:`penalty_scene` - the penalty problem (Table 4.3, Figure 4.22): a Galerkin BE
  stamp on a Q1 work piece, one touch of :func:`hpfebe.scenes.stamping.touch`.
* :data:`READINGS`, :class:`DtNReadings` - the readings of Table 4.2's stopping rule
  (Algorithm 4.3, step 7), recorded per DtN iteration by a hook of
  :meth:`FEMortarContact.dtn`.
* :func:`mortar_bodies`, :func:`penalty_bodies`, :func:`field_differences` - both
  bodies' fields of either solution and their relative differences on common points
  (the comparison of Figures 4.21 and 4.22).
* :class:`Section44Scene` - the parameters of both methods (config section
  ``ch4_section44``), the published colour bars of Figures 4.21, 4.22 (:data:`PUB_UX`,
  ...), and the sensitivity variants every explanation must survive
  (:func:`sensitivity_variants`, :data:`VARIANT_TEXT`).  The runs:
  :mod:`hpfebe.scenes.section44_runs`; the fields compared and exported:
  :mod:`.section44_fields`; the readings of Tables 4.2, 4.3 and of the figures' colour
  bars: :mod:`.section44_readings`, :mod:`.section44_figures`.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..checks import array, choice, integer, real
from ..constitutive.j2 import J2Material
from ..contact import ContactSettings
from ..contact.mortar_fe import FEMortarContact
from ..solvers import DtNSettings, UzawaSettings
from ..fem.elasticity import ElasticBody, rectangle_mesh
from ..fem.plastic_body import ElastoPlasticFE
from .materials import E, H, NU, SIGMA_Y
from .stamping import StampContact, stamp_body, stamp_interior

#: the stamp Omega_s and the work piece Omega_m, (x0, x1, y0, y1)
STAMP = (-0.5, 0.5, 0.0, 2.0)
WORK = (-2.0, 2.0, -2.0, 0.0)
#: the characteristic point X of the penalty runs' records (in the work piece)
X_POINT = (0.0, -0.1)


def section44_scene(stamp_cells=(10, 20), work_cells=(61, 31), E: float = E,
                    nu: float = NU, sigma_Y: float = SIGMA_Y, H: float = H,
                    theta: float = 1.0, F: float = 0.22, lift: float = 1e-4,
                    formulation: str = "bbar") -> FEMortarContact:
    """The mortar scene of Section 4.4: Q1 stamp [-1/2, 1/2] x [0, 2] (``stamp_cells`` =
    (nx, ny)), top fixed, on the J2 (sigma_Y, hardening H, isotropic share theta) Q1
    work piece [-2, 2] x [-2, 0] (``work_cells``) whose bottom is displaced by
    (0, ``lift``); plane strain, Tresca friction F on the stamp's bottom."""
    for name, cells in (("stamp_cells", stamp_cells), ("work_cells", work_cells)):
        k = array(name, cells, shape=(2,), dtype=int)
        if np.any(k < 1):
            raise ValueError(f"{name} must be two positive integers, got {cells!r}")
    lift = real("lift", lift)
    stamp = ElasticBody(rectangle_mesh(*STAMP, *map(int, stamp_cells)), E, nu)
    work = ElastoPlasticFE(rectangle_mesh(*WORK, *map(int, work_cells)),
                           J2Material(E, nu, sigma_Y, H, theta), formulation)
    return FEMortarContact(stamp, work, ("top", (0.0, 0.0)), ("bottom", (0.0, lift)), F)


def dtn_settings(omega_D: float, omega_N: float, tol: float = 1e-6, max_iter: int = 200,
                 tol_U: float = 1e-6, max_uzawa: int = 2000, rho: float = 8.264e5,
                 divergence: float = 1e6) -> DtNSettings:
    """Algorithm 4.3 as Section 4.4 runs it on :func:`section44_scene`: damping omega_D,
    omega_N, TOL_DtN = ``tol``, step 6 as printed ((1 - omega_N) P + omega_N B^T D^-T
    R1), step 4 by Uzawa (Algorithm 4.4) with the absolute step rho = 8.264e5 and
    TOL_U = ``tol_U``."""
    return DtNSettings(omega_D, omega_N, tol, max_iter, divergence, relaxation="convex",
                       uzawa=UzawaSettings(rho, tol_U, max_uzawa, relative=False))


def penalty_scene(work_cells, h_stamp: float, material: J2Material,
                  formulation: str = "full", be_degree: int = 1):
    """The penalty scene of Section 4.4 (FE/BE): the Galerkin BE stamp on :data:`STAMP`
    (P1 for ``be_degree`` 1, mesh size ``h_stamp``) and the Q1 work piece on
    :data:`WORK` (``work_cells`` = (nx, ny), ``formulation`` "full" or "bbar").
    Returns (stamp, work piece) for :func:`hpfebe.scenes.stamping.touch`: fresh copies
    of one pair built per arguments (:func:`_penalty_template`), since a touch changes
    the work piece's state."""
    cells = tuple(int(c) for c in array("work_cells", work_cells, shape=(2,), dtype=int))
    return copy.deepcopy(_penalty_template(cells, real("h_stamp", h_stamp, positive=True),
                                           material, formulation, int(be_degree)))


@functools.lru_cache(maxsize=8)
def _penalty_template(work_cells: tuple, h_stamp: float, material: J2Material,
                      formulation: str, be_degree: int):
    """The pristine (stamp, work piece) of :func:`penalty_scene`, the work piece's
    element lookup at :data:`X_POINT` (the touch's records) done: Table 4.3, the figures
    and their variants run up to 19 touches on a few meshes, and a copy costs a fifth of
    the assembly (the B operators, the elastic tangent's pattern) and lookup (measured
    0.014 s against 0.09 s on 61 x 31 cells)."""
    fe = ElastoPlasticFE(rectangle_mesh(*WORK, *work_cells), material, formulation)
    fe.elements_at(X_POINT)
    stamp = stamp_body("BE", STAMP, h_stamp, material.E, material.nu, p=be_degree)
    return stamp, fe


def penetration_l2(c) -> float:
    """||(-g_n)_+||_L2(Gamma_C) of a penalty ContactResult ``c`` with its slave
    quadrature (the first pass's points: Gamma_C counted once also with two passes)."""
    w = c.weights if c.passes is None else c.weights * (c.passes == 0)
    return float(np.sqrt(w @ np.asarray(np.maximum(-c.g_n, 0.0)) ** 2))


# --------------------------------------------------------------------------- parameters
# Figure 4.22 colorbars (report/published/scalars.csv): work piece first, then stamp
PUB_UX = {"work": (-0.9184e-5, 0.9184e-5), "stamp": (-0.8495e-5, 0.8495e-5)}
PUB_UY = {"work": (0.5293e-4, 0.9600e-4), "stamp": (-0.5079e-7, 0.5893e-4)}
PUB_DEV_MAX = 3.302
# Figure 4.21 colorbars (report/published/scalars.csv): work piece first, then stamp
PUB_MORTAR_UX = {"work": (-0.8262e-5, 0.8262e-5), "stamp": (-0.8486e-5, 0.8486e-5)}
PUB_MORTAR_UY = {"work": (0.5563e-4, 0.9600e-4), "stamp": (0.0, 0.6254e-4)}
PUB_MORTAR_DEV_MAX = 3.306


@dataclass(frozen=True)
class Section44Scene:
    """The parameters of Section 4.4's two methods (config section ``ch4_section44``).

    Penalty (Table 4.3, Figure 4.22): material E, nu, sigma_Y, H, theta; Coulomb mu_f;
    1/eps_n = f E for f in ``eps_n_factors`` (1/eps_t = eps_t_ratio of it), Figure 4.22
    at ``figure_factor``; the lift in ``n_load`` increments, Newton (rtol, max_newton,
    max_cuts); the BE stamp (h_stamp, be_degree) and the work piece mesh
    (``penalty_mesh``: "mortar" = work_cells, "h_work" = uniform h_work cells; its
    ``penalty_formulation``); ``two_pass``: the contact in two passes, each body the
    slave once (``compare_passes``: the sweep also with the other treatment);
    ``h_work_fine`` > 0: the sweep again on that mesh; ``penalty_law`` "coulomb" (mu_f)
    or "tresca" (the mortar's F).  Mortar (Table 4.2, Figure 4.21): Tresca F, Uzawa step
    rho, TOL_DtN, TOL_U, Newton tolerance and caps of step 2, the damping grid
    omegas_D x omegas_N, the figure's dampings, the Q1 meshes stamp_cells, work_cells
    and the work piece's formulation.  The claims' tolerances: slope_tol, range_tol,
    pen_factor, iteration_factor, alt_tol_dtn and the scanned fit_tols."""

    E: float = E
    nu: float = NU
    sigma_Y: float = SIGMA_Y
    H: float = H
    theta: float = 1.0
    mu_f: float = 0.2
    eps_n_factors: tuple[float, ...] = (20.0, 10.0, 5.0, 2.5)
    eps_t_ratio: float = 0.5
    figure_factor: float = 10.0
    lift: float = 1e-4
    n_load: int = 5
    h_work: float = 1.0 / 11.0
    h_stamp: float = 0.1
    be_degree: int = 1
    rtol: float = 1e-8
    max_newton: int = 40
    max_cuts: int = 4
    slope_tol: float = 0.15            # penetration ~ eps^1: |slope - 1| <= slope_tol
    range_tol: float = 0.1             # colour-bar extremes within 10 % of the published ones
    pen_factor: float = 2.0            # penetration norms within a factor 2
    two_pass: bool = True
    compare_passes: bool = True
    h_work_fine: float = 0.0           # > 0: the sweep again on this work piece mesh
    penalty_mesh: str = "mortar"
    penalty_formulation: str = "full"
    compare_variants: bool = True      # extra runs splitting the mortar-penalty difference
    penalty_law: str = "coulomb"
    F: float = 0.22                    # given (Tresca) friction
    rho: float = 8.264e5               # Uzawa step (absolute)
    tol_dtn: float = 1e-6
    tol_uzawa: float = 1e-6
    newton_tol: float = 1e-8           # step 2 (thesis TOL_N = 1e-4, see MORTAR_CHOICES)
    max_dtn: int = 50                  # DtN cap: reaching it = no convergence
    newton_max_iter: int = 15          # step 2 cap (converged runs need <= 8)
    max_uzawa: int = 2000
    coupling_tol: float = 1e-3
    omegas_D: tuple[float, ...] = (0.3, 0.5, 0.7, 0.9)
    omegas_N: tuple[float, ...] = (0.3, 0.5, 0.7, 0.9, 1.0)
    figure_omegas: tuple[float, ...] = (0.5, 0.7)
    stamp_cells: tuple[int, ...] = (10, 20)      # 11 x 21 = 231 nodes
    work_cells: tuple[int, ...] = (61, 31)       # 62 x 32 = 1984 nodes
    mortar_formulation: str = "full"
    iteration_factor: float = 1.3      # DtN counts within 30 %
    alt_tol_dtn: float = 1e-4          # the counts also at this looser TOL_DtN (same runs)
    # relative tolerances scanned for the one that fits Table 4.2 (tolerance_fit_claim)
    fit_tols: tuple[float, ...] = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5)
    monolithic: bool = True            # also the monolithic semismooth Newton

    def __post_init__(self):
        for name in ("stamp_cells", "work_cells", "figure_omegas"):
            if len(getattr(self, name)) != 2:
                raise ValueError(f"{name} must have two entries, got {getattr(self, name)!r}")
        if not self.eps_n_factors or any(not f > 0 for f in self.eps_n_factors):
            raise ValueError(f"eps_n_factors must be positive, got {self.eps_n_factors!r}")
        if self.figure_factor not in self.eps_n_factors:
            raise ValueError(f"figure_factor must be one of eps_n_factors "
                             f"{self.eps_n_factors!r}, got {self.figure_factor!r}")
        for name in ("tol_dtn", "tol_uzawa", "newton_tol", "coupling_tol", "alt_tol_dtn",
                     "rho", "iteration_factor", "slope_tol", "range_tol", "pen_factor",
                     "lift", "h_work", "h_stamp", "eps_t_ratio", "rtol"):
            real(name, getattr(self, name), positive=True)   # a tolerance <= 0: never met
        for name in ("mu_f", "F", "h_work_fine"):
            real(name, getattr(self, name), nonnegative=True)
        integer("max_cuts", self.max_cuts, lo=0)
        for name in ("n_load", "max_newton", "max_dtn", "newton_max_iter", "max_uzawa",
                     "be_degree"):
            integer(name, getattr(self, name), lo=1)
        for name in ("omegas_D", "omegas_N", "figure_omegas"):       # dampings
            for w in getattr(self, name) or [None]:
                real(name, w, lo=0.0, hi=1.0, lo_open=True)
        for name in ("stamp_cells", "work_cells"):
            for n in getattr(self, name) or [None]:
                integer(name, n, lo=1)
        if not self.fit_tols or any(not self.tol_dtn <= t < 1 for t in self.fit_tols):
            raise ValueError(f"fit_tols must lie in [tol_dtn, 1), got {self.fit_tols!r}")
        for name, allowed in (("penalty_mesh", ("mortar", "h_work")),
                              ("penalty_law", ("coulomb", "tresca")),
                              ("penalty_formulation", ("full", "bbar")),
                              ("mortar_formulation", ("full", "bbar"))):
            choice(name, getattr(self, name), allowed)

    def settings(self, factor: float) -> StampContact:
        """Penalty 1/eps_n = factor E, 1/eps_t = eps_t_ratio factor E; Coulomb mu_f or
        (penalty_law 'tresca') the mortar's Tresca bound F; Newton (rtol, max_newton,
        max_cuts, line search, bonded predictor), its systems by SuperLU with the
        minimum degree ordering of A + A^T and diagonal pivots ("MMD_AT_PLUS_A"):
        1.3x (61 x 31 cells) to 1.7x (88 x 44) faster per run than COLAMD, measured on
        every run of the section (sweeps, variants): the same Newton iterations in every
        increment, the fields within 4e-14 (relative)."""
        return StampContact(factor, self.eps_t_ratio * factor, self.mu_f,
                            F=self.F if self.penalty_law == "tresca" else None,
                            two_pass=self.two_pass, solver=ContactSettings(
                                rtol=self.rtol, max_iter=self.max_newton,
                                max_cuts=self.max_cuts, line_search=True, predictor=True,
                                lu_ordering="MMD_AT_PLUS_A"))

    @property
    def penalty_cells(self) -> tuple[int, int]:
        """(nx, ny) Q1 cells of the penalty work piece."""
        if self.penalty_mesh == "mortar":
            return int(self.work_cells[0]), int(self.work_cells[1])
        return tuple(max(1, int(round((hi - lo) / self.h_work)))
                     for lo, hi in ((WORK[0], WORK[1]), (WORK[2], WORK[3])))

    def material(self) -> J2Material:
        return J2Material(self.E, self.nu, self.sigma_Y, self.H, self.theta)

    def fine(self) -> "Section44Scene":
        """The parameters of the penetration sweep on the uniform h_work_fine mesh."""
        return replace(self, h_work=self.h_work_fine or self.h_work, penalty_mesh="h_work")

    def frictionless(self) -> "Section44Scene":
        return replace(self, mu_f=0.0, penalty_law="coulomb")

    def elastic(self) -> "Section44Scene":
        """The same scene with a work piece that never yields (sigma_Y x 1e12)."""
        return replace(self, sigma_Y=1e12 * self.sigma_Y)


#: the changes the explanations of both figures must survive (issue 22): the parameters
#: of :func:`sensitivity_variants`
VARIANT_TEXT = {
    "table": "the table's meshes",
    "alignment": "one work piece cell more across (the nodes of Gamma^m_C shifted against "
                 "the stamp's)",
    "load_steps": "4 x n_load load increments (the penalty runs; the mortar DtN is one "
                  "step from the virgin state, unchanged)",
    "refinement": "both bodies refined: the work piece on the h_work_fine mesh (without "
                  "one: twice its cells), the stamp's cells doubled and h_stamp halved",
}


def sensitivity_variants(prm: Section44Scene) -> dict[str, Section44Scene]:
    """The parameters of :data:`VARIANT_TEXT` ("table": ``prm`` itself).  The work piece
    cells are the mortar's ``work_cells`` and, with penalty_mesh 'mortar', the
    penalty's."""
    nx, ny = prm.work_cells
    fine = prm.fine().penalty_cells if prm.h_work_fine > 0 else (2 * nx, 2 * ny)
    return {"table": prm,
            "alignment": replace(prm, work_cells=(nx + 1, ny)),
            "load_steps": replace(prm, n_load=4 * prm.n_load),
            "refinement": replace(prm, work_cells=fine, h_stamp=prm.h_stamp / 2,
                                  stamp_cells=tuple(2 * c for c in prm.stamp_cells))}


# --------------------------------------------------------------------------- readings
#: Readings of the DtN stopping rule (Algorithm 4.3, step 7: "stop if ||P^k - P^k-1|| <=
#: TOL_DtN ||P^k-1||"), recorded per iteration by :class:`DtNReadings`: the quantity (P:
#: the transferred traction functional on Gamma^2_C; U2: the work piece's displacement
#: of step 2), the norm (l2 / max of the coefficient vector, L2(Gamma_C) of the function
#: M2^-1 P, the elastic energy norm of U2, U2 on Gamma^2_C) and the reference (the
#: previous iterate - the printed rule -, the new one -
#: :func:`hpfebe.solvers.fixed_point`'s -, or the first nonzero P).
#: "P_n_l2_prev": the normal components of P alone (a test on the contact pressure).
#: "P_t_l2_prev" is no reading but a bound: the tangential components of P's increment
#: alone, relative to ||P^k-1|| (<= P_l2_prev: the printed rule cannot stop before it
#: falls below TOL).  Where the stamp slides, step 6 relaxes the tangential traction
#: alone (R1_t = F w lambda, |lambda| = 1, does not change), so this quantity contracts by
#: exactly 1 - omega_N per iteration.
READINGS = ("P_l2_prev", "P_l2_new", "P_max_prev", "P_L2gamma_prev", "P_l2_first",
            "U2_l2_prev", "U2_max_prev", "U2_energy_prev", "U2_contact_prev", "P_n_l2_prev",
            "P_t_l2_prev")
#: what each reading of :data:`READINGS` measures (the bound "P_t_l2_prev" left out)
READING_TEXT = {
    "P_l2_prev": "P, l2, relative to P^k-1 (the printed rule)",
    "P_l2_new": "P, l2, relative to P^k (fixed_point's; the table's stop)",
    "P_max_prev": "P, max-norm, relative to P^k-1",
    "P_L2gamma_prev": "P as function, L2(Gamma_C), relative to P^k-1",
    "P_l2_first": "P, l2, relative to the first nonzero P",
    "U2_l2_prev": "U2, l2 (all dofs), relative to U2^k-1",
    "U2_max_prev": "U2, max-norm, relative to U2^k-1",
    "U2_energy_prev": "U2, elastic energy norm, relative to U2^k-1",
    "U2_contact_prev": "U2 on Gamma_C, l2, relative to U2^k-1",
    "P_n_l2_prev": "the normal components of P alone, l2, relative to P_n^k-1",
}


def _rel(num, den) -> float:
    return float(num / den) if den > 0 else np.inf


class DtNReadings:
    """The relative increment of every DtN iteration k under every reading of the
    stopping rule (:data:`READINGS`), in :attr:`values` (inf where the reference is zero
    or not yet defined: the first iteration has P_0 = 0 and no previous U2): a
    per-iteration hook of :meth:`~hpfebe.contact.mortar_fe.FEMortarContact.dtn` on
    ``problem``, called with the :class:`~hpfebe.solvers.DtNState` of the iteration."""

    def __init__(self, problem: FEMortarContact):
        self.values = {k: [] for k in READINGS}
        self.first = None
        self.t2, self.c2 = problem.t2, problem.c2
        self._m2_lu = spla.splu(sp.csc_matrix(problem.mortar.M2))
        self._K2e = problem.work.K.tocsr()

    def _l2_gamma(self, v) -> float:
        """||M2^-1 v||_L2(Gamma_C) of a functional v on Gamma^2_C."""
        V = v.reshape(-1, 2)
        return float(np.sqrt(max((self._m2_lu.solve(V) * V).sum(), 0.0)))

    def _energy(self, v) -> float:
        return float(np.sqrt(max(v @ (self._K2e @ v), 0.0)))

    def __call__(self, state) -> None:
        P_old, P_new, u2_old, u2 = state.P, state.P_new, state.u2_old, state.u2
        out, t2 = self.values, self.t2
        if self.first is None:
            self.first = P_new
        dP = P_new - P_old
        out["P_l2_prev"].append(_rel(np.linalg.norm(dP), np.linalg.norm(P_old)))
        out["P_l2_new"].append(_rel(np.linalg.norm(dP), np.linalg.norm(P_new)))
        out["P_max_prev"].append(_rel(np.abs(dP).max(), np.abs(P_old).max()))
        out["P_L2gamma_prev"].append(_rel(self._l2_gamma(dP), self._l2_gamma(P_old)))
        out["P_l2_first"].append(_rel(np.linalg.norm(dP), np.linalg.norm(self.first)))
        out["P_t_l2_prev"].append(_rel(np.linalg.norm(dP.reshape(-1, 2)[:, t2]),
                                       np.linalg.norm(P_old)))
        out["P_n_l2_prev"].append(_rel(np.linalg.norm(dP.reshape(-1, 2)[:, 1 - t2]),
                                       np.linalg.norm(P_old.reshape(-1, 2)[:, 1 - t2])))
        if u2_old is None:
            for k in ("U2_l2_prev", "U2_max_prev", "U2_energy_prev", "U2_contact_prev"):
                out[k].append(np.inf)
            return
        dU = u2 - u2_old
        out["U2_l2_prev"].append(_rel(np.linalg.norm(dU), np.linalg.norm(u2_old)))
        out["U2_max_prev"].append(_rel(np.abs(dU).max(), np.abs(u2_old).max()))
        out["U2_energy_prev"].append(_rel(self._energy(dU), self._energy(u2_old)))
        out["U2_contact_prev"].append(_rel(np.linalg.norm(dU[self.c2]),
                                           np.linalg.norm(u2_old[self.c2])))


def tangential_share(problem: FEMortarContact, sol) -> float:
    """||T|| / ||P||: the tangential part of the transferred traction P of a solution
    against P (the share that bounds Table 4.2's printed rule from below)."""
    P = sol.P.reshape(-1, 2)
    return float(np.linalg.norm(P[:, problem.t2]) / np.linalg.norm(P))


# --------------------------------------------------------------------------- fields
def mortar_bodies(problem: FEMortarContact, sol) -> dict:
    """Both bodies' (nodal points, cells, nodal displacement) of a mortar solution."""
    u1, u2 = sol.extra["u1"], sol.extra["u2"]
    return {"work": (problem.work.mesh.p.T, problem.work.mesh.t.T,
                     problem.work.elastic.nodal_displacement(u2).T),
            "stamp": (problem.stamp.mesh.p.T, problem.stamp.mesh.t.T,
                      problem.stamp.nodal_displacement(u1).T)}


def penalty_bodies(fe: ElastoPlasticFE, peak, h_stamp: float) -> dict:
    """Both bodies' (points, cells, displacement) of a penalty solution at full lift
    (``peak``: the touch's Snapshot): the work piece's nodes, the BE stamp's interior by
    the representation formula on a grid of cell size h_stamp / 2."""
    nx = max(1, int(round((STAMP[1] - STAMP[0]) / h_stamp * 2)))
    ny = max(1, int(round((STAMP[3] - STAMP[2]) / h_stamp * 2)))
    ps, us, cs = stamp_interior(peak.stamp, peak.u_stamp, nx, ny)
    return {"work": (fe.mesh.p.T, fe.mesh.t.T, fe.elastic.nodal_displacement(peak.u_work).T),
            "stamp": (ps, np.asarray(cs), us)}


def _tensor_interp(points, values, at):
    """Bilinear (Q1) interpolation of nodal ``values`` on a tensor-product mesh with
    vertices ``points`` (n, 2) at the points ``at``."""
    from scipy.interpolate import RegularGridInterpolator

    xs, ys = np.unique(points[:, 0]), np.unique(points[:, 1])
    ix, iy = np.searchsorted(xs, points[:, 0]), np.searchsorted(ys, points[:, 1])
    grid = np.zeros((xs.size, ys.size) + values.shape[1:])
    grid[ix, iy] = values
    return RegularGridInterpolator((xs, ys), grid)(np.clip(at, [xs[0], ys[0]],
                                                           [xs[-1], ys[-1]]))


def _cell_value(mesh, cell_values, at):
    """The element-wise constant field of a tensor Q1 mesh at the points ``at``."""
    xs, ys = np.unique(mesh.p[0]), np.unique(mesh.p[1])
    c = mesh.p[:, mesh.t].mean(axis=1).T
    ix = np.clip(np.searchsorted(xs, c[:, 0]) - 1, 0, xs.size - 2)
    iy = np.clip(np.searchsorted(ys, c[:, 1]) - 1, 0, ys.size - 2)
    grid = np.full((xs.size - 1, ys.size - 1), np.nan)
    grid[ix, iy] = cell_values
    jx = np.clip(np.searchsorted(xs, at[:, 0]) - 1, 0, xs.size - 2)
    jy = np.clip(np.searchsorted(ys, at[:, 1]) - 1, 0, ys.size - 2)
    return grid[jx, jy]


def _difference(body: str, field: str, a: np.ndarray, b: np.ndarray) -> dict:
    return dict(body=body, field=field, n_points=int(a.size),
                rel_l2=float(np.linalg.norm(a - b) / np.linalg.norm(a)),
                rel_max=float(np.abs(a - b).max() / np.abs(a).max()))


def field_differences(a: dict, b: dict) -> list[dict]:
    """Relative differences ||a - b||_2 / ||a||_2 and max|a - b| / max|a| of the fields
    ``b`` against the reference ``a`` on b's points: displacements at b's nodes / grid
    points (a bilinearly interpolated unless the points coincide), ||dev sigma|| at b's
    element centroids (a's element value there).  ``a``, ``b``: :func:`mortar_bodies` or
    :func:`penalty_bodies` with the work piece's (mesh, element values of ||dev sigma||)
    under "dev".  One row (body, field, n_points, rel_l2, rel_max) per body and field."""
    rows = []
    for body in ("work", "stamp"):
        pb, _, ub = b[body]
        pa, _, ua = a[body]
        same = pa.shape == pb.shape and np.allclose(pa, pb)
        ui = ua if same else _tensor_interp(pa, ua, pb)
        rows += [_difference(body, name, ui[:, c], ub[:, c])
                 for c, name in ((0, "u_x"), (1, "u_y"))]
    (ma, da), (mb, db) = a["dev"], b["dev"]
    cent = mb.p[:, mb.t].mean(axis=1).T
    rows.append(_difference("work", "dev_sigma_norm", _cell_value(ma, da, cent), db))
    return rows


__all__ = ["PUB_DEV_MAX", "PUB_MORTAR_DEV_MAX", "PUB_MORTAR_UX", "PUB_MORTAR_UY", "PUB_UX",
           "PUB_UY", "READINGS", "READING_TEXT", "STAMP", "VARIANT_TEXT", "WORK", "X_POINT",
           "DtNReadings", "Section44Scene", "dtn_settings", "field_differences",
           "mortar_bodies", "penalty_bodies", "penalty_scene", "penetration_l2",
           "section44_scene", "sensitivity_variants", "tangential_share"]
