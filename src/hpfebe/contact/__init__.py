"""Contact problems: the one frictional penalty contact problem of two bodies
(:class:`TwoBodyContact`, Section 4.2, Algorithm 4.1), its rigid-obstacle case with
Tresca / Coulomb friction (:func:`solve_friction`, Sections 3.3.1, 4.2), normal penalty
contact with exact integration of the positive part (:func:`solve_penalty`, Section 3.2),
and mortar contact of two BE bodies (:class:`MortarContact`, Section 4.3) or of FE bodies
(:class:`FEMortarContact`, Section 4.4).  The bodies: :mod:`hpfebe.bodies`; the pointwise
laws: :mod:`hpfebe.constitutive`; Newton and the load path: :mod:`hpfebe.solvers`."""

from .friction import FrictionResult, FrictionSettings, solve_friction
from .loading import LoadSteps
from .limits import (MACHEPS, PenaltyCheck, backward_error, check_penalty_solution,
                     constrained_limit, saturation_index, singular_exponent,
                     solve_penalty_checked)
from .mortar import MortarContact, MortarSolution, node_points
from .mortar_fe import FEMortarContact, NeumannSettings
from .penalty import PenaltyResult, solve_penalty
from .result import ContactResult
from .settings import LINEAR_SOLVERS, LU_ORDERINGS, ContactSettings
from .two_body import TwoBodyContact

__all__ = ["ContactResult", "FEMortarContact", "FrictionResult",
           "LoadSteps", "MortarContact", "MortarSolution", "PenaltyResult",
           "TwoBodyContact", "solve_friction",
           "ContactSettings", "LINEAR_SOLVERS", "LU_ORDERINGS",
           "solve_penalty", "MACHEPS", "PenaltyCheck", "backward_error",
           "check_penalty_solution", "constrained_limit", "saturation_index",
           "singular_exponent", "solve_penalty_checked"]
__all__ += ["NeumannSettings"]
__all__ += ["node_points"]
__all__ += ["FrictionSettings"]
