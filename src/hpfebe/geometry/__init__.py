"""Polygonal boundary meshes of one or more closed curves (:class:`BoundaryMesh`).

The mesh class and its conventions (labels, degrees, orientation): :mod:`.mesh`;
input checks: :mod:`.validation`; the orientation of the curves: :mod:`.orientation`;
the self-intersection test (a grid of segments): :mod:`.crossing`; points and convex
polygons inside, on or outside the enclosed region: :mod:`.containment`; bisection and
degrees: :mod:`.refinement`; the common refinement of several meshes: :mod:`.common`.
"""

from .common import common_refinement
from .mesh import LABELS, BoundaryMesh

__all__ = ["BoundaryMesh", "common_refinement", "LABELS"]
