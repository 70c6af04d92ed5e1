"""Constitutive laws, the bottom layer under every body and contact treatment.

* :mod:`.laws` - the pointwise contact laws of the penalty method (normal penalty,
  Tresca / Coulomb return map, their linearisations; one sign convention), Sections 3.2,
  3.3.1, 4.2.1, 4.2.5.

* :mod:`.materials` - elastic material data: Lame constants, plane strain / plane stress,
  Hooke's law.
* :mod:`.j2` - J2 (von Mises) plasticity with linear hardening: the radial return map
  and its consistent tangent (Section 4.2.6).
"""

from .materials import PLANES, lame_constants, linear_stress, plane_modulus
from .j2 import J2Material, J2State, consistent_tangent, return_map
from .laws import (OPEN, SLIP, STATE_NAMES, STICK, LawState, normal_penalty,
                   penalty_friction, tresca_energy, updated_slip)

__all__ = ["PLANES", "lame_constants", "linear_stress", "plane_modulus", "J2Material",
           "J2State", "consistent_tangent", "return_map", "OPEN", "SLIP", "STICK",
           "STATE_NAMES", "LawState", "normal_penalty", "penalty_friction", "tresca_energy",
           "updated_slip"]
