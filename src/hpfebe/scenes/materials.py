"""The thesis's material data: the one home of E = 266926 and friends.

Chapters 3 and 4 use one elastic material for every body, E = 266926 and nu = 0.29 in
plane strain (the plane settled in Chapter 3), Coulomb friction mu_f = 0.1 where friction
is on, and in the elastoplastic examples of Sections 4.2.7 and 4.4 the J2 data
sigma_Y = 4.0 with hardening modulus H = 450.0.
"""

from __future__ import annotations

from dataclasses import dataclass

E = 266926.0
NU = 0.29
PLANE = "strain"
MU_F = 0.1
SIGMA_Y = 4.0
H = 450.0


@dataclass(frozen=True)
class FrictionalContactScene:
    """The material and friction data shared by the contact scenes of Chapters 3-4:
    E = 266926, nu = 0.29 (plane strain, settled in Chapter 3), Coulomb mu_f = 0.1."""

    E: float = E
    nu: float = NU
    plane: str = PLANE
    mu_f: float = MU_F
