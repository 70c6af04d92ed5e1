"""Pointwise contact laws of the penalty method and their linearisations (Sections 3.2,
3.3.1, 4.2.1 and 4.2.5): the one place where the laws are written.

Sign convention (every solver of :mod:`hpfebe.contact` uses it):

* ``penetration`` d_n = -g_n >= 0 in contact (g_n the signed normal gap, (4.18)); for a
  body against a rigid obstacle with gap function g (admissible U_n <= g) it is U_n - g.
* ``p_n >= 0`` is the contact pressure, the negative of the thesis's P_n^eps
  ((3.46), (4.19)):  p_n = (1/eps_n) (d_n)_+.
* ``g_t`` is the relative tangential displacement along the contact tangent, ``slip`` the
  accumulated slip g_t^p of the last converged load step (the internal variable of
  Algorithm 4.1), ``t_t`` the friction traction with the sign of the elastic slip, the
  negative of P_t^eps (4.20): the traction on the body is -p_n n - t_t t.

Return map (backward Euler, Section 4.2.5), with s the slip bound:

    t_trial = (g_t - slip) / eps_t
    t_t     = t_trial               if |t_trial| <= s    (stick)
            = s sign(t_trial)       otherwise            (slip)
    s       = F (Tresca: on all of Gamma_C) or mu_f p_n (Coulomb: open points carry no
              traction),
    slip   <- g_t - eps_t t_t      after a converged step (:func:`updated_slip`).

A trial traction within the rounding of its own evaluation of the bound,
||t_trial| - s| <= 8 macheps ((|g_t| + |slip|) / eps_t + s), slips (the traction is
the same either way; only the derivative differs): at the start of a load step every
point that slipped in the last one lies there, its slip just committed, and rounding
decided its stick/slip state in the first Newton iterate and with it the Newton path
(measured on the adaptive FE/FE scene of Figures 4.13-4.16: 931 Newton iterations over
its 48 meshes, counts differing by up to 4 per mesh between two linear solvers; with
the rule 383, the same for both, every load step after the first one in one iteration).

The return map is :func:`tresca_return` (compiled, one point) and
:func:`friction_projection` (arrays): the penalty path applies it to t_trial, the mortar
path (Algorithms 4.4, 4.5: :mod:`hpfebe.solvers.uzawa`, :mod:`hpfebe.solvers.semismooth`)
to the Uzawa multiplier and the nodal friction traction, with the same sign convention
(the traction, or lambda, has the sign of the slip; :func:`normal_projection` the
positive part of the normal law).

Consistent linearisation (4.35), pointwise (generalised derivatives):

    d p_n = (1/eps_n) [d_n >= 0] d(d_n)                (sign(0) := 1, Remark 4.2.2)
    d t_t = (1/eps_t) d g_t                            (stick)
          = 0                                          (Tresca slip)
          = mu_f sign(t_trial) dp_n                    (Coulomb slip)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

OPEN, STICK, SLIP = 0, 1, 2
_EPS = float(np.finfo(float).eps)
STATE_NAMES = {OPEN: "open", STICK: "stick", SLIP: "slip"}


@dataclass
class LawState:
    """The law at the contact points: pressure p_n, friction traction t_t, the trial
    traction, the slip bound s, the state (OPEN / STICK / SLIP) and the derivatives
    dp_n = d p_n / d d_n, dt_t = d t_t / d g_t, dt_n = d t_t / d d_n."""

    p_n: np.ndarray
    t_t: np.ndarray
    trial: np.ndarray
    bound: np.ndarray
    state: np.ndarray
    dp_n: np.ndarray
    dt_t: np.ndarray
    dt_n: np.ndarray

    @property
    def key(self) -> bytes:
        """The contact pattern (state and direction of slip), for cycling detection."""
        return self.state.tobytes() + np.signbit(self.trial).tobytes()


def normal_penalty(penetration, eps_n: float, active=None):
    """(p_n, dp_n) = ((1/eps_n) (d_n)_+, [d_n >= 0] / eps_n); ``active`` masks points
    that can carry contact at all (default: every point)."""
    d = np.asarray(penetration, dtype=float)
    on = d >= 0.0
    if active is not None:
        on &= active
    return np.where(on, d, 0.0) / eps_n, on / eps_n


def penalty_friction(penetration, g_t, slip, eps_n: float, eps_t: float, mu_f=None,
                     F=None, active=None) -> LawState:
    """Normal penalty with the Tresca (``F``: bound, scalar or per point) or Coulomb
    (``mu_f``) return map; frictionless when both are None or mu_f == 0."""
    if F is not None and mu_f is not None:
        raise ValueError("give F (Tresca bound) or mu_f (Coulomb coefficient), not both")
    p_n, dp_n = normal_penalty(penetration, eps_n, active)
    in_contact = dp_n > 0
    trial = (np.asarray(g_t, dtype=float) - slip) / eps_t
    zero = np.zeros_like(p_n)
    if F is None and not mu_f:
        # frictionless: no tangential traction; points in contact slide freely
        state = np.where(in_contact, SLIP, OPEN).astype(np.int8)
        return LawState(p_n, zero, np.where(in_contact, trial, 0.0), zero, state, dp_n,
                        zero, zero)
    if F is not None:
        s = np.broadcast_to(np.asarray(F, dtype=float), p_n.shape)
        carries = np.ones(p_n.shape, bool) if active is None else np.asarray(active)
    else:
        s = mu_f * p_n
        carries = in_contact
    trial = np.where(carries, trial, 0.0)
    # on the bound to the rounding of (g_t - slip) / eps_t: slip (module doc)
    rnd = 8.0 * _EPS * ((np.abs(g_t) + np.abs(slip)) / eps_t + s)
    stick = carries & (np.abs(trial) <= s - rnd)
    slipping = carries & ~stick
    sg = np.sign(trial)
    t_t = np.where(carries, friction_projection(trial, s), 0.0)     # the return map
    dt_t = np.where(stick, 1.0 / eps_t, 0.0)
    dt_n = zero if F is not None else np.where(slipping, mu_f * sg * dp_n, 0.0)
    state = np.full(p_n.shape, OPEN, dtype=np.int8)
    state[stick] = STICK
    state[slipping] = SLIP
    return LawState(p_n, t_t, trial, np.array(s, dtype=float), state, dp_n, dt_t, dt_n)


@njit(cache=True)
def tresca_return(trial, bound):
    """The return map of the friction law at one point, compiled: t = trial if
    |trial| <= bound (stick), bound sign(trial) otherwise (slip); NaN propagates.  The
    mortar path applies it to the Uzawa multiplier (Algorithm 4.4, lambda_new =
    P_Lambda(lambda + rho F (U_t - Q_t)) = tresca_return(., 1), the sign of lambda that
    of the slip as t_t's) in :func:`hpfebe.solvers.uzawa.tresca_uzawa`; the same
    branches as :func:`penalty_friction`'s stick / slip cases."""
    if trial > bound:
        return bound
    if trial < -bound:
        return -bound
    return trial


def friction_projection(trial, bound) -> np.ndarray:
    """:func:`tresca_return` on arrays (numpy): the projection of a trial friction traction
    onto [-bound, bound] (Tresca: bound F; Coulomb: mu_f p_n), trial where |trial| <=
    bound (stick), bound sign(trial) otherwise (slip), as the penalty law
    (:func:`penalty_friction`), the global Uzawa (Algorithm 4.5, step 3) and the
    semismooth Newton method of the mortar path use it."""
    trial = np.asarray(trial, dtype=float)
    return np.where(np.abs(trial) <= bound, trial, bound * np.sign(trial))


def normal_projection(trial) -> np.ndarray:
    """The projection of a trial contact pressure onto p_n >= 0, max(0, trial) (Algorithm
    4.5, step 3, the positive part of the normal law)."""
    return np.maximum(0.0, trial)


def updated_slip(g_t, law: LawState, eps_t: float) -> np.ndarray:
    """Backward Euler update of the slip after a converged step: g_t - eps_t t_t (open
    points follow the relative motion: their t_t is 0)."""
    return np.asarray(g_t, dtype=float) - eps_t * law.t_t


def tresca_energy(law: LawState, eps_n: float, eps_t: float, F) -> np.ndarray:
    """Pointwise potential of the Tresca law: (1/(2 eps_n)) d_n,+^2 + F Huber_{eps_t F}
    (eps_t t_trial), whose derivative is (p_n, t_t) (Remark 4.2.1)."""
    z = eps_t * law.trial
    a = np.abs(z)
    lim = eps_t * np.asarray(F, dtype=float)
    hub = np.where(a <= lim, z ** 2 / (2 * eps_t), F * a - 0.5 * eps_t * np.square(F))
    return 0.5 * eps_n * law.p_n ** 2 + hub
