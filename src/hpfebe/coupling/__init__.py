"""FE/BE coupling: Nitsche interface terms (Chapter 2)."""

from .examples import SINGULAR, SMOOTH, InterfaceProblem, problem
from .nitsche import DEFAULT_ALPHA, DEFAULT_LAMBDA, NitscheFEBE, NitscheSolution

__all__ = ["SINGULAR", "SMOOTH", "InterfaceProblem", "problem", "DEFAULT_ALPHA",
           "DEFAULT_LAMBDA", "NitscheFEBE", "NitscheSolution"]
