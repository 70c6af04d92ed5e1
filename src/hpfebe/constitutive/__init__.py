"""Constitutive laws, the bottom layer under every body and contact treatment.

* :mod:`.laws` - the pointwise contact laws of the penalty method (normal penalty,
  Tresca / Coulomb return map, their linearisations; one sign convention), Sections 3.2,
  3.3.1, 4.2.1, 4.2.5.

Elastic material data (:mod:`hpfebe.materials`) and the J2 return map
(:mod:`hpfebe.fem.plasticity`) move here in a later step of the layout (DESIGN.md).
"""

from .laws import (OPEN, SLIP, STATE_NAMES, STICK, LawState, normal_penalty,
                   penalty_friction, tresca_energy, updated_slip)

__all__ = ["OPEN", "SLIP", "STICK", "STATE_NAMES", "LawState", "normal_penalty",
           "penalty_friction", "tresca_energy", "updated_slip"]
