"""A posteriori error estimation and adaptive h-refinement (Section 3.3).

* :mod:`.marking` - maximum strategy (Algorithm 3.2), the thesis's "largest share"
  criterion, Doerfler bulk marking.
* :mod:`.bem_estimator` - residual BE indicator (3.107), error measure (3.105), Laplace
  and Lame.
* :mod:`.fe_estimator` - residual FE indicator (3.100), error measure (3.99), P1/Q1,
  Poisson and linear elasticity; the indicators of two FE bodies in contact with the
  contact datum on Gamma_C.
* :mod:`.adaptive` - the loop of Algorithm 3.2, for one mesh or several (one marking
  per mesh), with the marked elements of every step in its history.
* :mod:`.mortar_estimator` - the hp-adaptive mortar contact of Section 4.3.5: the
  indicator of two BE bodies in mortar contact and the h-or-p choice of Algorithm 4.6.
"""

from .adaptive import AdaptiveHistory, adapt, default_refine
from .bem_estimator import (INDICATOR_VARIANTS, bem_indicators, boundary_residuals,
                            consistency_weight, contact_traction, error_measure_B,
                            error_measure_B_lame, lame_bem_indicators,
                            lame_boundary_residuals, lame_contact_indicators, norm_B,
                            solve_lame_mixed, solve_laplace_mixed, true_error)
from .fe_estimator import energy_error as fe_energy_error
from .fe_estimator import energy_error_elasticity as fe_energy_error_elasticity
from .fe_estimator import (contact_traction_datum, fe_indicators, hooke_stress, lame_stress,
                           two_body_indicators)
from .marking import mark_bulk, mark_doerfler, mark_max
from .mortar_estimator import hp_refine, mortar_indicators

__all__ = ["AdaptiveHistory", "adapt", "default_refine", "bem_indicators",
           "boundary_residuals", "error_measure_B", "solve_laplace_mixed",
           "error_measure_B_lame", "lame_bem_indicators", "lame_boundary_residuals",
           "solve_lame_mixed", "fe_energy_error", "fe_energy_error_elasticity",
           "fe_indicators", "lame_stress", "hooke_stress", "contact_traction_datum",
           "two_body_indicators", "mark_bulk", "mark_doerfler", "mark_max", "mortar_indicators",
           "hp_refine", "INDICATOR_VARIANTS", "consistency_weight", "contact_traction",
           "lame_contact_indicators", "norm_B", "true_error"]
