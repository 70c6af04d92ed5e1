"""Boundary element operators: kernels, Galerkin assembly, S_hat, representation formula;
compressed (H-matrix) operators in :mod:`hpfebe.bem.hmatrix`."""

from .assembly import assemble, sandwich
from .hmatrix import CompressedOperators, HMatrix, HMatrixSettings
from .lame import LameBEM
from .laplace import LaplaceBEM
from .mixed import MixedData, MixedSolution, solve_mixed
from .operators import BoundaryOperators

__all__ = ["assemble", "sandwich", "BoundaryOperators", "LameBEM", "LaplaceBEM",
           "MixedData", "MixedSolution", "solve_mixed",
           "HMatrix", "HMatrixSettings", "CompressedOperators"]
