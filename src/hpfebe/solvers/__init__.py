"""Solvers that act on a problem's residual, tangent and projection and know nothing of
which problem it is (DESIGN.md): :class:`SolverInfo` and the one backward-error rule,
Newton with a line search (:func:`newton`), the one load path (:func:`load_path`: commit on
convergence, cut and retry on failure) and the fixed-point iteration (:func:`fixed_point`)
(:mod:`.info`, :mod:`.newton`, :mod:`.load_path`, :mod:`.fixed_point`); for the mortar
contact problems of Section 4.3: Polyak's projected CG (:mod:`.pcg`), Uzawa for given
friction and for the global problem (Algorithms 4.4, 4.5, :mod:`.uzawa`), the
Dirichlet-to-Neumann algorithm with a per-iteration hook (Algorithm 4.3, :mod:`.dtn`) and
the monolithic semismooth Newton method (:mod:`.semismooth`), each returning SolverInfo."""

from .dtn import DtNProblem, DtNSettings, DtNState, dtn
from .fixed_point import fixed_point
from .info import BACKWARD_TOL, Iterate, NewtonProblem, SingularStep, SolverInfo
from .load_path import LoadStep, load_path
from .newton import LineSearch, newton
from .pcg import BoundQP, projected_cg
from .semismooth import SemismoothSettings, semismooth_contact
from .uzawa import GlobalUzawaSettings, UzawaSettings, global_uzawa, tresca_uzawa

__all__ = ["BACKWARD_TOL", "Iterate", "LineSearch", "LoadStep", "NewtonProblem",
           "SingularStep", "SolverInfo", "fixed_point", "load_path", "newton"]
__all__ += ["BoundQP", "DtNProblem", "DtNSettings", "DtNState", "GlobalUzawaSettings",
            "SemismoothSettings", "UzawaSettings", "dtn", "global_uzawa", "projected_cg",
            "semismooth_contact", "tresca_uzawa"]
