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
* :mod:`.ch4_work_precision` - beyond the thesis (issue 28): Section 4.4's stamp force
  on a mesh family, mortar and penalty, against the wall time, with its extrapolated
  reference (exported as a module).

Every name is imported on first use (PEP 562, as in :mod:`hpfebe`): a job imports only
the scenes it runs (issue 28: importing all of them cost a job about 1.2-3.4 s CPU, e.g.
``adaptive_bem`` pulls in scikit-fem and the adaptivity for a Chapter 2 job that needs
only :mod:`.interface`).  ``from hpfebe.scenes import X`` works as before.
"""

from importlib import import_module

#: scenes exported as modules (``from hpfebe.scenes import penalty``)
_MODULES = ("adaptive_bem", "adaptive_fefe", "interface", "penalty", "plasticity",
            "plasticity_fields",
            "mortar", "mortar_readings", "mortar_runs", "section44", "section44_fields",
            "section44_figures", "section44_readings", "section44_runs",
            "bem_scaling",            # issue 27: dense against compressed BEM
            "bem_hertz",              # issue 27: Hertz contact on the compressed operators
            "ch4_work_precision",     # issue 28: Chapter 4's work-precision figure
            "adaptive_bem_readings", "interface_readings", "penalty_readings")  # Ch. 2-3

#: public name -> the scene module that defines it
_API = {name: module for module, names in {
    "materials": ("E", "H", "MU_F", "NU", "PLANE", "SIGMA_Y", "FrictionalContactScene"),
    "stamping": ("STAMP_KINDS", "STAMP_SOLVER", "Snapshot", "StampContact", "StepRecord",
                 "TouchResult", "TouchSteps",
                 "be_work_piece", "curve_difference", "element_areas", "field_difference",
                 "lift_schedule", "plastic_zone", "stamp_body", "stamp_interior", "touch",
                 "touch_be", "work_piece", "zone_mismatch"),
    "mortar": ("ModelProblem", "adaptive_model_problem", "contact_from_meshes", "model_gap",
               "model_meshes", "model_problem", "mortar_contact_state"),
    "section44": ("READINGS", "STAMP", "WORK", "X_POINT", "DtNReadings", "dtn_settings",
                  "field_differences", "mortar_bodies", "penalty_bodies", "penalty_scene",
                  "penetration_l2", "section44_scene", "tangential_share"),
}.items() for name in names}

__all__ = [*_API, *_MODULES]


def __getattr__(name: str):
    if name in _MODULES:
        value = import_module(f"{__name__}.{name}")
    elif name in _API:
        value = getattr(import_module(f"{__name__}.{_API[name]}"), name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value          # later look-ups skip __getattr__
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
