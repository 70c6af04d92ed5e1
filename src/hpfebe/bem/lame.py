"""Boundary integral operators of 2D linear elasticity (Lame), Sections 1.2-1.4.

Material: Young's modulus E, Poisson ratio nu; plane strain uses the Lame constants

    lambda = E nu / ((1 + nu)(1 - 2 nu)),   mu = E / (2 (1 + nu)),

plane stress the same formulas with the modified  lambda* = 2 lambda mu / (lambda + 2 mu)
(every formula below is written with "lambda" meaning lambda or lambda*).

Fundamental solution (Section 1.2, with a length scale R inside the log as for Laplace,
so that V is positive definite on any boundary):

    G(x, y) = c1 { -log(|r| / R) I + c2 r r^T / |r|^2 },   r = x - y,
    c1 = (lambda + 3 mu) / (4 pi mu (lambda + 2 mu)),   c2 = (lambda + mu) / (lambda + 3 mu).

Operators (1.4), n the outward normal, traction T_n u = sigma(u) n:

    V phi(x) = int G(x,y) phi(y) ds_y,
    K u(x)   = int (T_{n_y} G(x,y)^T) u(y) ds_y,   i.e. kernel K_ik = [sigma_y(G e_i) n_y]_k,
    K' = K^T (Galerkin),  W u = -T_{n_x} K u,

so that the interior Calderon identity reads V t = (K + 1/2) u and (K + 1/2) kills the
rigid motions, exactly as in :mod:`hpfebe.bem.laplace`.

Hypersingular operator by integration by parts (no hypersingular quadrature).  For 2D
elasticity (Steinbach, "Numerical Approximation Methods for Elliptic Boundary Value
Problems", Springer 2008, Section 6.6, the 2D counterpart of the 3D formula (6.24);
also Han, "A new class of variational formulations for the coupling of finite and
boundary element methods", J. Comput. Math. 8 (1990)) the bilinear form is

    <W u, v> = int int (dv/ds)(x)^T  Vt(x - y)  (du/ds)(y) ds_y ds_x,
    Vt(r)    = E' / (4 pi) { -log(|r| / R) I + r r^T / |r|^2 },
    E'       = 4 mu (lambda + mu) / (lambda + 2 mu)   (= E / (1 - nu^2) in plane strain),

i.e. 4 mu^2 times the fundamental solution with (3 - 4 nu) replaced by 1.  Galerkin:
W = T^T Vt T with T the exact derivative matrix of :mod:`hpfebe.spaces` (per component)
and Vt assembled on W_hp by the same :func:`assemble` as V.  The constant R is
irrelevant here (tangential derivatives have zero mean on closed curves).  Verified in
tests/test_lame.py through the Calderon identity W u = (1/2 - K') t for Kelvin fields,
the rigid motions in ker W and the patch test of S_hat.

Vector functions are interleaved: global index = 2 * scalar dof + component.

S_hat (Section 1.4) with a zero total force constraint (the analogue of the zero-flux
constraint of :mod:`hpfebe.bem.laplace`, see its docstring): changing R adds
c (m_x m_x^T + m_y m_y^T) to V, where m_c are the two total-force functionals
(int Psi_c ds); restricting Psi to int Psi = 0 - which the exact traction of every
elastic field without body force satisfies (equilibrium) - gives

    S_hat = W + B^T P B,   P = V^{-1} - V^{-1} m (m^T V^{-1} m)^{-1} m^T V^{-1},

independent of R, symmetric, with the three rigid motions in its kernel.
``zero_force=False`` gives the thesis's W + B^T V^{-1} B verbatim.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numba import njit

from ..geometry import BoundaryMesh
from ..spaces import ContinuousSpace, DiscontinuousSpace
from .assembly import assemble, local_block
from .potentials import evaluate_potential

PLANES = ("strain", "stress")


# ----------------------------------------------------------------------------- kernels
# Kernels follow the batched interface of :mod:`hpfebe.bem.integration`:
# kernel(rx, ry, npts, n_x, n_y, kp, out) fills out[q, c1*2 + c2] for q < npts.
# kp layout: [c1 log R, c1 c2, lambda, mu, c1, c2, Et log R, Et], Et = E'/(4 pi)
@njit(cache=True, inline="always")
def _log_rr(rx, ry, a0, a1, out):
    """a0 I + a1 r r^T / |r|^2 into out[0:4]."""
    f = a1 / (rx * rx + ry * ry)
    out[0] = a0 + f * rx * rx
    out[1] = f * rx * ry
    out[2] = out[1]
    out[3] = a0 + f * ry * ry


@njit(cache=True, inline="always")
def _traction_of_G(rx, ry, ny0, ny1, lam, mu, c1, c2, out):
    """K_ik(x, y) = [sigma_y(G(x, .) e_i) n_y]_k at r = x - y into out[0:4] (degree -1;
    on a straight element only its odd Cauchy part survives: principal value)."""
    r2 = rx * rx + ry * ry
    for i in range(2):
        ri = rx if i == 0 else ry
        e0 = 1.0 if i == 0 else 0.0
        e1 = 1.0 - e0
        # D_jl = d v_j / d y_l for v = G(x, .) e_i, with d/dy = -d/dr and
        # dG_ji/dr_l = c1 (-d_ij r_l + c2 (d_il r_j + d_jl r_i) - 2 c2 r_i r_j r_l/|r|^2)/|r|^2
        g = 2.0 * c2 * ri / r2
        d00 = -c1 * (-e0 * rx + c2 * (e0 * rx + ri) - g * rx * rx) / r2
        d01 = -c1 * (-e0 * ry + c2 * e1 * rx - g * rx * ry) / r2
        d10 = -c1 * (-e1 * rx + c2 * e0 * ry - g * ry * rx) / r2
        d11 = -c1 * (-e1 * ry + c2 * (e1 * ry + ri) - g * ry * ry) / r2
        div = d00 + d11
        s00 = lam * div + 2.0 * mu * d00
        s11 = lam * div + 2.0 * mu * d11
        s01 = mu * (d01 + d10)
        out[i * 2 + 0] = s00 * ny0 + s01 * ny1
        out[i * 2 + 1] = s01 * ny0 + s11 * ny1


@njit(cache=True)
def single_layer_kernel(rx, ry, npts, nx, ny, kp, out):
    """Regular part of G: c1 log R I + c1 c2 r r^T / |r|^2 (degree 0); the log part
    -c1 log|r| I is ``logc``."""
    for q in range(npts):
        _log_rr(rx[q], ry[q], kp[0], kp[1], out[q])


@njit(cache=True)
def double_layer_kernel(rx, ry, npts, nx, ny, kp, out):
    """Traction of G with respect to y, (1.4): K_ik = [sigma_y(G e_i) n_y]_k."""
    for q in range(npts):
        _traction_of_G(rx[q], ry[q], ny[0], ny[1], kp[2], kp[3], kp[4], kp[5], out[q])


@njit(cache=True)
def hypersingular_kernel(rx, ry, npts, nx, ny, kp, out):
    """Regular part of Vt: E'/(4 pi) (log R I + r r^T/|r|^2); log part -E'/(4 pi) log|r| I."""
    for q in range(npts):
        _log_rr(rx[q], ry[q], kp[6], kp[7], out[q])


# potential kernels (points off Gamma, see potentials.py): full kernel including the log
@njit(cache=True, inline="always")
def _pot_single(rx, ry, ny0, ny1, kp, out):
    _log_rr(rx, ry, kp[0] - 0.5 * kp[4] * math.log(rx * rx + ry * ry), kp[1], out)


@njit(cache=True, inline="always")
def _pot_double(rx, ry, ny0, ny1, kp, out):
    _traction_of_G(rx, ry, ny0, ny1, kp[2], kp[3], kp[4], kp[5], out)


def lame_constants(E: float, nu: float, plane: str = "strain") -> tuple[float, float]:
    """(lambda, mu) of the 2D model: plane strain, or plane stress with
    lambda* = 2 lambda mu / (lambda + 2 mu)."""
    E = float(E)
    nu = float(nu)
    if not (math.isfinite(E) and E > 0):
        raise ValueError(f"E (Young's modulus) must be positive, got {E!r}")
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise ValueError(f"nu (Poisson ratio) must lie in (-1, 0.5), got {nu!r}")
    if plane not in PLANES:
        raise ValueError(f"plane must be one of {PLANES}, got {plane!r}")
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = E / (2.0 * (1.0 + nu))
    if plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def kernel_params(lam: float, mu: float, scale: float) -> np.ndarray:
    c1 = (lam + 3.0 * mu) / (4.0 * math.pi * mu * (lam + 2.0 * mu))
    c2 = (lam + mu) / (lam + 3.0 * mu)
    Et = 4.0 * mu * (lam + mu) / (lam + 2.0 * mu) / (4.0 * math.pi)
    lR = math.log(scale)
    return np.array([c1 * lR, c1 * c2, lam, mu, c1, c2, Et * lR, Et])


def _logc(c: float) -> np.ndarray:
    return np.array([-c, 0.0, 0.0, -c])


NO_LOG = np.zeros(4)


def _kron2(A):
    """Scalar matrix -> interleaved 2-component matrix (A kron I_2)."""
    if sp.issparse(A):
        return sp.kron(A, sp.identity(2), format="csr")
    return np.kron(A, np.eye(2))


class LameBEM:
    """Galerkin boundary element operators of 2D linear elasticity on one boundary mesh.

    Parameters
    ----------
    mesh : BoundaryMesh (closed curves, outward normals)
    E, nu : Young's modulus (> 0) and Poisson ratio (in (-1, 0.5))
    plane : "strain" or "stress"
    scale : length scale R of the fundamental solution (default: 2 x diameter)
    zero_force : constrain Psi to zero total force (scale-invariant S_hat, module doc)

    Matrices (interleaved components, assembled on first use, cached): ``V`` (W_hp^2 x
    W_hp^2), ``K`` (test W_hp^2, trial V_hp^2), ``K_adj``, ``W`` (V_hp^2 x V_hp^2), ``M``,
    ``B = K + M/2``, ``S_hat``; ``Psi(U)`` the discrete traction.
    """

    d = 2

    def __init__(self, mesh: BoundaryMesh, E: float, nu: float, plane: str = "strain",
                 scale: float | None = None, zero_force: bool = True):
        if not isinstance(mesh, BoundaryMesh):
            raise ValueError(f"mesh must be a BoundaryMesh, got {type(mesh).__name__}")
        self.mesh = mesh
        self.E, self.nu, self.plane = float(E), float(nu), plane
        self.lam, self.mu = lame_constants(E, nu, plane)
        self.scale = float(2.0 * mesh.diameter if scale is None else scale)
        if not (math.isfinite(self.scale) and self.scale > 0):
            raise ValueError(f"scale must be positive, got {scale!r}")
        self.zero_force = bool(zero_force)
        self.kp = kernel_params(self.lam, self.mu, self.scale)
        self.W_space = DiscontinuousSpace(mesh)
        self.V_space = ContinuousSpace(mesh)
        self._cache: dict[str, object] = {}

    def _get(self, name, build):
        if name not in self._cache:
            self._cache[name] = build()
        return self._cache[name]

    @property
    def c1(self) -> float:
        return float(self.kp[4])

    @property
    def Et(self) -> float:
        """E'/(4 pi), the factor of the integrated-by-parts hypersingular kernel."""
        return float(self.kp[7])

    # --------------------------------------------------------------- operators
    @property
    def V(self) -> np.ndarray:
        """Single layer (1.4), W_hp^2 x W_hp^2, symmetric positive definite."""
        return self._get("V", lambda: assemble(single_layer_kernel, _logc(self.c1), self.kp,
                                               self.W_space, self.W_space, d=2,
                                               symmetric=True))

    @property
    def K(self) -> np.ndarray:
        """Double layer (1.4), test W_hp^2, trial V_hp^2."""
        return self._get("K", lambda: assemble(double_layer_kernel, NO_LOG, self.kp,
                                               self.W_space, self.V_space, d=2))

    @property
    def K_adj(self) -> np.ndarray:
        """Adjoint double layer K' = K^T (V_hp^2 x W_hp^2)."""
        return self.K.T

    @property
    def T(self):
        """Sparse W_hp^2 coefficients of d/ds of V_hp^2 functions (per component)."""
        return self._get("T", lambda: _kron2(self.V_space.derivative_matrix(self.W_space)))

    @property
    def M(self):
        """Sparse mass matrix, test W_hp^2, trial V_hp^2."""
        return self._get("M", lambda: _kron2(self.V_space.mass_matrix(self.W_space)))

    @property
    def Vt(self) -> np.ndarray:
        """Single-layer-type matrix of the hypersingular kernel Vt on W_hp^2."""
        return self._get("Vt", lambda: assemble(hypersingular_kernel, _logc(self.Et), self.kp,
                                                self.W_space, self.W_space, d=2,
                                                symmetric=True))

    @property
    def W(self) -> np.ndarray:
        """Hypersingular operator, V_hp^2 x V_hp^2: <W U, U'> = <Vt dU/ds, dU'/ds>."""
        def build():
            T = self.T
            W = T.T @ (T.T @ self.Vt.T).T
            return 0.5 * (W + W.T)
        return self._get("W", build)

    @property
    def B(self) -> np.ndarray:
        """K + M/2 (test W_hp^2, trial V_hp^2): right-hand side of V Psi = B U."""
        return self._get("B", lambda: self.K + 0.5 * self.M.toarray())

    @property
    def V_cho(self):
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
        """(2 n_W, 2): the total-force functionals, m[:, c] . Psi = int Psi_c ds."""
        def build():
            m1 = np.asarray(self.V_space.mass_matrix(self.W_space).sum(axis=1)).ravel()
            return np.kron(m1[:, None], np.eye(2))
        return self._get("m", build)

    @property
    def S_hat(self) -> np.ndarray:
        """Discrete Steklov-Poincare operator W + B^T V^{-1} B (Section 1.4), symmetric;
        with ``zero_force`` restricted to zero-total-force tractions (scale invariant)."""
        def build():
            c, lower = self.V_cho
            Y = sla.solve_triangular(c, self.B, lower=lower)
            S = self.W + Y.T @ Y
            if self.zero_force:
                Z = sla.solve_triangular(c, self.m, lower=lower)
                YZ = Y.T @ Z
                S -= YZ @ np.linalg.solve(Z.T @ Z, YZ.T)
            return 0.5 * (S + S.T)
        return self._get("S_hat", build)

    def Psi(self, U) -> np.ndarray:
        """Discrete traction Psi = V^{-1} (K + M/2) U in W_hp^2 (Section 1.4), with zero
        total force if ``zero_force``."""
        psi = sla.cho_solve(self.V_cho, self.B @ np.asarray(U))
        if self.zero_force:
            Wm = self._get("w_eq", lambda: sla.cho_solve(self.V_cho, self.m))
            psi = psi - Wm @ np.linalg.solve(self.m.T @ Wm, self.m.T @ psi)
        return psi

    # --------------------------------------------------------------- post-processing
    def representation(self, points, U, psi) -> np.ndarray:
        """Somigliana's identity (1.2) with f = 0 at interior points, shape (n, 2):
        u(x) = int G(x,y) psi(y) ds_y - int (T_{n_y} G(x,y)^T) U(y) ds_y,
        ``U`` in V_hp^2, ``psi`` in W_hp^2 (interleaved)."""
        pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, dtype=float)))
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
        U = np.asarray(U, dtype=float).reshape(-1, 2)
        psi = np.asarray(psi, dtype=float).reshape(-1, 2)
        if U.shape[0] != self.V_space.ndof or psi.shape[0] != self.W_space.ndof:
            raise ValueError("U must have 2 * V_space.ndof and psi 2 * W_space.ndof entries")
        u = evaluate_potential(_pot_single, self.kp, 2, pts, self.W_space, psi)
        u -= evaluate_potential(_pot_double, self.kp, 2, pts, self.V_space, U)
        return u


