"""Finite element parts (scikit-fem based): labelled meshes, Poisson Q_p, linear elasticity,
the J2 plastic body with quadrature-point state (the J2 law: :mod:`hpfebe.constitutive.j2`),
Newton potentials of plastic cells.  Importing it makes scikit-fem find the edges of a
mesh by integer keys (:mod:`.skfem_entities`: the same arrays, 3-9x faster)."""

from . import skfem_entities
from .meshes import (Concentration, FEDomain, block_grid, cell_diameter, distance_to_set,
                     facet_containing, is_conforming, local_mesh_size, new_vertices,
                     refine_labelled, refinement_concentration, tensor_block_mesh)
from .elasticity import ElasticBody, rectangle_mesh
from .newton_potential import CellComplex, newton_operators
from .plastic_body import DisplacementSteps, ElastoPlasticFE
from .poisson import PoissonFE, quad_element

__all__ = ["Concentration", "FEDomain", "block_grid", "cell_diameter", "distance_to_set",
           "facet_containing", "is_conforming", "local_mesh_size", "new_vertices",
           "refine_labelled", "refinement_concentration", "tensor_block_mesh", "PoissonFE",
           "quad_element", "ElasticBody", "rectangle_mesh", "CellComplex", "newton_operators",
           "DisplacementSteps", "ElastoPlasticFE"]

skfem_entities.install()
