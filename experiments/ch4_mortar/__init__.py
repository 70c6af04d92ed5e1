"""Table 4.1, Figures 4.17 and 4.18 (Section 4.3.4, thesis lines 19474-19625): hp-mortar
BEM for two-body contact with given (Tresca) friction, solved by the Dirichlet-to-Neumann
algorithm (Algorithm 4.3) with the Uzawa algorithm (Algorithm 4.4) and Polyak's projected
CG inside (:mod:`hpfebe.solvers` on :mod:`hpfebe.contact.mortar`), data transfer by the
mortar projection (4.87) and its adjoint (:mod:`hpfebe.coupling.mortar`).

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

The model problem: :mod:`hpfebe.scenes.mortar`; its parameters, the choices where the
thesis is silent, the published numbers and the runs: :mod:`hpfebe.scenes.mortar_runs`;
what the claims rest on: :mod:`hpfebe.scenes.mortar_readings`; the artefacts:
:mod:`.table`, :mod:`.uzawa`.  ParaView files (``exports``, both boundaries with U and
the contact state along Gamma^1_C): Figure 4.17's, 4.18's finest and 4.19's solutions,
and the semismooth Newton reference of the solver comparison (Coulomb).
"""

from __future__ import annotations

import dataclasses

from hpfebe.scenes import mortar_runs as mr
from hpfebe.suite import ArtefactResult, from_config, select_scenes, timed

from .table import (convergence_sweep, damping_sweep, figure_4_17, figure_4_18,
                    figure_dtn_map, table_4_1)
from .uzawa import figure_4_19, figure_4_20, figure_solver_comparison, figure_uzawa_rho

ARTEFACTS = ("table_4_1", "figure_4_17", "figure_4_18", "figure_4_19", "figure_4_20",
             "figure_dtn_map", "figure_uzawa_rho", "figure_solver_comparison")
#: independent computations, one workflow job each (wall times: the module's report):
#: the damping sweep on the Table 4.1 mesh (its consistent-reading runs give Figure 4.17's
#: solution), the Figure 4.18 mesh sweep, the global Uzawa solves (Algorithm 4.5), the DtN
#: map and solver comparison on the Table 4.1 mesh
SCENES = {"table": ("table_4_1", "figure_4_17"), "sweep": ("figure_4_18",),
          "uzawa": ("figure_4_19", "figure_4_20", "figure_uzawa_rho"),
          "beyond": ("figure_dtn_map", "figure_solver_comparison")}


def _table_problem(prm: mr.MortarScene):
    """The Table 4.1 problem (p = table_p on the table_n meshes), shared by the DtN
    artefacts on that mesh, and its set-up time."""
    return timed(prm.problem, prm.table_n[0], prm.table_n[1], prm.table_p, prm.table_p)


def _scene_table(prm: mr.MortarScene, table) -> list[ArtefactResult]:
    pr, setup = table
    df, best = damping_sweep(prm, pr)
    if best is None:
        raise RuntimeError("table_4_1: no damping pair converged, nothing to plot")
    return [table_4_1(prm, pr, df, setup), figure_4_17(prm, pr, best)]


#: the computation of each scene of :data:`SCENES`; those on the Table 4.1 mesh get
#: ``table`` = (problem, set-up time) of :func:`_table_problem` (assembled once per run)
_SCENE_RUNS = {
    "table": (_scene_table, True),
    "sweep": (lambda prm, _: [figure_4_18(prm, *convergence_sweep(prm))], False),
    "uzawa": (lambda prm, _: [figure_4_19(prm), figure_4_20(prm), figure_uzawa_rho(prm)],
              False),
    "beyond": (lambda prm, table: [figure_dtn_map(prm, table[0]),
                                   figure_solver_comparison(prm, table[0])], True)}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """scenes: names of :data:`SCENES` to compute (None: all)."""
    prm = from_config(mr.MortarScene, config, "ch4_mortar")
    if quick and "adapt_steps" not in (config or {}):
        prm = dataclasses.replace(prm, adapt_steps=mr.QUICK_ADAPT[0],
                                  adapt_show=mr.QUICK_ADAPT[1])
    table, out = None, []
    for name in select_scenes(SCENES, scenes, "ch4_mortar"):     # in the order of SCENES
        f, on_table_mesh = _SCENE_RUNS[name]
        if on_table_mesh and table is None:
            table = _table_problem(prm)
        out += f(prm, table)
    return out
