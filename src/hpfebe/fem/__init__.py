"""Finite element parts (scikit-fem based): meshes of the FE subdomain and Poisson Q_p."""

from .meshes import FEDomain, block_grid, tensor_block_mesh
from .poisson import PoissonFE, quad_element

__all__ = ["FEDomain", "block_grid", "tensor_block_mesh", "PoissonFE", "quad_element"]
