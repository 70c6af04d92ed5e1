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
import scipy.linalg as sla
from numba import njit, prange

from ..geometry import BoundaryMesh
from ..quadrature import rule_tables
from ..spaces import P_MAX, ContinuousSpace, DiscontinuousSpace, eval_basis, gll_tables
from .assembly import assemble
from .integration import NMAX, _order
from .kernels import INV_2PI, LAPLACE_DL, LAPLACE_SL



SINGLE_LAYER_LOGC = np.array([-INV_2PI])
NO_LOG = np.array([0.0])


def _scale_param(R: float) -> np.ndarray:
    return np.array([math.log(R) * INV_2PI])


class LaplaceBEM:
    """Galerkin boundary element operators of the Laplacian on one boundary mesh.

    Parameters
    ----------
    mesh : BoundaryMesh (closed curves, outward normals)
    scale : length scale R of the fundamental solution (default: diameter of the mesh)
    zero_flux : constrain Psi to zero total flux (scale-invariant S_hat, see module doc)

    Attributes: ``W_space`` (W_hp), ``V_space`` (V_hp, all dofs), and the matrices
    ``V``, ``K``, ``W``, ``M`` (assembled on first use, then cached).
    """

    def __init__(self, mesh: BoundaryMesh, scale: float | None = None,
                 zero_flux: bool = True):
        if not isinstance(mesh, BoundaryMesh):
            raise ValueError(f"mesh must be a BoundaryMesh, got {type(mesh).__name__}")
        self.mesh = mesh
        self.scale = float(mesh.diameter if scale is None else scale)
        if not (math.isfinite(self.scale) and self.scale > 0):
            raise ValueError(f"scale must be positive, got {scale!r}")
        self.zero_flux = bool(zero_flux)
        self.W_space = DiscontinuousSpace(mesh)
        self.V_space = ContinuousSpace(mesh)
        self._cache: dict[str, object] = {}

    def _get(self, name, build):
        if name not in self._cache:
            self._cache[name] = build()
        return self._cache[name]

    # --------------------------------------------------------------- operators
    @property
    def V(self) -> np.ndarray:
        """Single layer, W_hp x W_hp, symmetric positive definite."""
        return self._get("V", lambda: assemble(LAPLACE_SL, SINGLE_LAYER_LOGC,
                                               _scale_param(self.scale), self.W_space,
                                               self.W_space, symmetric=True))

    @property
    def K(self) -> np.ndarray:
        """Double layer, test W_hp, trial V_hp."""
        return self._get("K", lambda: assemble(LAPLACE_DL, NO_LOG, [0.0],
                                               self.W_space, self.V_space))

    @property
    def K_adj(self) -> np.ndarray:
        """Adjoint double layer K' = K^T (V_hp x W_hp)."""
        return self.K.T

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
        """Hypersingular operator, V_hp x V_hp: <W U, U'> = <V dU/ds, dU'/ds>."""
        def build():
            T = self.T
            VT = np.ascontiguousarray((T.T @ self.V).T)  # V T, using V = V^T
            W = T.T @ VT
            return 0.5 * (W + W.T)
        return self._get("W", build)

    @property
    def B(self) -> np.ndarray:
        """K + M/2 (test W_hp, trial V_hp): the right-hand side operator of V Psi = B U."""
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
    def m(self) -> np.ndarray:
        """m_k = int_Gamma Phi_k ds (W_hp): the total-flux functional."""
        return self._get("m", lambda: np.asarray(self.M.sum(axis=1)).ravel())

    @property
    def S_hat(self) -> np.ndarray:
        """Discrete Steklov-Poincare operator W + B^T V^{-1} B (Section 1.4), symmetric;
        with ``zero_flux`` restricted to zero-flux densities (scale invariant)."""
        def build():
            c, lower = self.V_cho
            Y = sla.solve_triangular(c, self.B, lower=lower)
            S = self.W + Y.T @ Y
            if self.zero_flux:
                z = sla.solve_triangular(c, self.m, lower=lower)
                yz = Y.T @ z
                S -= np.outer(yz, yz) / (z @ z)
            return 0.5 * (S + S.T)
        return self._get("S_hat", build)

    def Psi(self, U) -> np.ndarray:
        """Discrete traction Psi = V^{-1} (K + M/2) U in W_hp (zero total flux if
        ``zero_flux``: Psi = P (K + M/2) U)."""
        psi = sla.cho_solve(self.V_cho, self.B @ np.asarray(U))
        if self.zero_flux:
            w = self._get("w_eq", lambda: sla.cho_solve(self.V_cho, self.m))
            psi = psi - np.multiply.outer(w, self.m @ psi) / (self.m @ w)
        return psi

    def solve_dirichlet(self, g) -> np.ndarray:
        """Neumann data psi_h in W_hp of the interior Dirichlet problem with trace
        g (coefficients in V_hp): V psi_h = (K + M/2) g."""
        return self.Psi(g)

    # --------------------------------------------------------------- post-processing
    def representation(self, points, U, psi) -> np.ndarray:
        """u(x) = int G(x,y) psi(y) ds_y - int d_{n_y}G(x,y) U(y) ds_y for interior x
        (formula (1.2) with f = 0); ``U`` in V_hp, ``psi`` in W_hp.  Quadrature orders
        grow with log(element size / distance), elements near x are subdivided."""
        pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, dtype=float)))
        if pts.shape[1] != 2:
            raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
        mesh = self.mesh
        gx, gw, _, _ = rule_tables(NMAX)
        gll_x, gll_b = gll_tables(P_MAX)
        out = _representation(pts, mesh.nodes, mesh.elements,
                              np.ascontiguousarray(mesh.normals), mesh.degrees,
                              self.W_space.elem_dofs, self.V_space.elem_dofs,
                              np.ascontiguousarray(psi, dtype=float),
                              np.ascontiguousarray(U, dtype=float),
                              math.log(self.scale), gx, gw, gll_x, gll_b)
        if not np.all(np.isfinite(out)):
            raise FloatingPointError("representation formula evaluated on the boundary")
        return out


