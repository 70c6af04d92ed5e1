"""The thesis's scenes: geometries, loads and material data of its examples, built from
the core (bodies, contact problems); experiments and tests import them.

* :mod:`.materials` - the material data of every Chapter 3-4 scene (E = 266926, nu = 0.29,
  mu_f = 0.1, sigma_Y = 4, H = 450).
* :mod:`.stamping` - the stamping examples of Section 4.2.7 (FE or BE stamp on an
  elastoplastic FE or BE work piece, one touch of incremental loading).
* :mod:`.section44` - Section 4.4: the FE mortar scene, the FE/BE penalty scene, the
  readings of Table 4.2's stopping rule, the fields of both compared on common points.
* :mod:`.interface` - the model problems of Section 2.2.5 (Examples 1, 2) and the
  lambda_Nit sweeps of Chapter 2.
* :mod:`.penalty` - the benchmark body of Section 3.2.5 (Table 3.1, Theorem 3.2.6, the
  stress test) and its sweeps; :mod:`.adaptive_bem` - adaptive h-BEM with Coulomb
  friction of Section 3.3.5 (Figures 3.2-3.9).  These three are exported as modules
  (``from hpfebe.scenes import penalty``).

* :mod:`.mortar` - the model problem of Section 4.3.4 (Table 4.1, Figures 4.17-4.20): its
  meshes, initial gap, the mortar contact problem on them, the hp-adaptive run.
"""

from . import adaptive_bem, adaptive_fefe, interface, penalty, plasticity, plasticity_fields
from .materials import E, H, MU_F, NU, PLANE, SIGMA_Y, FrictionalContactScene
from .stamping import (STAMP_KINDS, STAMP_SOLVER, Snapshot, StampContact, StepRecord,
                       TouchResult, TouchSteps,
                       be_work_piece, curve_difference, element_areas, field_difference,
                       lift_schedule, plastic_zone, stamp_body, stamp_interior, touch,
                       touch_be, work_piece, zone_mismatch)
from .mortar import (ModelProblem, adaptive_model_problem, contact_from_meshes, model_gap,
                     model_meshes, model_problem, mortar_contact_state)
from .section44 import (READINGS, STAMP, WORK, X_POINT, DtNReadings, dtn_settings,
                        field_differences, mortar_bodies, penalty_bodies, penalty_scene,
                        penetration_l2, section44_scene, tangential_share)

__all__ = ["STAMP_KINDS", "STAMP_SOLVER", "Snapshot", "StampContact", "StepRecord",
           "TouchResult", "TouchSteps",
           "be_work_piece", "curve_difference", "element_areas", "field_difference",
           "lift_schedule", "plastic_zone", "stamp_body", "stamp_interior", "touch",
           "touch_be", "work_piece", "zone_mismatch"]
__all__ += ["E", "H", "MU_F", "NU", "PLANE", "SIGMA_Y", "FrictionalContactScene"]
__all__ += ["READINGS", "STAMP", "WORK", "X_POINT", "DtNReadings", "dtn_settings",
            "field_differences", "mortar_bodies", "penalty_bodies", "penalty_scene",
            "penetration_l2", "section44_scene", "tangential_share"]
__all__ += ["adaptive_bem", "adaptive_fefe", "interface", "penalty",
            "plasticity", "plasticity_fields"]    # scenes exported as modules
__all__ += ["ModelProblem", "adaptive_model_problem", "contact_from_meshes", "model_gap",
            "model_meshes", "model_problem", "mortar_contact_state"]
from . import (mortar, mortar_readings, mortar_runs, section44,  # noqa: E402
               section44_fields, section44_figures, section44_readings, section44_runs)
__all__ += ["mortar", "mortar_readings", "mortar_runs", "section44", "section44_fields",
            "section44_figures", "section44_readings",
            "section44_runs"]    # scenes exported as modules
from . import bem_hertz, bem_scaling  # noqa: E402
__all__ += ["bem_hertz", "bem_scaling"]    # issue 27: compressed BEM, as modules
from . import adaptive_bem_readings, interface_readings, penalty_readings  # noqa: E402
__all__ += ["adaptive_bem_readings", "interface_readings", "penalty_readings"]  # Ch. 2-3
