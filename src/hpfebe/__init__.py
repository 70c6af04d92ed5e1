"""hpfebe: hp finite element / boundary element methods for interface and contact
problems, and the reproduction of the thesis's experiments.

The curated public API (``__all__``), bottom layer first:

* meshes and spaces: :class:`BoundaryMesh`, :class:`FEDomain`, :class:`ContinuousSpace`,
  :class:`DiscontinuousSpace`
* boundary element operators: :class:`LaplaceBEM`, :class:`LameBEM`
* finite element bodies: :class:`PoissonFE`, :class:`ElasticBody`,
  :class:`ElastoPlasticFE`
* materials and laws: :func:`lame_constants`, :class:`J2Material`,
  :func:`penalty_friction`
* contact bodies: :class:`FEBody`, :class:`PlasticFEBody`, :class:`BEBody`,
  :class:`ElastoPlasticBE`, :class:`PlasticBEBody`, :class:`RigidObstacle`
* coupling and contact problems: :class:`NitscheFEBE`, :class:`TwoBodyContact`,
  :class:`MortarContact`, :class:`FEMortarContact`, :func:`solve_penalty`,
  :func:`solve_friction`
* solvers: :func:`newton`, :func:`load_path`, :class:`SolverInfo`; adaptivity:
  :func:`adapt`

Every subpackage's ``__init__`` exports its public names.  The names are imported on
first use (PEP 562): importing all of them costs about 0.2 s more than ``import hpfebe``
(numba-cached kernels, scikit-fem), which the CLI and most tests do not need.
"""

from importlib import import_module

from . import _numba_cache

__version__ = "0.1.0"

# before any kernel is defined: numba's cache keyed on every kernel source (a cached
# kernel keeps the machine code of the jitted functions of other files it calls)
_numba_cache.configure()

#: public name -> the module that defines it
_API = {
    "BoundaryMesh": "geometry", "FEDomain": "fem",
    "ContinuousSpace": "spaces", "DiscontinuousSpace": "spaces",
    "LaplaceBEM": "bem", "LameBEM": "bem",
    "PoissonFE": "fem", "ElasticBody": "fem", "ElastoPlasticFE": "fem",
    "lame_constants": "constitutive", "J2Material": "constitutive", "penalty_friction": "constitutive",
    "FEBody": "bodies", "PlasticFEBody": "bodies", "BEBody": "bodies",
    "ElastoPlasticBE": "bodies", "PlasticBEBody": "bodies", "RigidObstacle": "bodies",
    "NitscheFEBE": "coupling", "TwoBodyContact": "contact", "MortarContact": "contact",
    "FEMortarContact": "contact", "solve_penalty": "contact", "solve_friction": "contact",
    "newton": "solvers", "load_path": "solvers", "SolverInfo": "solvers",
    "adapt": "adaptivity",
}

__all__ = [*_API, "__version__"]


def __getattr__(name: str):
    try:
        module = _API[name]
    except KeyError:
        raise AttributeError(f"module 'hpfebe' has no attribute {name!r}") from None
    value = getattr(import_module(f"{__name__}.{module}"), name)
    globals()[name] = value          # later look-ups skip __getattr__
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
