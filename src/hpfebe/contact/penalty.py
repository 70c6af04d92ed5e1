"""Normal penalty contact of one elastic body with a rigid obstacle (Section 3.2).

Penalty formulation (3.45)-(3.46), discretised with the Steklov-Poincare approximation
S_hat of :class:`hpfebe.bem.lame.LameBEM` (the discrete form (3.57)-(3.58)): find U in
V_hp^2 with U = 0 on Gamma_D such that

    <S_hat U, v> + (1/eps) int_{Gamma_C} (U_n - g)_+ v_n ds = L(v)   for all such v,

n the outward normal, U_n = U . n, g the gap function ((3.38): admissible U_n - g <= 0).
Sign convention of the thesis's example (line ~8560, EXPERIMENTS.md): the body's bottom
side y = -1 has n = (0, -1) and the rigid line y = -1 + d moves up into it, so the
non-penetration condition y + u_y >= -1 + d reads U_n <= -d: g = -d (negative gap =
initial overlap).  The contact pressure is p_eps = (1/eps) (U_n - g)_+ >= 0, the negative
of p_n^eps in (3.46).

The equation is the gradient of the convex, C^1, piecewise quadratic energy

    J(U) = 1/2 U^T S_hat U + 1/(2 eps) int_{Gamma_C} (U_n - g)_+^2 ds - L(U),

solved by a semismooth (active set) Newton method with a backtracking line search on J
(globalisation: each step decreases J, so the active sets cannot cycle forever; a
repeated active set without decrease is still detected and reported).  The positive part
is integrated exactly: g is replaced by its nodal interpolant g_h in V_hp, so that
U_n - g_h is a polynomial of degree p_I on each contact element; its roots split the
element and Gauss rules with p_I + 1 points integrate (U_n - g_h)_+ v_n and its
derivative exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..solvers import SolverInfo
from ..bodies.body import RigidObstacle, against_obstacle
from ..checks import boolean, integer, real
from .settings import ContactSettings
from .two_body import TwoBodyContact


@dataclass
class PenaltyResult:
    """Solution of the penalty contact problem and the Newton diagnostics.

    Parameters
    ----------
    U : ndarray
        interleaved V_hp^2 coefficients (all dofs, zero on Gamma_D)
    iterations, residuals : int, list
        the Newton steps taken and the max-norm of the residual per iterate
    converged, reason : bool, str
        the outcome ("converged", "no contact", "max_iter", "cycling", "line search
        failed")
    pressure : callable
        (elem, t) -> p_eps = (1/eps)(U_n - g_h)_+ >= 0 on contact elements (t in
        [-1, 1])
    pressure_nodes : tuple
        (x, p) at the GLL nodes of Gamma_C
    info : SolverInfo
        of the Newton iteration
    jacobian : ndarray or None
        only with ``solve_penalty(..., keep_jacobian=True)``: the Newton matrix
        S_hat + (1/eps) J_c(U) at the returned iterate, restricted to the free dofs
        (dense; e.g. for its condition number)
    """

    U: np.ndarray
    iterations: int
    residuals: list
    converged: bool
    reason: str
    eps: float
    pressure: object = None
    pressure_nodes: tuple = None
    energy: float = float("nan")
    info: SolverInfo = None
    jacobian: np.ndarray | None = None


def solve_penalty(bem, eps: float, gap, load=None, contact_label: str = "C",
                  dirichlet_label: str = "D", S=None, max_iter: int = 50,
                  tol: float = 1e-10, keep_jacobian: bool = False) -> PenaltyResult:
    """Penalty contact (3.45)-(3.46) with S_hat: the frictionless rigid-obstacle case of
    :class:`hpfebe.contact.two_body.TwoBodyContact` with the exact integration of the
    positive part, solved by semismooth Newton (energy line search, round-off stop,
    cycling detection; module doc).

    Parameters
    ----------
    bem
        LameBEM of the body (its mesh carries the labels)
    eps : penalty parameter > 0
    gap
        float or callable g(x) (x of shape (n, 2)) on Gamma_C, constraint U_n <= g
    load
        interleaved vector L(v) on V_hp^2, default 0
    S
        S_hat to use (default ``bem.S_hat``; pass it to reuse one matrix for many eps)
    max_iter, tol
        Newton limit; stop when max|residual| <= tol * (force scale of the
        current iterate: max of |L|, |S_hat U| and the contact forces, free dofs; not
        relative to the initial residual, which grows like 1/eps)
    keep_jacobian
        return the Newton matrix at the final iterate (free dofs)

    A gap that is never closed gives the zero-contact solution (reason "no contact").
    """
    eps = real("eps (penalty parameter)", eps, positive=True)
    tol = real("tol", tol, positive=True)
    max_iter = integer("max_iter", max_iter, lo=1)
    keep_jacobian = boolean("keep_jacobian", keep_jacobian)
    body, fixed, f = against_obstacle(bem, S, contact_label, dirichlet_label, load)
    pr = TwoBodyContact(body, RigidObstacle(gap), contact_label, eps_n=eps,
                        quadrature="exact")
    res = pr.solve(f, fixed, settings=ContactSettings(
        rtol=tol, max_iter=max_iter, line_search=True, norm="max", merit="energy",
        roundoff_stop=True))
    info = res.info.steps[-1]
    cs = pr.contact_state(res.U, 0.0)
    if info.converged and info.iterations == 0 and cs["n_active"] == 0:
        info.reason = "no contact"
    p_fun, p_nodes = pr.exact.pressure(res.U, eps)
    jac = None
    if keep_jacobian:
        _, cs = pr.internal_force(res.U, 0.0)
        free = np.setdiff1d(np.arange(pr.ndofs), [] if fixed is None else fixed)
        jac = pr.tangent(cs)[np.ix_(free, free)]
    return PenaltyResult(U=res.U, iterations=info.iterations, residuals=info.residuals,
                         converged=info.converged, reason=info.reason, eps=eps,
                         pressure=p_fun, pressure_nodes=p_nodes,
                         energy=float(info.merits[-1]), info=info, jacobian=jac)


def penalty_terms(bem, U, gap, contact_label: str = "C"):
    """(int (U_n - g_h)_+^2 / 2, the vector int (U_n - g_h)_+ v_n over V_hp^2, the number
    of contact elements in (partial) contact), integrated exactly (module doc): the
    contact terms of :func:`solve_penalty` with eps = 1."""
    body, _, _ = against_obstacle(bem, None, contact_label, "D", None)
    pr = TwoBodyContact(body, RigidObstacle(gap), contact_label, eps_n=1.0,
                        quadrature="exact")
    cs = pr.contact_state(np.asarray(U, dtype=float), 0.0)
    return (0.5 * float(cs["weights"] @ cs["p_n"] ** 2), pr.contact_force(cs),
            cs["n_active"])


def penalty_residual(bem, U, eps: float, gap, S=None, contact_label: str = "C") -> np.ndarray:
    """S_hat U + (1/eps) int_{Gamma_C} (U_n - g_h)_+ v_n ds on all dofs: the equation
    :func:`solve_penalty` solves (without the load) at a given U."""
    S = bem.S_hat if S is None else S
    return S @ U + penalty_terms(bem, U, gap, contact_label)[1] / eps