def local_blocks(mesh: BoundaryMesh, i: int, j: int, E: float, nu: float,
                 plane: str = "strain", scale: float = 1.0) -> dict:
    """Local Galerkin blocks (interleaved components) of test element i and trial element
    j at their degrees: V (Legendre^2 x Legendre^2), K (Legendre^2 x GLL^2) and
    W = T_i^T Vt_ij T_j (GLL^2 x GLL^2).  For tests."""
    lam, mu = lame_constants(E, nu, plane)
    kp = kernel_params(lam, mu, scale)
    V = local_block(single_layer_kernel, _logc(kp[4]), kp, mesh, i, j, 0, 0, d=2)
    K = local_block(double_layer_kernel, NO_LOG, kp, mesh, i, j, 0, 1, d=2)
    Vt = local_block(hypersingular_kernel, _logc(kp[7]), kp, mesh, i, j, 0, 0, d=2)
    Ts = []
    for e in (i, j):
        p = int(mesh.degrees[e])
        single = BoundaryMesh.polygon([(0, 0), (1, 0), (0, 1)], n=1, p=p)
        Vs = ContinuousSpace(single)
        T = Vs.derivative_matrix(DiscontinuousSpace(single)).toarray()
        Tl = T[:p][:, Vs.elem_dofs[0, :p + 1]] * (single.lengths[0] / mesh.lengths[e])
        Ts.append(np.kron(Tl, np.eye(2)))
    W = Ts[0].T @ Vt @ Ts[1]
    return {"V": V, "K": K, "W": W, "Vt": Vt}
