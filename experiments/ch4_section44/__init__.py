"""Tables 4.2-4.3 and Figures 4.21-4.22 (Section 4.4, thesis lines 20355-20720): mortar
against penalty for frictional contact between an elastic stamp and an elastoplastic
work piece.

Scene: elastic Omega_s = [-1/2, 1/2] x [0, 2] (top fixed) on elastoplastic
Omega_m = [-2, 2] x [-2, 0] (J2 flow with linear hardening (4.21)-(4.22),
:class:`hpfebe.fem.plastic_body.ElastoPlasticFE`) whose bottom is lifted by 1e-4;
E = 266926, nu = 0.29, sigma_Y = 4.0, H = 450.0 (:mod:`hpfebe.scenes.section44`).

Penalty (Table 4.3, Figure 4.22): FE/BE - the stamp a Galerkin BE body (P1 on the
boundary, :class:`hpfebe.bem.lame.LameBEM`, :func:`hpfebe.scenes.penalty_scene`), the
work piece plain Q1 on the mortar part's mesh (61 x 31 cells, the thesis's 1984 nodes in
both methods; B-bar and the uniform h_work mesh as options); Coulomb friction mu_f =
0.2 with the penalty laws (4.19)-(4.20) (a comparison variant: the mortar's Tresca F in
the penalty law, ``penalty_law``), 1/eps_n = 20, 10, 5, 2.5 x E_m and 1/eps_t
half of that, Algorithm 4.1 (incremental loading, Newton with the consistent tangents
(4.36)-(4.43)), the contact in two passes (each body the slave once, ``two_pass``;
the single pass beside it).  Reported: Newton iterations (total over the load
increments) and the L2 norm of the penetration ([u_n] - g)_+ on Gamma_C (the first
pass's quadrature of :class:`hpfebe.contact.two_body.TwoBodyContact`) per penalty pair;
Figure 4.22: u_x, u_y of both bodies and ||dev sigma_m|| with the colorbar ranges beside
the published ones.

Mortar (Table 4.2, Figure 4.21): pure FEM, Q1 in both bodies
(:class:`hpfebe.contact.FEMortarContact`, :func:`hpfebe.scenes.section44_scene`), given
(Tresca) friction F = 0.22, the Dirichlet-to-Neumann algorithm (Algorithm 4.3, Remark
4.3.5, :func:`hpfebe.solvers.dtn`) with the elastoplastic Neumann problem of the work
piece solved by Newton (step 2) and the stamp's frictional contact problem by Uzawa
(Algorithm 4.4, rho = 8.264e5; step 4), TOL_DtN = TOL_U = 1e-6;
Table 4.2: DtN iterations (Uzawa iterations of the first DtN iteration) on the damping
grid, non-convergence detected; Figure 4.21: the fields at omega_D = 0.5, omega_N = 0.7
with the plastic region, and the relative differences between the mortar and the
penalty solutions on common points.  The choices where the thesis is silent are
:data:`hpfebe.scenes.section44_runs.CHOICES` (penalty) and
:data:`~hpfebe.scenes.section44_runs.MORTAR_CHOICES`.

Jobs (:data:`SCENES`): "penalty" (Table 4.3, :mod:`.penalty`, and both figures,
:mod:`.fields`: the figures use Table 4.3's penalty runs and Figure 4.22's ranges; the
comparison of the two methods :mod:`.comparison`, the drawings :mod:`.plots`), "dtn"
(Table 4.2 and the monolithic Newton, :mod:`.dtn`).  The scene, its parameters and the
published colour bars: :mod:`hpfebe.scenes.section44`; the runs:
:mod:`hpfebe.scenes.section44_runs`; the fields compared and exported:
:mod:`hpfebe.scenes.section44_fields`; what the claims rest on:
:mod:`hpfebe.scenes.section44_readings` (Tables 4.2, 4.3) and
:mod:`hpfebe.scenes.section44_figures` (the colour bars).  The explanations of the
figures' and Table 4.2's differences are re-tested on
:func:`hpfebe.scenes.section44.sensitivity_variants` (interface mesh alignment, load
steps, refinement) and kept as explanations only where they survive them; readings that
are not derived are hypotheses.  ParaView files (``exports``): the final state of each
job - the stiffest penalty run (table_4_3), the DtN solution at Figure 4.21's dampings
(table_4_2), both figures' solutions.
"""

from __future__ import annotations

import functools

from hpfebe.scenes import section44, section44_runs
from hpfebe.suite import ArtefactResult, from_config, select_scenes, timed

from .dtn import mortar_sweep, table_4_2
from .fields import figures
from .penalty import table_4_3

ARTEFACTS = ("table_4_3", "figure_4_22", "table_4_2", "figure_4_21")
#: independent computations: Table 4.3's penalty sweeps (both contact treatments, the
#: fine mesh) with the two figures, which use the penalty runs of Table 4.3's parameters
#: (Figure 4.21 compares the mortar solution with each), the colour ranges of Figure
#: 4.22 and the sensitivity variants of their explanations; and Table 4.2's DtN sweep
SCENES = {"penalty": ("table_4_3", "figure_4_22", "figure_4_21"), "dtn": ("table_4_2",)}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """The artefacts of the scenes asked for (:data:`SCENES`; None: all); ``quick`` is
    unused: config/quick.yaml sets the sizes."""
    prm = from_config(section44.Section44Scene, config, scene="ch4_section44")
    scenes = select_scenes(SCENES, scenes, "ch4_section44")
    solve = penalty_solver()            # the table and the figures share the penalty runs
    out = {}
    if "penalty" in scenes:
        out["table_4_3"] = table_4_3(prm, solve)
        out.update(figures(prm, solve))
    if "dtn" in scenes:
        pr, setup = timed(section44_runs.mortar_scene, prm)
        tab, sols = mortar_sweep(prm, pr)
        out["table_4_2"] = table_4_2(prm, pr, tab, sols, setup)
    return [out[a] for a in ARTEFACTS if a in out]


def penalty_solver():
    """:func:`hpfebe.scenes.section44_runs.run_penalty` memoised on (parameters, factor):
    Table 4.3, both figures, the comparison variants and the sensitivity checks ask for
    the same runs."""
    return functools.lru_cache(maxsize=None)(section44_runs.run_penalty)
