"""Contact: pointwise laws (:mod:`.laws`), bodies (:mod:`.bodies`: FE, BE, rigid
obstacle), the one frictional penalty contact problem of two bodies
(:class:`TwoBodyContact`, Section 4.2, Algorithm 4.1), its rigid-obstacle case with
Tresca / Coulomb friction (:func:`solve_friction`, Sections 3.3.1, 4.2), and normal
penalty contact with exact integration of the positive part (:func:`solve_penalty`,
Section 3.2).  Newton and the load path: :mod:`hpfebe.nonlinear`."""

from .bodies import BEBody, FEBody, RigidObstacle, as_body
from .friction import FrictionResult, solve_friction
from .laws import OPEN, SLIP, STICK, penalty_friction
from .penalty import PenaltyResult, solve_penalty
from .two_body import ContactResult, TwoBodyContact, TwoBodyResult

__all__ = ["BEBody", "ContactResult", "FEBody", "FrictionResult", "OPEN", "PenaltyResult",
           "RigidObstacle", "SLIP", "STICK", "TwoBodyContact", "TwoBodyResult", "as_body",
           "penalty_friction", "solve_friction", "solve_penalty"]
