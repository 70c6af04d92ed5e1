"""Penalty contact with Tresca or Coulomb friction of one body against a rigid obstacle
(Sections 3.3.1 and 4.2.1-4.2.5; Algorithm 4.1 for one body): the rigid-obstacle case
of :class:`hpfebe.contact.two_body.TwoBodyContact`.

Discrete problem (cf. (3.95), with the tangential law (4.19)-(4.20) of
:mod:`hpfebe.constitutive.laws` in place of the smoothed (3.86)): find U in V_hp^2 with U = 0
on Gamma_D such that

    <S_hat U, v> + int_{Gamma_C} p_n v_n ds + int_{Gamma_C} t_t v_t ds = L(v)

for all such v; n the outward normal, t the element tangent (n = (t_y, -t_x)), g the gap
(admissible U_n <= g; g = -d for a rigid plane pushed into the body by d), w the
prescribed tangential motion of the obstacle (``obstacle_slip``); sign conventions and
the return map in :mod:`hpfebe.constitutive.laws` (penetration U_n - g, slip relative to w).

Integration: Gauss-Legendre with ``nq`` points (default p_I + 1) on every element of
Gamma_C; the contact state (pressure, stick/slip, slip history) lives at these points,
so the residual is piecewise linear in U and the Newton matrix its exact generalised
derivative.

Newton (:func:`hpfebe.solvers.newton` in the load path of Algorithm 4.1, load factor
lambda_j = j / N scaling the load and the obstacle motion; the gap is geometry):
backtracking line search on the energy (Tresca; the equation is its gradient) or on
||R||_2 (Coulomb, no potential); max-norm residual, stopping when
max|R| <= tol * max(|L_j|, |R(0)|, |S_hat U|) on the free dofs.  Each step starts from
the bonded predictor (every point in contact and sticking) when it lowers the merit:
from U = 0 the first Newton step sees full slip, and for stiff penalties the
semismooth iteration then crawls through the stick band of width eps_t s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..bodies.body import RigidObstacle, against_obstacle
from ..checks import InputTypeError, boolean, choice, integer, real
from .result import ContactResult
from .settings import ContactSettings
from .two_body import TwoBodyContact

LAWS = ("tresca", "coulomb")
FrictionResult = ContactResult


@dataclass(frozen=True)
class FrictionSettings:
    """The law and the solver settings of :func:`solve_friction` (validated on creation).

    Attributes
    ----------
    eps_n, eps_t : float
        Penalty parameters (> 0) of the normal and the tangential law.
    friction : {"tresca", "coulomb"}
        Tresca (give the bound ``F`` >= 0, float or callable F(x)) or Coulomb (give the
        coefficient ``mu_f`` >= 0).
    F, mu_f : float or callable, float
        The Tresca bound or the Coulomb coefficient (the other one stays None).
    load_steps : int
        N equal increments of the load and the obstacle motion (the slip history is
        carried from step to step).
    max_iter, tol : int, float
        Newton limit and relative tolerance per load step (module doc).
    nq : int or None
        Gauss points per contact element (None: p_I + 1).
    predictor : bool
        Start each step from the bonded predictor when it lowers the merit.
    contact_label, dirichlet_label : str
        The labels of Gamma_C and Gamma_D on the mesh.
    """

    eps_n: float
    eps_t: float
    friction: str = "tresca"
    F: object = None
    mu_f: float | None = None
    load_steps: int = 1
    max_iter: int = 50
    tol: float = 1e-10
    nq: int | None = None
    predictor: bool = True
    contact_label: str = "C"
    dirichlet_label: str = "D"

    def __post_init__(self):
        checked = dict(eps_n=real("eps_n", self.eps_n, positive=True),
                       eps_t=real("eps_t", self.eps_t, positive=True))
        law, bound = _law(self.friction, self.F, self.mu_f)
        checked.update(friction=law,
                       max_iter=integer("max_iter", self.max_iter, lo=1),
                       load_steps=integer("load_steps", self.load_steps, lo=1),
                       tol=real("tol", self.tol, positive=True),
                       nq=integer("nq", self.nq, lo=1, allow_none=True),
                       predictor=boolean("predictor", self.predictor), **bound)
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    @property
    def bound(self) -> dict:
        """The friction bound as :class:`TwoBodyContact` takes it (F= or mu_f=)."""
        return dict(F=self.F) if self.friction == "tresca" else dict(mu_f=self.mu_f)


def _law(friction, F, mu_f):
    if not isinstance(friction, str):
        raise InputTypeError(f"friction must be one of {LAWS}, got {friction!r}")
    law = choice("friction", friction, LAWS, fold_case=True)
    if law == "tresca":
        if F is None:
            raise ValueError("F (Tresca friction bound) is required for friction='tresca'")
        if mu_f is not None:
            raise ValueError("mu_f is the Coulomb coefficient; Tresca takes F")
        return law, dict(F=F)
    if mu_f is None:
        raise ValueError("mu_f (Coulomb coefficient) is required for friction='coulomb'")
    if F is not None:
        raise ValueError("F is the Tresca bound; Coulomb takes mu_f")
    return law, dict(mu_f=real("mu_f", mu_f, nonnegative=True))


def solve_friction(bem, gap, settings: FrictionSettings, obstacle_slip=None, load=None,
                   S=None, initial=None) -> ContactResult:
    """Frictional penalty contact of a :class:`~hpfebe.bem.LameBEM` body with a rigid obstacle.

    Parameters
    ----------
    bem : LameBEM
        The body (its mesh carries the labels of ``settings``).
    gap : float or callable
        g(x) on Gamma_C (constraint U_n <= g).
    settings : FrictionSettings
        The law (penalty parameters, Tresca or Coulomb) and the Newton settings.
    obstacle_slip : float or callable, optional
        Tangential motion w of the obstacle, reached at the last load step.
    load : ndarray, optional
        Interleaved vector L(v) on V_hp^2, likewise ramped.
    S : ndarray, optional
        S_hat to reuse (default ``bem.S_hat``).
    initial : ContactResult, optional
        A converged result of the same body, law and points to continue from (U, slip,
        load and obstacle motion ramped from its final values).

    Returns
    -------
    ContactResult
        U, the contact state at the Gauss points, the Newton history per load step.
    """
    if not isinstance(settings, FrictionSettings):
        raise InputTypeError(f"settings must be a FrictionSettings, got {settings!r}")
    st = settings
    body, fixed, f = against_obstacle(bem, S, st.contact_label, st.dirichlet_label, load)
    pr = TwoBodyContact(body, RigidObstacle(gap, obstacle_slip), st.contact_label,
                        eps_n=st.eps_n, eps_t=st.eps_t, nq=st.nq, **st.bound)
    return pr.solve(f, fixed, None, np.arange(1, st.load_steps + 1) / st.load_steps,
                    ContactSettings(rtol=st.tol, max_iter=st.max_iter, line_search=True,
                                    norm="max", predictor=st.predictor,
                                    merit="energy" if st.friction == "tresca"
                                    else "residual"),
                    initial=initial)
