"""Contact: penalty formulation with semismooth Newton (Section 3.2), penalty Tresca /
Coulomb friction with the return map (Sections 3.3.1, 4.2), and two bodies - FE or BE,
in any combination - in frictional penalty contact on non-matching meshes (Section 4.2)."""

from .bem_body import BEBodyAdapter, FEBodyAdapter, make_adapter
from .friction import FrictionResult, solve_friction
from .penalty import PenaltyResult, solve_penalty
from .two_body import TwoBodyContact, TwoBodyResult

__all__ = ["BEBodyAdapter", "FEBodyAdapter", "FrictionResult", "PenaltyResult",
           "TwoBodyContact", "TwoBodyResult", "make_adapter", "solve_friction",
           "solve_penalty"]
