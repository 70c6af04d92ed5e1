"""FE/BE coupling: Nitsche interface terms (Chapter 2), the mortar projection (4.87)."""

from .examples import SINGULAR, SMOOTH, InterfaceProblem, problem
from .mortar import MortarProjection
from .nitsche import DEFAULT_ALPHA, DEFAULT_LAMBDA, NitscheFEBE, NitscheSolution

__all__ = ["SINGULAR", "SMOOTH", "InterfaceProblem", "problem", "DEFAULT_ALPHA",
           "DEFAULT_LAMBDA", "MortarProjection", "NitscheFEBE", "NitscheSolution"]
