"""hpfebe: hp finite element / boundary element methods for interface and contact
problems, and the reproduction of the thesis's experiments."""

from .geometry import BoundaryMesh
from .spaces import ContinuousSpace, DiscontinuousSpace

__all__ = ["BoundaryMesh", "ContinuousSpace", "DiscontinuousSpace", "__version__"]
__version__ = "0.1.0"
