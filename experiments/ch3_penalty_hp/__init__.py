"""hp-penalty BEM for frictionless contact: the rate of Theorem 3.2.6 and a stability
stress test (beyond the thesis, issue 4; the scene: :mod:`hpfebe.scenes.penalty`, the
body and obstacle of Table 3.1 in plane strain, p on every element, (3.57)).

``figure_penalty_hp_rate`` (:mod:`.hp_rate`) - Theorem 3.2.6 (thesis lines 8363-8480):
if u is in H~^{3/2}(Sigma), Tu in H^{1/2}(Gamma) and eps >= C~ (h/p)^{1-epsilon},
epsilon in (0, 1/2), then

    ||u - U^eps||_{H~^{1/2}(Sigma)} <= C ( h/p ||u||_{3/2} + (eps + h/p) ||Tu||_{1/2} ),   (3.81)

i.e. with eps = C_pen (h/p)^{1-epsilon} the energy error ||I U - U_ref||_{S_ref} is
O((h/p)^{1-epsilon}).  The corners where Gamma_D meets Gamma_N give singularities
r^lambda, lambda < 1 (:func:`hpfebe.contact.singular_exponent`): on uniform meshes the
observed rate is min(1 - epsilon, lambda) at best.

``figure_penalty_stability`` (:mod:`.stability`) - a fixed mesh, eps = C_eps h down to
C_eps = 1e-20, the flat obstacle (penalty error against the eps -> 0 limit) and a tilted
one (partial contact), every run checked by its condition number, relative residual and
componentwise backward error (:func:`hpfebe.contact.solve_penalty_checked`).  The choices:
``scene.HP_RATE_CHOICES``, ``scene.STABILITY_CHOICES``; the claims' verdicts:
:mod:`hpfebe.scenes.penalty_readings`.
"""

from __future__ import annotations

from hpfebe.scenes import penalty as scene
from hpfebe.suite import ArtefactResult, from_config_sections, select_scenes

from .hp_rate import rate_result
from .stability import stability_result

ARTEFACTS = ("figure_penalty_hp_rate", "figure_penalty_stability")
#: independent computations: the hp-rate sweep and the fixed-mesh stress test
SCENES = {"hp_rate": ("figure_penalty_hp_rate",), "stability": ("figure_penalty_stability",)}

SCENE_RUNS = {"hp_rate": rate_result, "stability": stability_result}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """The artefacts of the scenes asked for (None: both; ``quick`` is unused:
    config/quick.yaml sets the sizes)."""
    prm = from_config_sections(scene.PenaltyHpScene, config, "ch3_penalty_hp",
                               hp_rate=scene.HpRateParams, stability=scene.StabilityParams)
    names = select_scenes(SCENES, scenes, "ch3_penalty_hp")
    jit_s = scene.warm_up(prm)  # compile / load the numba cache
    return [SCENE_RUNS[name](prm, jit_s) for name in names]
