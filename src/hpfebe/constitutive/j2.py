"""Small-strain J2 flow theory with mixed isotropic/kinematic linear hardening (thesis
Section 4.2.2, (4.21)-(4.22); discrete form and return map Section 4.2.6, (4.38)-(4.43);
Simo & Hughes, Computational Inelasticity, Box 3.1-3.2).

    sigma = C : (eps - eps_p),   C = kappa 1 x 1 + 2 mu (I - 1/3 1 x 1)            (4.23)
    eta = dev sigma - beta,   f(sigma, alpha, beta) = ||eta|| - sqrt(2/3) K(alpha)   (4.21)
    eps_p' = gamma n,  beta' = gamma 2/3 H'(alpha) n,  alpha' = gamma sqrt(2/3),  n = eta/||eta||
    K(alpha) = sigma_Y + theta H alpha,   H'(alpha) = (1 - theta) H,  theta in [0, 1] (4.22)

theta = 1: purely isotropic, theta = 0: purely kinematic (linear Prager) hardening.

Backward Euler (radial return, (4.38)-(4.41)) from the *committed* state
(eps_p_n, alpha_n, beta_n) to a total strain eps:

    s_trial = 2 mu (dev eps - eps_p_n),   eta_trial = s_trial - beta_n
    f_trial = ||eta_trial|| - sqrt(2/3) (sigma_Y + theta H alpha_n)
    f_trial <= 0: elastic;  otherwise  dgamma = f_trial / (2 mu + 2/3 H)     (4.41, linear)
    n = eta_trial / ||eta_trial||,  eps_p = eps_p_n + dgamma n,  alpha = alpha_n + sqrt(2/3) dgamma,
    beta = beta_n + 2/3 (1 - theta) H dgamma n,  sigma = kappa tr(eps) 1 + s_trial - 2 mu dgamma n

Tangents (all 3 x 3 x 3 x 3, minor- and major-symmetric):

* ``"algorithmic"`` (consistent, the derivative of the return map, (4.42)-(4.43); Simo-Hughes
  (3.3.13)):  C_alg = kappa 1 x 1 + 2 mu theta_1 (I - 1/3 1 x 1) - 2 mu theta_bar n x n,
  theta_1 = 1 - 2 mu dgamma / ||eta_trial||,  theta_bar = 1 / (1 + H / (3 mu)) - (1 - theta_1);
  Newton with it converges quadratically.
* ``"continuum"``: the elastoplastic moduli C^ep of Section 4.2.2 (thesis after (4.22)),
  theta_1 = 1, theta_bar = 1 / (1 + (K' + H') / (3 mu)) = 1 / (1 + H / (3 mu)); Newton with it
  converges only linearly once dgamma > 0 (the thesis's Table 4.3 iteration counts).

Plane strain: the strain has eps_33 = 0, but the stress, the plastic strain and the back
stress are full 3 x 3 tensors (the out-of-plane plastic strain eps_p_33 is not zero).

All functions work on N points at once: tensors (N, 3, 3), scalars (N,); no loops over
points.  :func:`radial_return_point` is the same radial return at one point for numba
kernels (tensors as 9-vectors, row-major), which the FE body's element loop calls
(:mod:`hpfebe.fem.plastic_body`); it gives the numbers of :func:`return_map` to round-off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from ..checks import array, choice, integer, real
from .materials import lame_constants

SQ23 = math.sqrt(2.0 / 3.0)
TANGENTS = ("algorithmic", "continuum")

_I3 = np.eye(3)
#: symmetric fourth-order identity I_ijkl = 1/2 (d_ik d_jl + d_il d_jk)
I_SYM = 0.5 * (np.einsum("ik,jl->ijkl", _I3, _I3) + np.einsum("il,jk->ijkl", _I3, _I3))
#: 1 x 1
ONE_ONE = np.einsum("ij,kl->ijkl", _I3, _I3)
#: deviatoric projector I - 1/3 1 x 1
P_DEV = I_SYM - ONE_ONE / 3.0


def dev(t: np.ndarray) -> np.ndarray:
    """Deviatoric part of tensors (..., 3, 3)."""
    tr = np.trace(t, axis1=-2, axis2=-1)
    return t - tr[..., None, None] * _I3 / 3.0


def tensor_norm(t: np.ndarray) -> np.ndarray:
    """||t|| = (t : t)^(1/2) of tensors (..., 3, 3)."""
    return np.sqrt(np.einsum("...ij,...ij->...", t, t))


def embed_plane(eps2: np.ndarray) -> np.ndarray:
    """Plane strain: (..., 2, 2) in-plane strains -> (..., 3, 3) with eps_i3 = 0."""
    eps2 = np.asarray(eps2, dtype=float)
    out = np.zeros(eps2.shape[:-2] + (3, 3))
    out[..., :2, :2] = eps2
    return out


@dataclass(frozen=True)
class J2Material:
    """Isotropic elasticity (E, nu; the 3D Lame constants = plane strain) and J2 plasticity
    with linear mixed hardening: yield stress ``sigma_Y`` > 0, hardening modulus ``H`` >= 0
    (H-bar of (4.22)), isotropic share ``theta`` in [0, 1]."""

    E: float
    nu: float
    sigma_Y: float
    H: float
    theta: float = 1.0

    def __post_init__(self):
        # numbers of any real kind (np.float32, a 0-d array) are stored as floats
        object.__setattr__(self, "E", real("E (Young's modulus)", self.E, positive=True))
        object.__setattr__(self, "nu", real("nu (Poisson ratio)", self.nu))
        lame_constants(self.E, self.nu, "strain")       # validates E and nu
        for name, bounds in (("sigma_Y (yield stress)", dict(positive=True)),
                             ("H (hardening modulus)", dict(nonnegative=True)),
                             ("theta (isotropic share of hardening)", dict(lo=0.0, hi=1.0))):
            attr = name.split()[0]
            object.__setattr__(self, attr, real(name, getattr(self, attr), **bounds))

    @property
    def lam(self) -> float:
        return lame_constants(self.E, self.nu, "strain")[0]

    @property
    def mu(self) -> float:
        return lame_constants(self.E, self.nu, "strain")[1]

    @property
    def stress_floor(self) -> float:
        """min(sigma_Y, 1e-3 E), the stress scale of the absolute floors of stopping
        tests (a yield-level stress; capped at the stress of a 0.1 % strain, so that a
        material that does not yield in the small-strain range - sigma_Y = 4e12, an
        elastic check - does not get a floor above every force of the problem, which
        let Newton accept its start)."""
        return min(self.sigma_Y, 1e-3 * self.E)

    @property
    def kappa(self) -> float:
        """Bulk modulus kappa = lambda + 2 mu / 3."""
        return self.lam + 2.0 * self.mu / 3.0

    def elastic_tangent(self) -> np.ndarray:
        """C = kappa 1 x 1 + 2 mu (I - 1/3 1 x 1), (3, 3, 3, 3)."""
        return self.kappa * ONE_ONE + 2.0 * self.mu * P_DEV

    def yield_function(self, sigma, alpha, beta) -> np.ndarray:
        """f = ||dev sigma - beta|| - sqrt(2/3) K(alpha)  (4.21)."""
        return tensor_norm(dev(sigma) - beta) - SQ23 * (self.sigma_Y + self.theta * self.H
                                                        * np.asarray(alpha))


@dataclass
class J2State:
    """History at N points: plastic strain ``eps_p`` (N, 3, 3), equivalent plastic strain
    ``alpha`` (N,), back stress ``beta`` (N, 3, 3)."""

    eps_p: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray

    @classmethod
    def zeros(cls, n: int) -> "J2State":
        n = integer("n (number of points)", n, lo=0)
        return cls(np.zeros((n, 3, 3)), np.zeros(n), np.zeros((n, 3, 3)))

    def copy(self) -> "J2State":
        return J2State(self.eps_p.copy(), self.alpha.copy(), self.beta.copy())

    @property
    def n(self) -> int:
        return self.alpha.shape[0]


@dataclass
class ReturnMap:
    """Result of :func:`return_map` at N points: stress (N, 3, 3), the trial-updated
    state, the tangent (N, 3, 3, 3, 3) (None if not asked for), dgamma (N,), the plastic
    flag (N,), the trial yield function value (N,), and the flow direction and trial
    norm from which :func:`consistent_tangent` computes the tangent later (at a subset
    of the points)."""

    sigma: np.ndarray
    state: J2State
    tangent: np.ndarray | None
    dgamma: np.ndarray
    plastic: np.ndarray
    f_trial: np.ndarray
    normal: np.ndarray | None = None      # n = eta_trial / ||eta_trial|| (N, 3, 3)
    eta_norm: np.ndarray | None = None    # ||eta_trial||, 1 where it is 0 (N,)


def return_map(mat: J2Material, eps: np.ndarray, committed: J2State,
               tangent: str | None = "algorithmic") -> ReturnMap:
    """Radial return (4.38)-(4.41) from the committed state to the total strains ``eps``
    (N, 3, 3) (or (N, 2, 2), embedded as plane strain); a pure function of its inputs.
    ``tangent``: "algorithmic" (consistent), "continuum" (C^ep of Section 4.2.2) or None."""
    choice("tangent", tangent, TANGENTS + (None,))
    eps = array("eps (total strains)", eps, finite=False)   # a NaN iterate: the solver's
    if eps.ndim == 3 and eps.shape[1:] == (2, 2):
        eps = embed_plane(eps)
    if eps.ndim != 3 or eps.shape[1:] != (3, 3):
        raise ValueError(f"eps must have shape (N, 3, 3) or (N, 2, 2), got {eps.shape}")
    if eps.shape[0] != committed.n:
        raise ValueError(f"eps has {eps.shape[0]} points, the state {committed.n}")
    mu, kappa, H, th = mat.mu, mat.kappa, mat.H, mat.theta
    tr = np.trace(eps, axis1=1, axis2=2)
    s_trial = 2.0 * mu * (dev(eps) - committed.eps_p)
    eta = s_trial - committed.beta
    eta_norm = tensor_norm(eta)
    f_trial = eta_norm - SQ23 * (mat.sigma_Y + th * H * committed.alpha)
    plastic = f_trial > 0.0
    dgamma = np.where(plastic, f_trial / (2.0 * mu + 2.0 / 3.0 * H), 0.0)
    safe = np.where(eta_norm > 0.0, eta_norm, 1.0)
    n = eta / safe[:, None, None]
    dg = dgamma[:, None, None]
    state = J2State(committed.eps_p + dg * n, committed.alpha + SQ23 * dgamma,
                    committed.beta + (2.0 / 3.0) * (1.0 - th) * H * dg * n)
    sigma = kappa * tr[:, None, None] * _I3 + s_trial - 2.0 * mu * dg * n
    rm = ReturnMap(sigma, state, None, dgamma, plastic, f_trial, n, safe)
    if tangent is not None:
        rm.tangent = consistent_tangent(mat, rm, tangent)
    return rm


def consistent_tangent(mat: J2Material, rm: ReturnMap, tangent: str = "algorithmic",
                       points: np.ndarray | None = None) -> np.ndarray:
    """The tangent (M, 3, 3, 3, 3) of the return map ``rm`` (module doc: "algorithmic"
    (4.42)-(4.43) or "continuum") at ``points`` (indices; None = all N points), from its
    flow direction and trial norm; pointwise, so a subset gives the same numbers as the
    full set.  At an elastic point it is the elastic tangent C, bit for bit."""
    choice("tangent", tangent, TANGENTS)
    if rm.normal is None or rm.eta_norm is None:
        raise ValueError("rm must come from return_map (flow direction and trial norm)")
    sel = slice(None) if points is None else np.asarray(points, dtype=np.int64)
    n, safe, dgamma, plastic = rm.normal[sel], rm.eta_norm[sel], rm.dgamma[sel], \
        rm.plastic[sel]
    mu, kappa, H = mat.mu, mat.kappa, mat.H
    if tangent == "algorithmic":
        theta1 = 1.0 - 2.0 * mu * dgamma / safe
    else:
        theta1 = np.ones_like(dgamma)
    theta_bar = np.where(plastic, 1.0 / (1.0 + H / (3.0 * mu)) - (1.0 - theta1), 0.0)
    theta1 = np.where(plastic, theta1, 1.0)
    return (kappa * ONE_ONE[None] + 2.0 * mu * theta1[:, None, None, None, None] * P_DEV[None]
            - 2.0 * mu * theta_bar[:, None, None, None, None]
            * np.einsum("nij,nkl->nijkl", n, n))


@numba.njit(cache=True)
def radial_return_point(eps, ep, alpha, beta, mu, kappa, H, theta, sigma_Y,
                        sigma, ep_new, beta_new, normal):
    """The radial return (4.38)-(4.41) at one point (tensors as 9-vectors, row-major):
    from the committed (``ep``, ``alpha``, ``beta``) to the total strain ``eps``; writes
    the stress ``sigma``, the updated ``ep_new``, ``beta_new`` and the flow direction
    ``normal`` n = eta_trial / ||eta_trial||; returns (alpha_new, dgamma, f_trial,
    ||eta_trial|| or 1 where it is 0) - the numbers of :func:`return_map` at the point."""
    tr = eps[0] + eps[4] + eps[8]
    nrm2 = 0.0
    for a in range(9):
        d = eps[a] - tr / 3.0 if a % 4 == 0 else eps[a]
        s = 2.0 * mu * (d - ep[a])
        sigma[a] = s                          # s_trial until the update below
        normal[a] = s - beta[a]               # eta_trial
        nrm2 += normal[a] * normal[a]
    norm = math.sqrt(nrm2)
    f = norm - SQ23 * (sigma_Y + theta * H * alpha)
    dg = f / (2.0 * mu + 2.0 / 3.0 * H) if f > 0.0 else 0.0
    safe = norm if norm > 0.0 else 1.0
    hk = (2.0 / 3.0) * (1.0 - theta) * H
    for a in range(9):
        n = normal[a] / safe
        normal[a] = n
        ep_new[a] = ep[a] + dg * n
        beta_new[a] = beta[a] + hk * dg * n
        sigma[a] = (kappa * tr if a % 4 == 0 else 0.0) + sigma[a] - 2.0 * mu * dg * n
    return alpha + SQ23 * dg, dg, f, safe


@numba.njit(cache=True)
def tangent_factors(dgamma, safe, plastic, mu, H, algorithmic):
    """(theta_1, theta_bar) of the tangent at one point (module doc): C = kappa 1 x 1 +
    2 mu theta_1 (I - 1/3 1 x 1) - 2 mu theta_bar n x n; (1, 0) at an elastic point."""
    if not plastic:
        return 1.0, 0.0
    theta1 = 1.0 - 2.0 * mu * dgamma / safe if algorithmic else 1.0
    return theta1, 1.0 / (1.0 + H / (3.0 * mu)) - (1.0 - theta1)
