"""Solvers that act on a problem's residual, tangent and projection and know nothing of
which problem it is (DESIGN.md): :class:`SolverInfo` and the one backward-error rule,
Newton with a line search (:func:`newton`), the one load path (:func:`load_path`: commit on
convergence, cut and retry on failure) and the fixed-point iteration (:func:`fixed_point`)
of :mod:`.nonlinear`."""

from .nonlinear import (BACKWARD_TOL, Iterate, LineSearch, LoadStep, NewtonProblem,
                        SingularStep, SolverInfo, fixed_point, load_path, newton)

__all__ = ["BACKWARD_TOL", "Iterate", "LineSearch", "LoadStep", "NewtonProblem",
           "SingularStep", "SolverInfo", "fixed_point", "load_path", "newton"]
