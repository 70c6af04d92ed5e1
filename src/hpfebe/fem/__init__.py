"""Finite element parts (scikit-fem based): labelled meshes, Poisson Q_p, linear elasticity."""

from .meshes import (Concentration, FEDomain, block_grid, cell_diameter, distance_to_set,
                     facet_containing, is_conforming, local_mesh_size, new_vertices,
                     refine_labelled, refinement_concentration, tensor_block_mesh)
from .poisson import PoissonFE, quad_element

__all__ = ["Concentration", "FEDomain", "block_grid", "cell_diameter", "distance_to_set",
           "facet_containing", "is_conforming", "local_mesh_size", "new_vertices",
           "refine_labelled", "refinement_concentration", "tensor_block_mesh", "PoissonFE",
           "quad_element"]