@njit(cache=True, parallel=True)
def _representation(pts, nodes, elements, normals, degrees, dofs_w, dofs_v, psi, U, logR,
                    gx, gw, gll_x, gll_b):
    npts = pts.shape[0]
    ne = elements.shape[0]
    nmax = gx.shape[0] - 1
    out = np.zeros(npts)
    pmax = degrees.max() + 1
    for q in prange(npts):
        phi = np.empty(pmax)
        stack = np.empty((64, 2))
        x0, x1 = pts[q, 0], pts[q, 1]
        acc = 0.0
        for e in range(ne):
            a = nodes[elements[e, 0]]
            b = nodes[elements[e, 1]]
            L = math.hypot(b[0] - a[0], b[1] - a[1])
            p = degrees[e]
            stack[0, 0], stack[0, 1] = 0.0, 1.0
            top = 1
            while top > 0:
                top -= 1
                s0, s1 = stack[top, 0], stack[top, 1]
                h = (s1 - s0) * L
                # distance from x to the sub-segment
                ux, uy = (b[0] - a[0]), (b[1] - a[1])
                t = ((x0 - a[0]) * ux + (x1 - a[1]) * uy) / (L * L)
                t = min(s1, max(s0, t))
                dist = math.hypot(x0 - a[0] - t * ux, x1 - a[1] - t * uy)
                if dist < h and top < 60 and h > 1e-14 * L:
                    m = 0.5 * (s0 + s1)
                    stack[top, 0], stack[top, 1] = s0, m
                    stack[top + 1, 0], stack[top + 1, 1] = m, s1
                    top += 2
                    continue
                n = _order(2.0 * dist / h, p, nmax)
                for k in range(n):
                    s = s0 + (s1 - s0) * gx[n, k]
                    w = gw[n, k] * h
                    rx = x0 - (a[0] + s * ux)
                    ry = x1 - (a[1] + s * uy)
                    r2 = rx * rx + ry * ry
                    G = -INV_2PI * (0.5 * math.log(r2) - logR)
                    dG = INV_2PI * (rx * normals[e, 0] + ry * normals[e, 1]) / r2
                    eval_basis(0, p, 2.0 * s - 1.0, gll_x, gll_b, phi)
                    vpsi = 0.0
                    for j in range(p):
                        vpsi += phi[j] * psi[dofs_w[e, j]]
                    eval_basis(1, p, 2.0 * s - 1.0, gll_x, gll_b, phi)
                    vu = 0.0
                    for j in range(p + 1):
                        if dofs_v[e, j] >= 0:
                            vu += phi[j] * U[dofs_v[e, j]]
                    acc += w * (G * vpsi - dG * vu)
        out[q] = acc
    return out


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
