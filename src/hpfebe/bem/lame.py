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

Hypersingular operator by integration by parts (no hypersingular quadrature).  In 2D the
Lame hypersingular operator is a composition of tangential derivatives and a single-layer
type potential (Hsiao & Wendland, "Boundary Integral Equations", Springer 2008,
Lemma 2.3.1; Steinbach, "Numerical Approximation Methods for Elliptic Boundary Value
Problems", Springer 2008, chapter on linear elastostatics, for the 3D analogue):

    <W u, v> = int int (dv/ds)(x)^T  Vt(x - y)  (du/ds)(y) ds_y ds_x,
    Vt(r)    = E' / (4 pi) { -log(|r| / R) I + r r^T / |r|^2 },
    E'       = 4 mu (lambda + mu) / (lambda + 2 mu)   (= E / (1 - nu^2) in plane strain),

i.e. 4 mu^2 times the fundamental solution with (3 - 4 nu) replaced by 1.  How the two
coefficients are pinned down (and checked in tests/bem/test_lame.py): the log coefficient by
the symbol of W on a straight line (E'|xi|/4, half the symbol of the half-plane
Dirichlet-to-Neumann map); the r r^T coefficient by the rigid rotation, whose tangential
derivative is -n and which must lie in ker W (it does to 1e-15 only with this
coefficient); the whole operator by the Calderon identity W u = (1/2 - K') t for Kelvin
fields (converging exponentially in p) and by the exact patch test of S_hat.
Galerkin: W = T^T Vt T with T the exact derivative matrix of :mod:`hpfebe.spaces` (per
component) and Vt assembled on W_hp by the same :func:`assemble` as V.  The constant R is
irrelevant here (tangential derivatives have zero mean on closed curves).

On meshes with all degrees 1, V, Vt and K have closed forms (:mod:`hpfebe.bem.lowest_order_lame`,
formulas (Q1), (Q2), (L1), (L2): K by the Guenter-derivative representation
K = K_Laplace I + (V_Laplace I - 2 mu V)(I J) T, J = [[0, 1], [-1, 0]]), used unless
``closed_form=False``; the general quadrature path of :func:`assemble` is the reference
(they agree to 1e-13 of the largest entry, tests/bem/test_bem_lowest_order_lame.py).

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
import scipy.sparse as sp

from ..checks import boolean
from ..constitutive.materials import lame_constants, linear_stress
from ..geometry import BoundaryMesh
from ..spaces import ContinuousSpace, DiscontinuousSpace
from .assembly import assemble, local_block, sandwich
from .hmatrix.dispatch import Compressible
from .kernels import (KP_C1, KP_C1_C2, KP_C1_LOG_R, KP_C2, KP_ET, KP_ET_LOG_R, KP_LAMBDA,
                      KP_LAME_SIZE, KP_MU, LAME_DL, LAME_HS, LAME_SL)
from .laplace import P1_W_DIRECT_MAX
from .lowest_order import applies as _closed_form_applies
from .lowest_order_lame import lame_p1, lame_p1_w
from .operators import BoundaryOperators, mesh_diameter
from .potentials import (POT_LAME_DL, POT_LAME_DL_GRAD, POT_LAME_SL, POT_LAME_SL_GRAD,
                         density, evaluate_potential, evaluation_points)

# The Lame kernels (regular parts) live in kernels.py as LAME_SL, LAME_DL, LAME_HS: the
# assemblers take kernel ids and the parameter array of kernel_params, read by the
# named indices KP_* of kernels.py.


def kernel_params(lam: float, mu: float, scale: float) -> np.ndarray:
    """Parameter array kp shared by all Lame kernels (indices KP_* of
    :mod:`hpfebe.bem.kernels`): c1 log R, c1 c2, lambda, mu, c1, c2, Et log R, Et with
    Et = E'/(4 pi) and R = ``scale``."""
    c1 = (lam + 3.0 * mu) / (4.0 * math.pi * mu * (lam + 2.0 * mu))
    c2 = (lam + mu) / (lam + 3.0 * mu)
    Et = 4.0 * mu * (lam + mu) / (lam + 2.0 * mu) / (4.0 * math.pi)
    lR = math.log(scale)
    kp = np.empty(KP_LAME_SIZE)
    kp[[KP_C1_LOG_R, KP_C1_C2, KP_LAMBDA, KP_MU, KP_C1, KP_C2, KP_ET_LOG_R, KP_ET]] = (
        c1 * lR, c1 * c2, lam, mu, c1, c2, Et * lR, Et)
    return kp


TINY = 1e-250   # below this c1 or E'/(4 pi) has lost its digits (subnormal products)


def _checked_kernel_params(E: float, nu: float, lam: float, mu: float, scale: float):
    """:func:`kernel_params`, refusing a Young's modulus whose kernel constants overflow
    or underflow in double precision (c1 ~ 1/E, E' ~ E): otherwise V would come out zero
    or infinite and the Cholesky factorisation fail with a misleading message."""
    try:
        kp = kernel_params(lam, mu, scale)
    except (ZeroDivisionError, OverflowError):
        kp = np.full(KP_LAME_SIZE, np.nan)
    c1, Et = kp[KP_C1], kp[KP_ET]
    if not (np.all(np.isfinite(kp)) and TINY < c1 < 1 / TINY and TINY < Et < 1 / TINY):
        raise ValueError(
            f"E = {E!r} (nu = {nu!r}) is out of the range double precision can handle: "
            f"the kernel constants overflow/underflow (c1 = {c1!r}, E'/(4 pi) = {Et!r}); "
            "express E in other units so that it is moderate")
    return kp


def _logc(c: float) -> np.ndarray:
    return np.array([-c, 0.0, 0.0, -c])


NO_LOG = np.zeros(4)


def _kron2(A):
    """Scalar matrix -> interleaved 2-component matrix (A kron I_2)."""
    if sp.issparse(A):
        return sp.kron(A, sp.identity(2), format="csr")
    return np.kron(A, np.eye(2))


class LameBEM(Compressible, BoundaryOperators):
    """Galerkin boundary element operators of 2D linear elasticity on one boundary mesh.

    Parameters
    ----------
    mesh : BoundaryMesh
        closed curves, outward normals
    E, nu : float
        Young's modulus (> 0) and Poisson ratio (in (-1, 0.5))
    plane : {"strain", "stress"}
        plane strain (default) or plane stress
    scale : float, optional
        the length scale R of the fundamental solution (default: 2 x the diameter)
    zero_force : bool
        constrain Psi to zero total force (scale-invariant S_hat, see the module doc;
        default True)
    closed_form : bool
        on a mesh with all degrees 1, V, K and Vt by the closed forms of
        :mod:`hpfebe.bem.lowest_order_lame` (one pass; W = T^T Vt T without forming T up
        to P1_W_DIRECT_MAX elements): equal to the quadrature path to round-off;
        ``False`` forces the general quadrature path (default True)
    compression : {None, "hmatrix"}
        None (dense matrices, default) or "hmatrix": V, K, K_adj, W, B and S_hat become
        LinearOperators of H-matrices (ACA+, :mod:`hpfebe.bem.hmatrix`; W compressed
        directly from the Vt kernel), Psi a preconditioned CG on the compressed V;
        ``hmatrix_info()`` reports storage, ranks, times, achieved errors
    tol : float
        the relative accuracy of the compressed operators, in (0, 1) (default 1e-8)

    Notes
    -----
    Matrices (interleaved components, assembled on first use, cached): ``V`` (W_hp^2 x
    W_hp^2), ``K`` (test W_hp^2, trial V_hp^2), ``K_adj``, ``W`` (V_hp^2 x V_hp^2), ``M``,
    ``B = K + M/2``, ``S_hat``; ``Psi(U)`` the discrete traction.  Post-processing at
    interior points: ``representation`` (Somigliana), ``displacement_gradient``,
    ``stress``.
    """

    d = 2
    _intermediates = ("Vt",)     # only W's input: S_hat releases it (issue 27, memory)

    def __init__(self, mesh: BoundaryMesh, E: float, nu: float, plane: str = "strain",
                 scale: float | None = None, zero_force: bool = True,
                 closed_form: bool = True, compression: str | None = None,
                 tol: float = 1e-8):
        self.lam, self.mu = lame_constants(E, nu, plane)       # checks E, nu, plane
        self.E, self.nu, self.plane = float(E), float(nu), plane
        if isinstance(mesh, BoundaryMesh) and scale is None:
            scale = 2.0 * mesh_diameter(mesh)
        super().__init__(mesh, scale, constrained=zero_force)
        self.zero_force = self.constrained
        self.kp = _checked_kernel_params(E, nu, self.lam, self.mu, self.scale)
        # p = 1 everywhere: V, K and Vt by the closed forms, all in one pass
        self.closed_form = boolean("closed_form", closed_form) and _closed_form_applies(mesh)
        self._set_compression(compression, tol)

    def hmatrix_kernels(self):
        """(kernel id, log coefficient) of V, K and of W's kernel Vt."""
        return ((LAME_SL, _logc(self.c1)), (LAME_DL, NO_LOG), (LAME_HS, _logc(self.Et)))

    def _closed(self, key: str) -> None:
        """One pass of the closed forms fills the cache's V, K and Vt (those not there)."""
        if self.closed_form and key not in self._cache:
            V, K, Vt = lame_p1(self.W_space, self.V_space, self.kp, self.scale)
            for k, A in (("V", V), ("K", K), ("Vt", Vt)):
                self._cache.setdefault(k, A)

    @property
    def c1(self) -> float:
        return float(self.kp[KP_C1])

    @property
    def Et(self) -> float:
        """E'/(4 pi), the factor of the integrated-by-parts hypersingular kernel."""
        return float(self.kp[KP_ET])

    # --------------------------------------------------------------- operators
    @property
    def V(self) -> np.ndarray:
        """Single layer (1.4), W_hp^2 x W_hp^2, symmetric positive definite."""
        if self.hm is not None:
            return self.hm.V
        self._closed("V")
        return self._get("V", lambda: assemble(LAME_SL, _logc(self.c1), self.kp,
                                               self.W_space, self.W_space, d=2,
                                               symmetric=True))

    @property
    def K(self) -> np.ndarray:
        """Double layer (1.4), test W_hp^2, trial V_hp^2."""
        if self.hm is not None:
            return self.hm.K
        self._closed("K")
        return self._get("K", lambda: assemble(LAME_DL, NO_LOG, self.kp,
                                               self.W_space, self.V_space, d=2))

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
        self._closed("Vt")
        return self._get("Vt", lambda: assemble(LAME_HS, _logc(self.Et), self.kp,
                                                self.W_space, self.W_space, d=2,
                                                symmetric=True))

    @property
    def W(self) -> np.ndarray:
        """Hypersingular operator, V_hp^2 x V_hp^2, with
        <W U, U'> = <Vt dU/ds, dU'/ds>."""
        if self.hm is not None:
            return self.hm.W
        if self.closed_form and self.mesh.n_elements <= P1_W_DIRECT_MAX:
            # p = 1, small mesh: T^T Vt T without forming T (as LaplaceBEM.W)
            return self._get("W", lambda: lame_p1_w(self.Vt, self.W_space, self.V_space))
        return self._get("W", lambda: sandwich(self.T, self.Vt))

    @property
    def m(self) -> np.ndarray:
        """The total-force functionals, shape (2 n_W, 2), with
        m[:, c] . Psi = int Psi_c ds."""
        def build():
            m1 = np.asarray(self.V_space.mass_matrix(self.W_space).sum(axis=1)).ravel()
            return np.kron(m1[:, None], np.eye(2))
        return self._get("m", build)

    @property
    def constraints(self) -> np.ndarray:
        return self.m

    # --------------------------------------------------------------- post-processing
    def representation(self, points, U, psi) -> np.ndarray:
        """Somigliana's identity (1.2) with f = 0 at interior points, shape (n, 2):
        u(x) = int G(x,y) psi(y) ds_y - int (T_{n_y} G(x,y)^T) U(y) ds_y,
        ``U`` in V_hp^2, ``psi`` in W_hp^2 (interleaved)."""
        pts, U, psi = self._check_cauchy(points, U, psi)
        u = evaluate_potential(POT_LAME_SL, self.kp, 2, pts, self.W_space, psi, name="psi")
        u -= evaluate_potential(POT_LAME_DL, self.kp, 2, pts, self.V_space, U, name="U")
        return u

    def _check_cauchy(self, points, U, psi):
        """(points (n, 2), U (ndof_V, 2), psi (ndof_W, 2)), checked (lengths named)."""
        return (evaluation_points(points), density("U", U, self.V_space, 2),
                density("psi", psi, self.W_space, 2))

    def displacement_gradient(self, points, U, psi) -> np.ndarray:
        """du_i/dx_m at interior points, shape (n, 2, 2): the x-gradient of Somigliana's
        identity (1.2) (kernels differentiated analytically, hpfebe.bem.potentials)."""
        pts, U, psi = self._check_cauchy(points, U, psi)
        g = evaluate_potential(POT_LAME_SL_GRAD, self.kp, 2, pts, self.W_space, psi, nout=4)
        g -= evaluate_potential(POT_LAME_DL_GRAD, self.kp, 2, pts, self.V_space, U, nout=4)
        return g.reshape(-1, 2, 2)

    def stress(self, points, U, psi) -> np.ndarray:
        """Stress sigma(u) = lambda tr eps I + 2 mu eps at interior points, (n, 2, 2)
        (lambda = lambda* in plane stress)."""
        g = self.displacement_gradient(points, U, psi)
        eps = np.moveaxis(0.5 * (g + np.swapaxes(g, 1, 2)), 0, -1)   # (2, 2, n)
        return np.moveaxis(linear_stress(eps, self.lam, self.mu), -1, 0)


def local_blocks(mesh: BoundaryMesh, i: int, j: int, E: float, nu: float,
                 plane: str = "strain", scale: float = 1.0) -> dict:
    """Local Galerkin blocks (interleaved components) of test element i and trial element
    j at their degrees: V (Legendre^2 x Legendre^2), K (Legendre^2 x GLL^2) and
    W = T_i^T Vt_ij T_j (GLL^2 x GLL^2).  For tests."""
    lam, mu = lame_constants(E, nu, plane)
    kp = kernel_params(lam, mu, scale)
    V = local_block(LAME_SL, _logc(kp[KP_C1]), kp, mesh, i, j, 0, 0, d=2)
    K = local_block(LAME_DL, NO_LOG, kp, mesh, i, j, 0, 1, d=2)
    Vt = local_block(LAME_HS, _logc(kp[KP_ET]), kp, mesh, i, j, 0, 0, d=2)
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
