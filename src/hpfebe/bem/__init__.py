"""Boundary element operators: kernels, Galerkin assembly, S_hat, representation formula."""

from .assembly import assemble
from .lame import LameBEM
from .laplace import LaplaceBEM

__all__ = ["assemble", "LameBEM", "LaplaceBEM"]
