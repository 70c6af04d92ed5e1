"""Compressed hp-BEM operators (issue 27): H-matrices with ACA+ far-field blocks.

A cluster tree on the boundary elements (:mod:`.cluster`), the standard admissibility
min(diam) <= eta dist, near-field blocks by the singular / near-singular quadrature of
the dense assembly (:mod:`.entries`), far-field blocks by ACA+ with QR/SVD
recompression to the user tolerance (:mod:`.aca`), numba matvecs (:mod:`.matrix`),
CG with a multilevel (:mod:`.precond`) or block-Jacobi preconditioner and GMRES
(:mod:`.solvers`), and the compressed V, K, K', W, B, S_hat,
Psi of a LaplaceBEM / LameBEM built with ``compression="hmatrix"`` (:mod:`.operators`).
"""

from .cluster import ClusterTree, block_tree, cluster_tree
from .dispatch import Compressible
from .matrix import HMatrix, Layout
from .operators import CompressedOperators, HMatrixSettings
from .precond import Multilevel
from .solvers import BlockJacobi, cg, gmres

__all__ = ["ClusterTree", "cluster_tree", "block_tree", "HMatrix", "Layout",
           "HMatrixSettings", "CompressedOperators", "Compressible", "BlockJacobi",
           "Multilevel", "cg", "gmres"]
