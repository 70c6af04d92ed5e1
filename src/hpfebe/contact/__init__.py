"""Contact: gap functions, penalty formulation with semismooth Newton (Section 3.2)."""

from .penalty import PenaltyResult, solve_penalty

__all__ = ["PenaltyResult", "solve_penalty"]
