"""Boundary integral operators of the 2D Laplace equation (Sections 1.2-1.4).

Fundamental solution with a length scale R (default: the diameter of Gamma),

    G(x, y) = -1/(2 pi) log(|x - y| / R),

so that V is positive definite on any boundary (the log capacity of Gamma/R is below 1,
Lemma 1.2.2).  Conventions of (1.3)-(1.4), with n the outward normal:

    V phi(x) = int G(x,y) phi(y) ds_y,           K u(x) = int d_{n_y} G(x,y) u(y) ds_y,
    <W u, v> = <V du/ds, dv/ds>  (integration by parts; W 1 = 0 on closed curves),

so that the interior Calderon identity reads  V psi = (K + 1/2) u  for psi = du/dn, and
(K + 1/2) 1 = 0.  Galerkin matrices (spaces of :mod:`hpfebe.spaces`):

    V (W_hp x W_hp),  K (test W_hp, trial V_hp),  K' = K^T,  W = T^T V T  (V_hp x V_hp),
    M (test W_hp, trial V_hp),

with T the exact W_hp coefficients of d/ds (:meth:`ContinuousSpace.derivative_matrix`).
On meshes with all degrees 1, V and K have closed forms (:mod:`hpfebe.bem.lowest_order`,
used unless ``closed_form=False``); otherwise :func:`hpfebe.bem.assembly.assemble`.
The discrete Steklov-Poincare operator of Section 1.4 is

    S_hat = W + (K + M/2)^T V^{-1} (K + M/2),      Psi = V^{-1} (K + M/2) U.

Scale invariance (a deliberate refinement of the thesis's definition).  Changing R adds
c m m^T to V (m_k = int Phi_k, c = log(R'/R)/(2 pi)), which changes the thesis's S_hat by
the rank-one term  -c b b^T / (1 + c m^T V^{-1} m),  b = B^T V^{-1} m: zero only if the
discrete equilibrium density satisfied (K' + 1/2) w_h = 0 exactly.  On the unit square
this is 3e-4 (p=1, 2 elements per side) to 8e-8 (p=8, 8 per side) relative: S_hat
depends on R at the level of the discretisation error.  With ``zero_flux=True``
(default) Psi is sought among densities with zero total flux m^T Psi = 0 - which the
exact Neumann datum of every harmonic function satisfies (Gauss) - so that

    S_hat = W + B^T P B,   P = V^{-1} - V^{-1} m (m^T V^{-1} m)^{-1} m^T V^{-1},

is symmetric, has the constants as kernel, converges at the same rate (the constraint
holds for the exact solution) and does not depend on R at all.  ``zero_flux=False`` gives
the thesis's formula verbatim.
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import boolean
from ..geometry import BoundaryMesh
from ..spaces import ContinuousSpace, DiscontinuousSpace
from .assembly import assemble, sandwich
from .hmatrix.dispatch import Compressible
from .kernels import INV_2PI, KP_LAPLACE_LOG_R, LAPLACE_DL, LAPLACE_SL
from .lowest_order import applies as _closed_form_applies
from .lowest_order import laplace_p1_vk, laplace_p1_w
from .operators import BoundaryOperators, mesh_diameter
from .potentials import (POT_LAPLACE_DL, POT_LAPLACE_SL, density, evaluate_potential,
                         evaluation_points)

SINGLE_LAYER_LOGC = np.array([-INV_2PI])
P1_W_DIRECT_MAX = 512   # p = 1 meshes up to this many elements: W by laplace_p1_w
NO_LOG = np.array([0.0])


def _scale_param(R: float) -> np.ndarray:
    """Kernel parameter array kp of the Laplace kernels (index KP_LAPLACE_LOG_R)."""
    kp = np.empty(KP_LAPLACE_LOG_R + 1)
    kp[KP_LAPLACE_LOG_R] = math.log(R) * INV_2PI
    return kp


class LaplaceBEM(Compressible, BoundaryOperators):
    """Galerkin boundary element operators of the Laplacian on one boundary mesh.

    Parameters
    ----------
    mesh : BoundaryMesh
        closed curves, outward normals
    scale : float, optional
        the length scale R of the fundamental solution (default: the diameter of the
        mesh)
    zero_flux : bool
        constrain Psi to zero total flux (scale-invariant S_hat, see the module doc;
        default True)
    closed_form : bool
        on a mesh with all degrees 1, assemble V and K together by the closed forms of
        :mod:`hpfebe.bem.lowest_order` (and W = T^T V T without forming T up to
        P1_W_DIRECT_MAX elements): equal to the quadrature path to round-off, 2-5x
        faster (issue 14); ``False`` forces the general quadrature path (default True)
    compression : {None, "hmatrix"}
        None (dense matrices, default) or "hmatrix": V, K, K_adj, W, B and S_hat become
        LinearOperators of H-matrices (ACA+, :mod:`hpfebe.bem.hmatrix`), Psi a
        preconditioned CG on the compressed V; ``hmatrix_info()`` reports storage,
        ranks, times and the achieved errors
    tol : float
        the relative accuracy of the compressed operators, in (0, 1) (checked also when
        ``compression`` is None; default 1e-8)

    Notes
    -----
    ``W_space`` (W_hp) and ``V_space`` (V_hp, all dofs) are the spaces; the matrices
    ``V``, ``K``, ``W``, ``M``, ``B``, ``S_hat`` are assembled on first use, then
    cached; ``Psi(U)`` is the discrete flux (see
    :class:`~hpfebe.bem.operators.BoundaryOperators`), ``representation`` the field
    inside (1.2).
    """

    def __init__(self, mesh: BoundaryMesh, scale: float | None = None,
                 zero_flux: bool = True, closed_form: bool = True,
                 compression: str | None = None, tol: float = 1e-8):
        if isinstance(mesh, BoundaryMesh) and scale is None:
            scale = mesh_diameter(mesh)
        super().__init__(mesh, scale, constrained=zero_flux)
        self.zero_flux = self.constrained
        self.kp = _scale_param(self.scale)
        # p = 1 everywhere: V and K by the closed forms, both in one pass
        self.closed_form = boolean("closed_form", closed_form) and _closed_form_applies(mesh)
        self._set_compression(compression, tol)

    def hmatrix_kernels(self):
        """(kernel id, log coefficient) of V, K and of W's single-layer kernel."""
        return ((LAPLACE_SL, SINGLE_LAYER_LOGC), (LAPLACE_DL, NO_LOG),
                (LAPLACE_SL, SINGLE_LAYER_LOGC))

    def _closed_vk(self):
        V, K = laplace_p1_vk(self.W_space, self.V_space, self.scale)
        self._cache.setdefault("V", V)
        self._cache.setdefault("K", K)

    @property
    def V(self) -> np.ndarray:
        """Single layer, W_hp x W_hp, symmetric positive definite."""
        if self.hm is not None:
            return self.hm.V
        if self.closed_form and "V" not in self._cache:
            self._closed_vk()
        return self._get("V", lambda: assemble(LAPLACE_SL, SINGLE_LAYER_LOGC, self.kp,
                                               self.W_space, self.W_space, symmetric=True))

    @property
    def K(self) -> np.ndarray:
        """Double layer, test W_hp, trial V_hp."""
        if self.hm is not None:
            return self.hm.K
        if self.closed_form and "K" not in self._cache:
            self._closed_vk()
        return self._get("K", lambda: assemble(LAPLACE_DL, NO_LOG, [0.0],
                                               self.W_space, self.V_space))

    @property
    def T(self):
        """Sparse W_hp coefficients of the arc-length derivative of V_hp functions."""
        return self._get("T", lambda: self.V_space.derivative_matrix(self.W_space))

    @property
    def M(self):
        """Sparse mass matrix, test W_hp, trial V_hp."""
        return self._get("M", lambda: self.V_space.mass_matrix(self.W_space))

    @property
    def W(self) -> np.ndarray:
        """Hypersingular operator, V_hp x V_hp, with <W U, U'> = <V dU/ds, dU'/ds>."""
        if self.hm is not None:
            return self.hm.W
        if self.closed_form and self.mesh.n_elements <= P1_W_DIRECT_MAX:
            # p = 1, small mesh: T^T V T without forming T (T costs more than W there);
            # larger meshes use the sandwich, which runs on threads
            return self._get("W", lambda: laplace_p1_w(self.V, self.W_space,
                                                       self.V_space))
        return self._get("W", lambda: sandwich(self.T, self.V))

    @property
    def m(self) -> np.ndarray:
        """The total-flux functional, m_k = int_Gamma Phi_k ds (W_hp)."""
        return self._get("m", lambda: np.asarray(self.M.sum(axis=1)).ravel())

    @property
    def constraints(self) -> np.ndarray:
        return self.m[:, None]

    def solve_dirichlet(self, g) -> np.ndarray:
        """Neumann data psi_h in W_hp of the interior Dirichlet problem with trace
        g (coefficients in V_hp): V psi_h = (K + M/2) g."""
        return self.Psi(g)

    def representation(self, points, U, psi) -> np.ndarray:
        """u(x) = int G(x,y) psi(y) ds_y - int d_{n_y}G(x,y) U(y) ds_y for interior x
        (formula (1.2) with f = 0); ``U`` in V_hp, ``psi`` in W_hp.  ValueError for
        ``U`` or ``psi`` of the wrong length, non-finite data, or a point on Gamma
        (:class:`~hpfebe.bem.potentials.PointOnBoundaryError`)."""
        pts = evaluation_points(points)
        U, psi = density("U", U, self.V_space, 1), density("psi", psi, self.W_space, 1)
        u = evaluate_potential(POT_LAPLACE_SL, self.kp, 1, pts, self.W_space, psi, name="psi")
        u -= evaluate_potential(POT_LAPLACE_DL, self.kp, 1, pts, self.V_space, U, name="U")
        return u[:, 0]


