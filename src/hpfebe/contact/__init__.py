"""Contact problems: the one frictional penalty contact problem of two bodies
(:class:`TwoBodyContact`, Section 4.2, Algorithm 4.1), its rigid-obstacle case with
Tresca / Coulomb friction (:func:`solve_friction`, Sections 3.3.1, 4.2), normal penalty
contact with exact integration of the positive part (:func:`solve_penalty`, Section 3.2),
and mortar contact of two BE bodies (:class:`MortarContact`, Section 4.3) or of FE bodies
(:class:`FEMortarContact`, Section 4.4).  The bodies: :mod:`hpfebe.bodies`; the pointwise
laws: :mod:`hpfebe.constitutive`; Newton and the load path: :mod:`hpfebe.solvers.nonlinear`."""

from .friction import FrictionResult, solve_friction
from .loading import LoadSteps
from .mortar import CondensedBody, MortarContact, MortarSolution, projected_cg
from .mortar_fe import FEMortarContact
from .penalty import PenaltyResult, solve_penalty
from .two_body import ContactResult, TwoBodyContact, TwoBodyResult

__all__ = ["ContactResult", "CondensedBody", "FEMortarContact", "FrictionResult",
           "LoadSteps", "MortarContact", "MortarSolution", "PenaltyResult",
           "TwoBodyContact", "TwoBodyResult", "projected_cg", "solve_friction",
           "solve_penalty"]
