"""Material data of 2D linear elasticity: the one home of the Lame constants, the plane
strain / plane stress reduction and Hooke's law (used by bem, fem and adaptivity).

    lambda = E nu / ((1 + nu)(1 - 2 nu)),   mu = E / (2 (1 + nu))          (plane strain)
    lambda* = 2 lambda mu / (lambda + 2 mu)                                  (plane stress)
    sigma(eps) = 2 mu eps + lambda tr(eps) I
    E' = 4 mu (lambda + mu) / (lambda + 2 mu)   (= E / (1 - nu^2) in plane strain, E in
                                                  plane stress)
"""

from __future__ import annotations

import numpy as np

from ..checks import choice, real

PLANES = ("strain", "stress")


def lame_constants(E: float, nu: float, plane: str = "strain") -> tuple[float, float]:
    """(lambda, mu) of the 2D model: plane strain, or plane stress with lambda*."""
    E = real("E (Young's modulus)", E, positive=True)
    nu = real("nu (Poisson ratio)", nu, lo=-1.0, hi=0.5, lo_open=True, hi_open=True)
    choice("plane", plane, PLANES)
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = E / (2.0 * (1.0 + nu))
    if plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def plane_modulus(E: float, nu: float, plane: str = "strain") -> float:
    """E' = 4 mu (lambda + mu) / (lambda + 2 mu): E / (1 - nu^2) (strain), E (stress)."""
    lam, mu = lame_constants(E, nu, plane)
    return 4.0 * mu * (lam + mu) / (lam + 2.0 * mu)


def linear_stress(eps: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Hooke's law sigma = 2 mu eps + lambda tr(eps) I for strains of shape (2, 2, ...)."""
    eps = np.asarray(eps, dtype=float)
    tr = eps[0, 0] + eps[1, 1]
    sig = 2.0 * mu * eps
    sig[0, 0] = sig[0, 0] + lam * tr
    sig[1, 1] = sig[1, 1] + lam * tr
    return sig
