"""Uzawa algorithms of the mortar contact problems (Section 4.3.3): Algorithm 4.4 for
given (Tresca) friction against an obstacle (:func:`tresca_uzawa`: the contact QP of
body 1 by Polyak's projected CG, :mod:`.pcg`, then the projection of the multiplier by
the friction law's return map, one compiled call per iteration) and Algorithm 4.5 for
the global problem with Tresca or Coulomb friction (:func:`global_uzawa`: the nodal
contact traction projected pointwise onto the admissible set).  Both act on what the
problem provides (the QP matrices, the linear response of the relative displacement) and
stop by :func:`hpfebe.solvers.fixed_point`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..checks import array, boolean, choice, integer, real, tolerance
from ..constitutive.laws import friction_projection, normal_projection, tresca_return
from .fixed_point import fixed_point, growth_reason
from .info import SolverInfo
from .pcg import BoundQP, _per_node, _polyak_core, pcg_info

FRICTIONS = ("coulomb", "tresca")


@dataclass(frozen=True)
class UzawaSettings:
    """Algorithm 4.4 (Uzawa for given friction, e.g. as step 4 of the DtN iteration):
    step ``rho`` (relative to rho_crit / 2 of Theorem 3.1.8 if ``relative``; the problem
    turns it into the nodal rho F of :func:`tresca_uzawa`), stopping rule
    ||lambda_m - lambda_m-1|| <= ``tol`` ||lambda_m||, at most ``max_iter`` iterations,
    the inner projected CG to ``cg_tol``."""

    rho: float = 1.0
    tol: float = 1e-6
    max_iter: int = 2000
    relative: bool = True
    cg_tol: float = 1e-11

    def __post_init__(self):
        _set(self, "rho", real("rho", self.rho, positive=True))
        for name in ("tol", "cg_tol"):
            _set(self, name, tolerance(name, getattr(self, name)))
        _set(self, "max_iter", integer("max_iter", self.max_iter, lo=1))
        _set(self, "relative", boolean("relative", self.relative))


def _set(settings, name: str, value) -> None:
    """Store the validated ``value`` of a field of a frozen settings dataclass (a
    numpy float as a Python float, ...)."""
    object.__setattr__(settings, name, value)


@njit(cache=True)
def _uzawa_step(A, b, Fw, rhoF, Qt, upper, lam, x, tol, max_iter, res, nA, lam_new):
    """One iteration of Algorithm 4.4 compiled (:func:`tresca_uzawa`; the same
    floating-point operations as its numpy formulation): the contact QP with the
    friction load, rhs = b - (0, F w lambda), by :func:`_polyak_core` from the start
    ``x`` (clipped to ``upper`` first, overwritten by the solution), then
    lambda_new = P_Lambda(lambda + rho F (U_t - Q_t)) into ``lam_new`` (the friction
    law's return map :func:`hpfebe.constitutive.laws.tresca_return` with bound 1 = clip
    to [-1, 1]).  ``Fw``, ``rhoF``: per node; ``nA``: :func:`_frobenius_bound` of A.
    Returns :func:`_polyak_core`'s (status, steps, n_residuals) and the size of the
    active set (x_i >= upper_i)."""
    nc = lam.size
    rhs = b.copy()
    for i in range(nc):
        rhs[nc + i] = rhs[nc + i] - Fw[i] * lam[i]
    for i in range(x.size):                   # np.minimum(x, upper) (NaN propagates)
        if not (x[i] <= upper[i] or x[i] != x[i]):
            x[i] = upper[i]
    status, steps, nres = _polyak_core(A, rhs, upper, x, tol, max_iter, res, nA)
    for i in range(nc):                       # the Tresca return map, bound 1
        lam_new[i] = tresca_return(lam[i] + rhoF[i] * (x[nc + i] - Qt[i]), 1.0)
    active = 0
    for i in range(x.size):
        if x[i] >= upper[i]:
            active += 1
    return status, steps, nres, active


# outcomes of _uzawa_loop
_CONVERGED, _MAX_ITER, _QP_FAILED, _NONFINITE, _GROWTH = range(5)
#: fixed_point's divergence factor (its default), the same rule in the compiled loop
DIVERGENCE = 1e6


@njit(cache=True)
def _uzawa_loop(A, b, Fw, rhoF, Qt, upper, lam, x, tol_cg, max_cg, res, nA, tol, max_iter,
                incs, counts):
    """Algorithm 4.4's iteration in one compiled call: :func:`_uzawa_step` until the
    stopping and divergence rules of :func:`hpfebe.solvers.fixed_point` (norm 2,
    min_iter 1, divergence :data:`DIVERGENCE`) end it, with the same floating-point
    operations (the increment's norm sqrt(d . d), as numpy's).  ``lam`` (in: lambda_0,
    out: the last accepted iterate), ``x`` (the QP start, out: the last QP's solution),
    ``incs[k - 1]`` the increments, ``counts``: (QP solves, CG steps, iterations, last
    QP's status, steps, n_residuals, active set size).  Returns an outcome code."""
    nc = lam.size
    lam_new = np.empty(nc)
    smallest = np.inf
    tiny = np.finfo(np.float64).tiny
    for k in range(1, max_iter + 1):
        status, steps, nres, active = _uzawa_step(A, b, Fw, rhoF, Qt, upper, lam, x,
                                                  tol_cg, max_cg, res, nA, lam_new)
        counts[0] += 1
        counts[1] += steps
        counts[2] = k
        counts[3], counts[4], counts[5], counts[6] = status, steps, nres, active
        if status != 1:              # a failed QP ends the iteration (lambda kept)
            return _QP_FAILED
        d = lam_new - lam
        inc = np.sqrt(np.dot(d, d))
        incs[k - 1] = inc
        if not np.isfinite(inc) or not np.all(np.isfinite(lam_new)):
            return _NONFINITE
        lam[:] = lam_new
        if inc <= tol * max(np.sqrt(np.dot(lam, lam)), tiny):
            return _CONVERGED
        if inc > DIVERGENCE * smallest:
            return _GROWTH
        smallest = min(smallest, inc)
    return _MAX_ITER


def tresca_uzawa(qp: BoundQP, Fw, rhoF, Qt, upper, lam0, x0=None,
                 settings: UzawaSettings = UzawaSettings()):
    """Algorithm 4.4 (Uzawa for given friction) on the contact QP ``qp`` of body 1 in the
    node frames (unknowns x = (U_n, U_t), nc nodes): for lambda_m solve

        min 1/2 x^T A x - (b - (0, F w lambda_m))^T x   subject to   x <= upper,

    then lambda_{m+1} = P_Lambda(lambda_m + rho F (U_t - Q_t)); stop when ||lambda_m -
    lambda_{m-1}|| <= tol ||lambda_m|| (:func:`fixed_point`; ``settings``: tol, max_iter,
    cg_tol, its rho already in ``rhoF``).  ``Fw``: the friction
    weights F w_j (or s_j w_j for a nodal bound s), ``rhoF``: rho F (or rho s_j),
    ``Qt``: the tangential obstacle, ``upper``: (g + Q_n, +inf), all per node.  The whole
    iteration is one compiled call (:func:`_uzawa_loop`: the QP and the projection per
    step, :func:`fixed_point`'s rules; Python's 60 us per step of the loop around one
    compiled step were two thirds of Table 4.1's 366k steps).
    Returns (x, lambda, info); x solves the QP of the returned lambda.  ``info.counts``:
    the QP solves and their CG steps in all; ``info.steps`` holds a QP's SolverInfo only
    where it failed (that ends the iteration) - one SolverInfo per iteration kept for
    hundreds of thousands of iterations cost a quarter of the run time in Python's
    garbage collector (measured on Table 4.1's capped cells)."""
    A, b, nA, res = qp.A, qp.b, qp.nA, qp.res
    nc = len(lam0)
    n, max_cg = b.size, res.size - 1
    if x0 is not None and np.shape(x0) != (n,):
        raise ValueError(f"x0 must have shape ({n},), got {np.shape(x0)}")
    args = (A, b, _per_node(Fw, nc), _per_node(rhoF, nc), _per_node(Qt, nc),
            _per_node(upper, n))
    tol = real("tol", settings.tol, positive=True)
    max_iter = integer("max_iter", settings.max_iter, lo=1)
    lam = np.array(array("lam0", lam0), dtype=float)
    x = np.zeros(n) if x0 is None else np.array(x0, dtype=float)
    incs, counts = np.empty(max_iter), np.zeros(7, np.int64)
    outcome = _uzawa_loop(*args, lam, x, float(settings.cg_tol), max_cg, res, nA, tol,
                          max_iter, incs, counts)
    k = int(counts[2])
    n_inc = k - (outcome == _QP_FAILED)
    info = SolverInfo(outcome == _CONVERGED, "max_iter", k, incs[:n_inc].tolist(),
                      counts=dict(qp_solves=int(counts[0]), cg_steps=int(counts[1])))
    if outcome == _CONVERGED:
        info.reason = "converged"
    elif outcome == _QP_FAILED:
        inner = pcg_info(int(counts[3]), int(counts[4]), int(counts[5]), res, int(counts[6]))
        info.steps.append(inner)
        info.reason = f"inner solve {k}: {inner.reason}"
    elif outcome == _NONFINITE:
        info.reason = f"diverged: non-finite iterate at iteration {k}"
    elif outcome == _GROWTH:
        info.reason = growth_reason(incs[k - 1], k, DIVERGENCE, float(np.min(incs[:k - 1])))
    x, qinfo = qp.solve(friction_rhs(b, Fw, lam), upper, x, settings.cg_tol)
    if not qinfo.converged and info.converged:
        info.converged, info.reason = False, f"final QP: {qinfo.reason}"
    return x, lam, info


def friction_rhs(b, Fw, lam) -> np.ndarray:
    """The right-hand side of the contact QP with the friction load: b - (0, F w lambda)."""
    rhs = b.copy()
    rhs[lam.size:] -= Fw * lam
    return rhs


@dataclass(frozen=True)
class GlobalUzawaSettings:
    """Algorithm 4.5: step ``rho`` (times rho_crit / 2 of the linear response if
    ``relative``), stopping tolerance and cap, the friction law ("coulomb" with the
    coefficient ``mu_f``, or "tresca" with the problem's bound F) and the growth factor
    of the divergence test."""

    rho: float = 1.0
    tol: float = 1e-6
    max_iter: int = 20000
    friction: str = "coulomb"
    mu_f: float = 0.1
    relative: bool = True
    divergence: float = 1e6

    def __post_init__(self):
        check_friction(self)
        _set(self, "tol", tolerance("tol", self.tol))
        for name in ("rho", "divergence"):
            _set(self, name, real(name, getattr(self, name), positive=True))
        _set(self, "max_iter", integer("max_iter", self.max_iter, lo=1))
        _set(self, "relative", boolean("relative", self.relative))


def check_friction(settings) -> None:
    """Validate (and store) ``settings.friction`` (a law of :data:`FRICTIONS`) and
    ``settings.mu_f`` >= 0 of a frozen settings dataclass."""
    _set(settings, "friction", choice("friction", settings.friction, FRICTIONS))
    _set(settings, "mu_f", real("mu_f", settings.mu_f, nonnegative=True))


def global_uzawa(response, frame, unframe, gap, F: float, step: float,
                 settings: GlobalUzawaSettings):
    """Algorithm 4.5 (Uzawa for the global problem) on the nodal contact traction P at the
    contact nodes (force on body 1 = -P): with d = ``response(P)`` the relative
    displacement U1 - pi U2 of the two Neumann problems under P,

        P <- Pi_M(P + rho (d - g n)) pointwise in the node frame (n, t):
        P_n <- max(0, P_n + rho (d_n - g)), P_t <- clip(P_t + rho d_t, -b, b),

    b = mu_f P_n (Coulomb) or b = F (Tresca) (the laws' projections,
    :func:`hpfebe.constitutive.laws.normal_projection`, :func:`friction_projection`);
    nodes with an infinite ``gap`` carry no pressure.  ``frame(v)`` -> (v_n, v_t),
    ``unframe(v_n, v_t)`` -> v; ``step``: rho itself.  Stopping: :func:`fixed_point`
    (relative increment of P, at least 3 iterations).  Returns (P, info)."""
    closed = np.isfinite(gap)
    g = np.where(closed, gap, 0.0)
    coulomb = settings.friction == "coulomb"
    nc = g.size

    def update(p):
        dn, dt = frame(response(p))
        pn, pt = frame(p)
        pn = np.where(closed, normal_projection(pn + step * (dn - g)), 0.0)
        bound = settings.mu_f * pn if coulomb else np.full(nc, F)
        pt = friction_projection(pt + step * dt, bound)
        return unframe(pn, pt)

    return fixed_point(update, np.zeros(2 * nc), settings.tol, settings.max_iter, norm=2,
                       divergence=settings.divergence, min_iter=3)