def local_blocks(mesh: BoundaryMesh, i: int, j: int, scale: float = 1.0) -> dict:
    """Local Galerkin blocks of the test element i and trial element j of ``mesh`` at
    their degrees: V (Legendre x Legendre), K (Legendre x GLL Lagrange) and
    W = T_i^T V_ij T_j (GLL x GLL), with the kernel scale R = ``scale``.  For tests and
    for inspecting one entry without assembling the whole matrix."""
    from .assembly import local_block

    kp = _scale_param(scale)
    V = local_block(LAPLACE_SL, SINGLE_LAYER_LOGC, kp, mesh, i, j, 0, 0)
    K = local_block(LAPLACE_DL, NO_LOG, [0.0], mesh, i, j, 0, 1)
    Ts = []
    for e in (i, j):
        p = int(mesh.degrees[e])
        single = BoundaryMesh.polygon([(0, 0), (1, 0), (0, 1)], n=1, p=p)
        T = ContinuousSpace(single).derivative_matrix(DiscontinuousSpace(single)).toarray()
        # local rows/cols of element 0 of the reference triangle, rescaled to |e|
        Vs = ContinuousSpace(single)
        Ts.append(T[:p][:, Vs.elem_dofs[0, :p + 1]] * (single.lengths[0] / mesh.lengths[e]))
    W = Ts[0].T @ V @ Ts[1]
    return {"V": V, "K": K, "W": W}
