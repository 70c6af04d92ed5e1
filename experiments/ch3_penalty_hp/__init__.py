"""hp-penalty BEM for frictionless contact: the rate of Theorem 3.2.6 and a stability stress test.

Beyond the thesis (issue 4).  The problem is the one of Table 3.1 (thesis lines 8540-8640,
:mod:`experiments.ch3_penalty`, scene :mod:`hpfebe.scenes.penalty`): rigid
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
(:func:`hpfebe.contact.singular_exponent`), so on uniform meshes the
discretisation error converges like h^lambda and the observed rate is
min(1 - epsilon, lambda) at best.

``figure_penalty_stability`` - stress test at a fixed mesh, eps = C_eps h down to
C_eps = 1e-20, for the flat obstacle of Table 3.1 (all of Gamma_C in contact; penalty
error against the eps -> 0 limit on the same mesh,
:func:`hpfebe.contact.constrained_limit`) and a tilted one, g(x) = -d + s (x + 1)
(partial contact).  Every run is checked by
:func:`hpfebe.contact.solve_penalty_checked` (condition number, relative residual,
componentwise backward error of G(U) = S_hat U + (1/eps) int (U_n - g_h)_+ v_n = 0).
The choices are :data:`.hp_rate.RATE_CHOICES` and :data:`.stability.STABILITY_CHOICES`;
the two artefacts are independent :data:`SCENES` (modules :mod:`.hp_rate`,
:mod:`.stability`).  The scene (body, obstacles, the sweeps) is
:mod:`hpfebe.scenes.penalty`.
"""

from __future__ import annotations

from hpfebe.scenes import penalty as scene
from hpfebe.suite import ArtefactResult, from_config_sections, select_scenes

from .hp_rate import RATE_CHOICES, rate_result
from .stability import STABILITY_CHOICES, stability_result

ARTEFACTS = ("figure_penalty_hp_rate", "figure_penalty_stability")
#: independent computations: the hp-rate sweep and the fixed-mesh stress test
SCENES = {"hp_rate": ("figure_penalty_hp_rate",), "stability": ("figure_penalty_stability",)}

CHOICES = RATE_CHOICES + STABILITY_CHOICES

#: the parameters of the scene (config section ch3_penalty_hp, subsections hp_rate, stability)
HpRateParams, StabilityParams, Params = (scene.HpRateParams, scene.StabilityParams,
                                         scene.PenaltyHpScene)


# --------------------------------------------------------------------------- run
SCENE_RUNS = {"hp_rate": rate_result, "stability": stability_result}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """The artefacts of the scenes asked for (None: both; ``quick`` is unused:
    config/quick.yaml sets the sizes)."""
    prm = from_config_sections(Params, config, "ch3_penalty_hp", hp_rate=HpRateParams,
                               stability=StabilityParams)
    names = select_scenes(SCENES, scenes, "ch3_penalty_hp")
    jit_s = scene.warm_up(prm)  # compile / load the numba cache
    return [SCENE_RUNS[name](prm, jit_s) for name in names]
