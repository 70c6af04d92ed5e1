"""What every boundary element operator family shares (Section 1.4).

:class:`BoundaryOperators` owns the spaces W_hp and V_hp of one mesh, caches the matrices
(assembled on first use), and builds from a subclass's V, K, M, W and its constraint
functionals C the discrete Steklov-Poincare operator and the discrete traction

    B = K + M/2,     S_hat = W + B^T P B,     Psi = P B U,
    P = V^{-1} - V^{-1} C (C^T V^{-1} C)^{-1} C^T V^{-1}    (constrained)
    P = V^{-1}                                               (unconstrained, the thesis),

with V factorised once (Cholesky).  The constraint C^T Psi = 0 is the one the exact
traction of a solution without sources satisfies (zero flux for Laplace, zero total force
for Lame); it makes S_hat independent of the kernel's length scale (see
:mod:`hpfebe.bem.laplace`).  Subclasses (:class:`~hpfebe.bem.laplace.LaplaceBEM`,
:class:`~hpfebe.bem.lame.LameBEM`) define ``d`` (components), ``V``, ``K``, ``M``, ``W``
and ``constraints``.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import scipy.linalg as sla
from numba import njit

from ..checks import boolean, instance, real
from ..geometry import BoundaryMesh
from ..spaces import ContinuousSpace, DiscontinuousSpace
from .assembly_kernels import _symmetrise


def mesh_diameter(mesh: BoundaryMesh) -> float:
    """``mesh.diameter`` (largest distance of two nodes, the default kernel scale), the
    same float: by all pairs of the used nodes for small meshes while scipy.spatial
    (its convex hull) is not imported yet - that import is 0.3-0.6 s of a process's
    first operator, more than assembling one small mesh."""
    if "scipy.spatial" in sys.modules or len(mesh.nodes) > 512:
        return mesh.diameter
    return _max_pair_distance(np.ascontiguousarray(mesh.nodes[np.unique(mesh.elements)]))


@njit(cache=True)
def _max_pair_distance(x):
    """max_ij |x_i - x_j|: the same float as numpy's all-pairs norm, without its
    n x n x 2 temporaries (2.6 ms -> 0.14 ms at 256 nodes)."""
    best = 0.0
    for i in range(x.shape[0]):
        for j in range(x.shape[0]):
            d0 = x[i, 0] - x[j, 0]
            d1 = x[i, 1] - x[j, 1]
            best = max(best, math.sqrt(d0 * d0 + d1 * d1))
    return best


class BoundaryOperators:
    d = 1
    _intermediates: tuple[str, ...] = ()   # cache entries S_hat releases (only W's inputs)

    def __init__(self, mesh: BoundaryMesh, scale: float, constrained: bool):
        self.mesh = instance("mesh", mesh, BoundaryMesh)
        self.scale = real("scale", scale, positive=True)
        # the constraint flag of the subclass ("no" is not True): Laplace's zero_flux,
        # Lame's zero_force
        self.constrained = boolean("zero_flux" if self.d == 1 else "zero_force",
                                   constrained)
        self.W_space = DiscontinuousSpace(mesh)
        self.V_space = ContinuousSpace(mesh)
        self._cache: dict[str, object] = {}

    def _get(self, name, build):
        if name not in self._cache:
            self._cache[name] = build()
        return self._cache[name]

    @property
    def K_adj(self) -> np.ndarray:
        """Adjoint double layer K' = K^T (Galerkin)."""
        return self.K.T

    @property
    def B(self) -> np.ndarray:
        """K + M/2 (test W_hp, trial V_hp), the right-hand side of V Psi = B U."""
        return self._get("B", lambda: self.K + 0.5 * self.M.toarray())

    @property
    def V_cho(self):
        """Cholesky factor of V (computed once)."""
        def build():
            try:
                return sla.cho_factor(self.V, lower=True)
            except np.linalg.LinAlgError as exc:
                raise np.linalg.LinAlgError(
                    "V is not positive definite: increase the kernel scale "
                    f"(scale={self.scale})") from exc
        return self._get("V_cho", build)

    @property
    def S_hat(self) -> np.ndarray:
        """Discrete Steklov-Poincare operator W + B^T P B (Section 1.4), symmetric.

        With Y = L^{-1} B (V = L L^T) and Z = L^{-1} C: S_hat = W + Y^T Y
        - Y^T Z (Z^T Z)^{-1} Z^T Y, then (S + S^T) / 2.  Memory (issue 27): W is built
        first; B (an O(n^2) sum) and the subclass's ``_intermediates`` (Lame: Vt, only
        W's input) leave the cache before Y exists (rebuilt on demand, the same floats),
        B itself once Y is there; Y is freed before W is added and the symmetrisation
        is in place.  Peak beside the cached V, V_cho, K, W: Y and S (Lame p = 1,
        N = 2048: 9.10 -> about 6 n^2 doubles in all); the same floats as the former
        ``0.5 * (S + S.T)`` of ``S = W + Y^T Y - ...``."""
        def build():
            W = self.W
            B = self.B
            for name in ("B",) + self._intermediates:
                self._cache.pop(name, None)
            c, lower = self.V_cho
            Y = sla.solve_triangular(c, B, lower=lower)
            del B
            S = Y.T @ Y
            if self.constrained:
                Z = sla.solve_triangular(c, self.constraints, lower=lower)
                YZ = Y.T @ Z
            del Y
            S += W                                 # = W + Y^T Y (IEEE + commutes)
            if self.constrained:
                S -= YZ @ np.linalg.solve(Z.T @ Z, YZ.T)
            _symmetrise(S)
            return S
        return self._get("S_hat", build)

    def Psi(self, U) -> np.ndarray:
        """Discrete traction Psi = P (K + M/2) U in W_hp (``U``: coefficients in V_hp,
        one vector or the columns of a matrix)."""
        U = np.asarray(U, dtype=float)
        n = self.d * self.V_space.ndof
        if U.ndim not in (1, 2) or U.shape[0] != n:
            raise ValueError(f"U must have {n} rows (d x V_hp dofs), got shape {U.shape}")
        if not np.all(np.isfinite(U)):
            raise ValueError("U contains NaN or infinite entries")
        psi = sla.cho_solve(self.V_cho, self.B @ U)
        if self.constrained:
            C = self.constraints
            VC = self._get("V_inv_C", lambda: sla.cho_solve(self.V_cho, C))
            psi = psi - VC @ np.linalg.solve(C.T @ VC, np.tensordot(C.T, psi, axes=1))
        return psi
