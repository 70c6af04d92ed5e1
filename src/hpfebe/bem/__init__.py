"""Boundary element operators: kernels, Galerkin assembly, S_hat, representation formula."""

from .assembly import assemble, sandwich
from .lame import LameBEM
from .laplace import LaplaceBEM
from .operators import BoundaryOperators

__all__ = ["assemble", "sandwich", "BoundaryOperators", "LameBEM", "LaplaceBEM"]
