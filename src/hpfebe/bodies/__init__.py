"""Bodies of the contact problems behind one protocol (Chapter 4, Section 4.2; the
protocol is described in :mod:`.body`): a finite element body (:class:`FEBody`), an
elastoplastic FE body (:class:`PlasticFEBody`), a boundary element body
(:class:`BEBody`), the elastoplastic BE body of Section 4.2.4 (:class:`ElastoPlasticBE`,
its contact wrapper :class:`PlasticBEBody`, :mod:`.plastic_be`) and a rigid obstacle
(:class:`RigidObstacle`).  Bodies know nothing of the contact problems above them.
"""

from .body import BEBody, FEBody, PlasticFEBody, RigidObstacle, as_body
from .condensed import CondensedBody
from .cell_operators import CellStrainOperators
from .plastic_be import DirichletSolver, ElastoPlasticBE, PlasticBEBody, staggered_path

__all__ = ["BEBody", "FEBody", "PlasticFEBody", "RigidObstacle", "as_body",
           "ElastoPlasticBE", "PlasticBEBody", "DirichletSolver", "staggered_path"]
__all__ += ["CondensedBody"]
__all__ += ["CellStrainOperators"]
