"""Contact: gap functions, penalty formulation with semismooth Newton (Section 3.2),
penalty Tresca / Coulomb friction with the return map (Sections 3.3.1, 4.2)."""

from .friction import FrictionResult, solve_friction
from .penalty import PenaltyResult, solve_penalty

__all__ = ["FrictionResult", "PenaltyResult", "solve_friction", "solve_penalty"]

# two elastic FE bodies in frictional penalty contact (Section 4.2)
from .two_body import TwoBodyContact, TwoBodyResult  # noqa: E402

__all__ += ["TwoBodyContact", "TwoBodyResult"]
