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

import numpy as np

from ..bodies.body import RigidObstacle, against_obstacle
from ..constitutive.laws import OPEN, SLIP, STATE_NAMES, STICK  # noqa: F401  (re-exported)
from ..checks import InputTypeError, boolean, choice, integer, real
from .result import ContactResult
from .settings import ContactSettings
from .two_body import TwoBodyContact

LAWS = ("tresca", "coulomb")
FrictionResult = ContactResult


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


def solve_friction(bem, eps_n: float, eps_t: float, gap, friction: str = "tresca",
                   F=None, mu_f=None, obstacle_slip=None, load=None, load_steps: int = 1,
                   contact_label: str = "C", dirichlet_label: str = "D",
                   max_iter: int = 50, tol: float = 1e-10, S=None,
                   nq: int | None = None, initial=None,
                   predictor: bool = True) -> ContactResult:
    """Frictional penalty contact of a :class:`LameBEM` body with a rigid obstacle.

    bem : LameBEM (its mesh carries the labels); eps_n, eps_t : penalty parameters (> 0)
    gap : float or callable g(x) on Gamma_C (constraint U_n <= g)
    friction : "tresca" (give F >= 0, float or callable) or "coulomb" (give mu_f >= 0)
    obstacle_slip : tangential motion w of the obstacle (float or callable), reached at
        the last load step; load : interleaved vector L(v) on V_hp^2, likewise
    load_steps : N equal increments; the slip history is carried from step to step
    max_iter, tol : Newton limit and relative tolerance per step (module doc)
    S : S_hat to reuse (default ``bem.S_hat``); nq : Gauss points per contact element
    predictor : start each step from the bonded predictor when it lowers the merit
    initial : a converged result of the same body, law and points to continue from
        (U, slip, load and obstacle motion ramped from its final values)
    """
    eps_n = real("eps_n", eps_n, positive=True)
    eps_t = real("eps_t", eps_t, positive=True)
    law, bound = _law(friction, F, mu_f)
    max_iter = integer("max_iter", max_iter, lo=1)
    load_steps = integer("load_steps", load_steps, lo=1)
    tol = real("tol", tol, positive=True)
    nq = integer("nq", nq, lo=1, allow_none=True)
    predictor = boolean("predictor", predictor)
    body, fixed, f = against_obstacle(bem, S, contact_label, dirichlet_label, load)
    pr = TwoBodyContact(body, RigidObstacle(gap, obstacle_slip), contact_label,
                        eps_n=eps_n, eps_t=eps_t, nq=nq, **bound)
    return pr.solve(f, fixed, None, np.arange(1, load_steps + 1) / load_steps,
                    ContactSettings(rtol=tol, max_iter=max_iter, line_search=True,
                                    norm="max", predictor=predictor,
                                    merit="energy" if law == "tresca" else "residual"),
                    initial=initial)
