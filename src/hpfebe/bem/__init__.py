"""Boundary element operators: kernels, Galerkin assembly, S_hat, representation formula."""

from .assembly import assemble
from .laplace import LaplaceBEM

__all__ = ["assemble", "LaplaceBEM"]
