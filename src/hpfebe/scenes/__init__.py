"""The thesis's scenes: geometries, loads and material data of its examples, built from
the core (bodies, contact problems); experiments and tests import them.

* :mod:`.materials` - the material data of every Chapter 3-4 scene (E = 266926, nu = 0.29,
  mu_f = 0.1, sigma_Y = 4, H = 450).
* :mod:`.stamping` - the stamping examples of Section 4.2.7 (FE or BE stamp on an
  elastoplastic FE or BE work piece, one touch of incremental loading).

The other thesis scenes (``contact.mortar.model_problem``, ``mortar_fe.section44_scene``,
``coupling.examples``, ``contact.limits.square_body``) move here in a later step.
"""

from .stamping import (STAMP_KINDS, ContactSettings, Snapshot, StepRecord, TouchResult,
                       be_work_piece, curve_difference, element_areas, field_difference,
                       lift_schedule, plastic_zone, stamp_body, stamp_interior, touch,
                       touch_be, work_piece, zone_mismatch)

__all__ = ["STAMP_KINDS", "ContactSettings", "Snapshot", "StepRecord", "TouchResult",
           "be_work_piece", "curve_difference", "element_areas", "field_difference",
           "lift_schedule", "plastic_zone", "stamp_body", "stamp_interior", "touch",
           "touch_be", "work_piece", "zone_mismatch"]
