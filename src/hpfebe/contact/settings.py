"""How Algorithm 4.1 solves a penalty contact problem (:class:`ContactSettings`): the
Newton stopping test, line search and predictor, the step cuts of the load path, and the
linear solver of the Newton systems.  One frozen, validated object that
:meth:`hpfebe.contact.two_body.TwoBodyContact.solve` and the stamping scenes
(:mod:`hpfebe.scenes.stamping`) take."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import boolean, choice, integer, real, tolerance
from ..solvers import LineSearch

#: merit functions of the line search: ||R||_2, or the potential of a potential law
MERITS = ("residual", "energy")
#: column orderings of the sparse LU (:meth:`hpfebe.contact.loading.LoadSteps._factor`):
#: SuperLU's default COLAMD, or minimum degree on A^T + A with symmetric-mode
#: (diagonal-preferring) threshold pivoting - about 1.7x faster on the stamping systems
#: (Q1 work piece, FE or BE stamp, 8e3 dofs), but with other round-off in every Newton step
LU_ORDERINGS = ("COLAMD", "MMD_AT_PLUS_A")
#: Newton solvers of a system with an FE body (:meth:`LoadSteps._solve`): "lu" a sparse
#: LU of every Newton matrix; "woodbury" one factorisation of the bodies' stiffness per
#: problem and the contact terms by the Sherman-Morrison-Woodbury formula (linear bodies)
LINEAR_SOLVERS = ("lu", "woodbury")
NORMS = ("l2", "max")


@dataclass(frozen=True)
class ContactSettings:
    """The solver settings of Algorithm 4.1 (:meth:`TwoBodyContact.solve`).

    Newton stops when ||R_free|| <= atol + rtol * scale, ``norm`` "l2" or "max", scale =
    the largest of the load, the body force and the contact force of the iterate
    (max-norm over the free dofs; not relative to R^(0), which grows like 1/eps and
    would accept wrong contact sets for stiff penalties): the backward-error rule of
    :mod:`hpfebe.solvers.info`, scale-free with the default ``atol = 0`` (moduli, loads
    and prescribed displacements scaled together give the same iterations and
    decisions).  ``atol`` (a force) is a floor for residuals at round-off of the data
    forces (a stamp lifted off: :func:`hpfebe.scenes.stamping.reference_force` sets it
    to rtol x a force of the scene); it must scale with the problem, and
    :meth:`TwoBodyContact.solve` refuses an ``atol`` above rtol x the data force
    (:func:`hpfebe.contact.two_body.data_force`, the residual of the prescribed data), which
    would accept the start or any iterate within that floor as converged; at most ``max_iter``
    iterations per load step; a failed step is halved and retried from the last
    converged state at most ``max_cuts`` times.  ``roundoff_stop``: a Newton update at
    round-off level ends the step, converged only if the backward error is small
    (:func:`hpfebe.solvers.newton`).  ``line_search``: Armijo on ``merit``
    ("residual": ||R||_2, down to ``min_step``; "energy": the potential, for
    frictionless and Tresca contact, 30 halvings); cycling of the contact state is then
    detected.  ``predictor``: start each step from the bonded solution (every point in
    contact and sticking) when it lowers the merit.  ``lu_ordering``: the column
    ordering of the sparse LU of a system with an FE body (:data:`LU_ORDERINGS`:
    "COLAMD", SuperLU's default, or "MMD_AT_PLUS_A", faster, other round-off).
    ``linear_solver`` (:data:`LINEAR_SOLVERS`): "lu", a sparse LU of every Newton
    matrix, or for linear bodies with an FE body "woodbury", one factorisation of the
    bodies' stiffness for the whole load path and the contact terms by the
    Sherman-Morrison-Woodbury formula on the active points
    (:class:`hpfebe.contact.woodbury.WoodburySolver`: the same Newton steps up to
    round-off; measured 7x less CPU on 83,076 dofs with 640 contact points).
    ``secant_start``: the first Newton step from the bonded predictor (an elastic
    solution: plastic points far past yield) with the secant stiffness of the
    elastoplastic FE bodies (:meth:`hpfebe.fem.plastic_body.ElastoPlasticFE.tangent_matrix`)
    instead of their algorithmic tangent (measured, Example 1 of Section 4.2.7, h = 0.05:
    the touches' first increments 24 and 31 -> 15 and 17 Newton iterations, the same
    solutions to the tolerance).
    ``ls_refine``: the ``refine`` of the residual line search
    (:class:`hpfebe.solvers.LineSearch`: an accepted step below 1 halved further while
    ||R|| decreases, at most this many times; 0 = plain Armijo backtracking)."""

    rtol: float = 1e-10
    atol: float = 0.0
    max_iter: int = 30
    line_search: bool = False
    min_step: float = 2.0 ** -12
    max_cuts: int = 0
    norm: str = "l2"
    merit: str = "residual"
    predictor: bool = False
    roundoff_stop: bool = False
    lu_ordering: str = "COLAMD"
    linear_solver: str = "lu"
    ls_refine: int = 0
    secant_start: bool = False

    def __post_init__(self):
        # every field checked by hpfebe.checks and stored as a Python float/int/bool
        # ('no' is not True, 1.5 is not a count, np.float32 is a number)
        def put(name, value):
            object.__setattr__(self, name, value)

        # 0 < rtol < 1: a purely absolute test (rtol = 0, atol > 0) is not scale-free,
        # and rtol >= 1 accepts a residual as large as every force of the iterate
        put("rtol", tolerance("rtol", self.rtol))
        put("atol", real("atol", self.atol, nonnegative=True))
        put("max_iter", integer("max_iter", self.max_iter, lo=1))
        put("max_cuts", integer("max_cuts", self.max_cuts, lo=0))
        put("ls_refine", integer("ls_refine", self.ls_refine, lo=0))
        put("min_step", real("min_step", self.min_step, lo=0.0, hi=1.0, lo_open=True))
        for name, allowed in (("norm", NORMS), ("merit", MERITS),
                              ("lu_ordering", LU_ORDERINGS),
                              ("linear_solver", LINEAR_SOLVERS)):
            choice(name, getattr(self, name), allowed)
        for name in ("line_search", "predictor", "roundoff_stop", "secant_start"):
            put(name, boolean(name, getattr(self, name)))

    def check_floor(self, data_force: float, lam: float = 1.0) -> None:
        """ValueError unless ``atol`` is at most rtol x ``data_force`` (the residual of
        the prescribed data at the load factor ``lam``,
        :func:`hpfebe.contact.two_body.data_force`): above it the stopping test
        ||R|| <= atol + rtol scale accepts residuals beyond rtol relative to every force
        of the problem (the start itself once atol >= ||R(U_D)||), and "converged"
        means nothing.  Scale-free: the decision is the same when atol and the problem's
        forces are scaled together."""
        cap = self.rtol * real("data_force", data_force, nonnegative=True)
        if not self.atol <= cap:
            raise ValueError(
                f"atol must be at most rtol x the data force of this problem "
                f"({self.rtol:g} x {data_force:.3e} = {cap:.3e}, the residual of the "
                f"prescribed data at load factor {lam:g}), got {self.atol!r}: a larger "
                "absolute floor accepts residuals beyond rtol relative to every force of "
                "the problem; use atol = 0 (the scale-free default) or a floor that "
                "scales with the problem's forces")

    def line_search_rule(self) -> LineSearch:
        """The Armijo rule of :func:`hpfebe.solvers.newton` for ``merit``: on the energy
        the default 30 halvings; on ||R||_2 no slack, down to ``min_step`` and the last
        trial step taken."""
        if self.merit == "energy":
            return LineSearch(enabled=self.line_search)
        return LineSearch(slack=0.0, max_halvings=int(round(-np.log2(self.min_step))),
                          accept_last=True, enabled=self.line_search,
                          refine=self.ls_refine)

    def newton_options(self) -> dict:
        """The keywords of :func:`hpfebe.solvers.newton` (the predictor is the
        problem's: :meth:`hpfebe.contact.loading.LoadSteps.newton_options`)."""
        return dict(tol=float(self.rtol), atol=float(self.atol),
                    max_iter=int(self.max_iter), line_search=self.line_search_rule(),
                    norm=np.inf if self.norm == "max" else 2,
                    roundoff_stop=self.roundoff_stop)
