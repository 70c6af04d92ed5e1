"""Limits and diagnostics of the penalty contact problem of Section 3.2.5.

The benchmark body (thesis lines 8540-8640, :func:`hpfebe.scenes.penalty.square_body`):
Omega = [-1,1]^2 with Gamma_C = the bottom side (n = (0, -1)), Gamma_N = the vertical
sides (traction free), Gamma_D = the top side (u = 0), discretised with S_hat of
:class:`hpfebe.bem.lame.LameBEM`.  For the penalty problem (3.57)

    G(U) = S_hat U + (1/eps) int_{Gamma_C} (U_n - g_h)_+ v_n ds = 0   (free dofs)

this module gives

* the eps -> 0 limit on a fixed mesh when all of Gamma_C is in contact: U_n = g at every
  contact node, the other free dofs from S_hat U = 0 (elimination, no penalty, so no
  ill-conditioning) - :func:`constrained_limit`;
* the componentwise (Oettli-Prager) backward error max_i |G_i| / (|A| |U|)_i of an iterate
  U, A the Newton matrix S_hat + (1/eps) J_c(U): for tiny eps the residual cannot drop
  below ~ macheps (|A| |U|)_i in the contact rows, however exact U is -
  :func:`backward_error`, :func:`check_penalty_solution`;
* where a penalty error stops decreasing like eps (round-off floor) -
  :func:`saturation_index`;
* the exponent lambda of the displacement singularity r^lambda at a corner of angle omega
  with one side clamped and the other traction free (Williams):

      4 kappa sin^2(lambda omega) + 4 lambda^2 sin^2(omega) = (kappa + 1)^2,

  kappa = (lambda_L + 3 mu) / (lambda_L + mu) the Kolosov constant (3 - 4 nu in plane
  strain, (3 - nu) / (1 + nu) in plane stress) - :func:`singular_exponent`.  The
  clamped / free corners of the benchmark bound the regularity of its solution.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from ..constitutive.materials import lame_constants
from .penalty import PenaltyResult, penalty_residual, solve_penalty

__all__ = ["MACHEPS", "PenaltyCheck", "backward_error", "check_penalty_solution",
           "constrained_limit", "saturation_index", "singular_exponent",
           "solve_penalty_checked"]

MACHEPS = float(np.finfo(float).eps)

# --------------------------------------------------------------------------- corner
def singular_exponent(nu: float, plane: str = "strain", omega: float = math.pi / 2) -> float:
    """Smallest real exponent lambda in (0, 1) of r^lambda at a clamped / traction-free
    corner of angle ``omega`` (Williams' equation, module docstring).  ValueError if
    there is no real root in (0, 1) (e.g. omega = pi: lambda = 1/2 + i log(kappa)/(2 pi))."""
    lam_L, mu = lame_constants(1.0, nu, plane)
    omega = float(omega)
    if not (0.0 < omega <= 2.0 * math.pi):
        raise ValueError(f"omega (corner angle) must lie in (0, 2 pi], got {omega!r}")
    kappa = (lam_L + 3.0 * mu) / (lam_L + mu)

    def f(lam):
        return (4 * kappa * np.sin(lam * omega) ** 2 + 4 * lam ** 2 * math.sin(omega) ** 2
                - (kappa + 1) ** 2)

    # f(0) = -(kappa + 1)^2 < 0: the first sign change on a fine grid brackets the root
    grid = np.linspace(1e-6, 1.0, 2001)
    change = np.flatnonzero(f(grid[1:]) >= 0)
    if change.size == 0:
        raise ValueError(f"omega = {omega!r}: no real singular exponent in (0, 1) "
                         f"(nu = {nu!r}, plane {plane!r})")
    k = int(change[0])
    return float(brentq(lambda x: float(f(x)), grid[k], grid[k + 1], xtol=1e-15))


# --------------------------------------------------------------------------- eps -> 0
def constrained_limit(bem, gap: float, S=None, contact_label: str = "C",
                      dirichlet_label: str = "D") -> np.ndarray:
    """eps -> 0 limit of the penalty solution with the constant gap ``gap`` on this mesh
    when all of Gamma_C is in contact: U_n = gap at every free contact node, the other
    free dofs from S_hat U = 0 (elimination).  Gamma_C must be straight and parallel to
    a coordinate axis (U_n is then one displacement component).  Interleaved V_hp^2
    coefficients, zero on Gamma_D."""
    S = bem.S_hat if S is None else S
    mesh, Vs = bem.mesh, bem.V_space
    gap = float(gap)
    if not math.isfinite(gap):
        raise ValueError(f"gap must be finite, got {gap!r}")
    celems = np.flatnonzero(mesh.where(contact_label))
    if celems.size == 0:
        raise ValueError(f"contact_label {contact_label!r}: no element carries this label")
    normals = mesh.normals[celems]
    n = normals[0]
    axis = int(np.argmax(np.abs(n)))
    if np.abs(normals - n).max() > 1e-12 or abs(abs(n[axis]) - 1.0) > 1e-12:
        raise ValueError(f"contact_label {contact_label!r}: Gamma_C must be straight and "
                         "parallel to a coordinate axis")
    ndof = 2 * Vs.ndof
    isfree = np.zeros(ndof, dtype=bool)
    isfree[Vs.free_dofs(dirichlet_label, components=2)] = True
    cn = np.zeros(ndof, dtype=bool)
    cn[2 * Vs.dofs_on(contact_label) + axis] = True
    cn &= isfree
    rest = np.flatnonzero(isfree & ~cn)
    U0 = np.zeros(ndof)
    U0[cn] = gap * np.sign(n[axis])          # U_n = U_axis n_axis = gap
    U0[rest] = np.linalg.solve(S[np.ix_(rest, rest)],
                               -S[np.ix_(rest, np.flatnonzero(cn))] @ U0[cn])
    return U0


def saturation_index(C_eps, err, ratio: float = 0.5) -> int | None:
    """Index of the first C_eps (sorted decreasingly) at which ``err`` stops decreasing
    like eps: the decrease per decade (err_k / err_{k-1})^(1/decades) exceeds ``ratio``
    (about 0.1 while err ~ eps).  None if it never does."""
    C = np.asarray(C_eps, dtype=float)
    e = np.asarray(err, dtype=float)
    if C.ndim != 1 or C.shape != e.shape:
        raise ValueError(f"C_eps and err must be 1D of equal length, got {C.shape}, {e.shape}")
    if np.any(C <= 0) or np.any(np.diff(C) >= 0):
        raise ValueError("C_eps must be positive and strictly decreasing")
    if not 0.0 < ratio < 1.0:
        raise ValueError(f"ratio must lie in (0, 1), got {ratio!r}")
    decades = np.log10(C[:-1] / C[1:])
    per_decade = (e[1:] / e[:-1]) ** (1.0 / decades)
    sat = np.flatnonzero(per_decade > ratio)
    return int(sat[0] + 1) if sat.size else None


# --------------------------------------------------------------------------- accuracy
def backward_error(A: np.ndarray, U: np.ndarray, G: np.ndarray) -> float:
    """Componentwise (Oettli-Prager) backward error max_i |G_i| / (|A| |U|)_i of the
    residual G at U (rows with (|A| |U|)_i = 0 do not count)."""
    A, U, G = np.asarray(A, float), np.asarray(U, float), np.asarray(G, float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or U.shape != (A.shape[1],) \
            or G.shape != (A.shape[0],):
        raise ValueError(f"A must be square and U, G match it, got {A.shape}, {U.shape}, "
                         f"{G.shape}")
    den = np.abs(A) @ np.abs(U)
    return float(np.max(np.abs(G) / np.where(den > 0, den, np.inf)))


@dataclass(frozen=True)
class PenaltyCheck:
    """Whether a penalty solution can be trusted.

    Parameters
    ----------
    condition_number : float
        2-norm condition number of the Newton matrix at U (free dofs)
    residual : float
        the solver's final max-norm residual
    relative_residual : float
        residual / max|(S_hat U)_free| (the physical force scale)
    backward_error : float
        :func:`backward_error` of G(U) = 0 on the free dofs
    accepted : bool
        converged, finite, and relative_residual <= accept_rel or backward_error <=
        accept_eta macheps
    reason : str
        the solver's reason, plus LAPACK's ill-conditioning warning and why the run is
        not accepted
    lapack_warning : bool
        LAPACK warned (rcond < macheps) during the solve
    solve_s : float
        wall time of the solve alone
    """

    condition_number: float
    residual: float
    relative_residual: float
    backward_error: float
    accepted: bool
    reason: str
    lapack_warning: bool
    solve_s: float = float("nan")


def _lapack_reason(reason: str, messages) -> str:
    if not messages:
        return reason
    m = messages[0]
    if "rcond" in m:
        return (reason + " | LAPACK: " + m.split(":")[0].strip() + " ("
                + m.split("rcond =")[-1].strip().rstrip(".") + ")")
    return reason + " | " + m


def check_penalty_solution(bem, result: PenaltyResult, gap, S=None, messages=(),
                           accept_rel: float = 1e-6, accept_eta: float = 20.0,
                           contact_label: str = "C",
                           dirichlet_label: str = "D") -> PenaltyCheck:
    """:class:`PenaltyCheck` of ``result`` (from ``solve_penalty(..., keep_jacobian=True)``;
    ``messages``: warnings caught during that solve)."""
    if result.jacobian is None:
        raise ValueError("result must come from solve_penalty(..., keep_jacobian=True)")
    if not (accept_rel > 0 and accept_eta > 0):
        raise ValueError(f"accept_rel and accept_eta must be positive, got {accept_rel!r}, "
                         f"{accept_eta!r}")
    S = bem.S_hat if S is None else S
    free = bem.V_space.free_dofs(dirichlet_label, components=2)
    A, U = result.jacobian, result.U
    finite_A = bool(np.all(np.isfinite(A)))
    cond = float(np.linalg.cond(A)) if finite_A else math.inf
    finite = bool(np.all(np.isfinite(U)))
    force = float(np.abs((S @ U)[free]).max()) if finite else math.nan
    resid = float(result.residuals[-1])
    rel = resid / force if finite and force > 0 else math.inf
    if finite and finite_A:
        G = penalty_residual(bem, U, result.eps, gap, S=S, contact_label=contact_label)
        eta = backward_error(A, U[free], G[free])
    else:
        eta = math.inf
    accepted = bool(result.converged and finite and
                    (rel <= accept_rel or eta <= accept_eta * MACHEPS))
    reason = _lapack_reason(result.reason, list(messages))
    if result.converged and not accepted:
        reason += (f" | NOT accepted: relative residual {rel:.1e} > {accept_rel:g}"
                   f" and backward error {eta / MACHEPS:.1e} macheps > "
                   f"{accept_eta:g} macheps (false convergence)")
    return PenaltyCheck(condition_number=cond, residual=resid, relative_residual=rel,
                        backward_error=eta, accepted=accepted, reason=reason,
                        lapack_warning=bool(messages))


def solve_penalty_checked(bem, eps: float, gap, S=None, max_iter: int = 50,
                          accept_rel: float = 1e-6, accept_eta: float = 20.0,
                          contact_label: str = "C", dirichlet_label: str = "D"
                          ) -> tuple[PenaltyResult, PenaltyCheck]:
    """``solve_penalty`` (no load) with the Newton matrix kept and LAPACK's warnings
    caught, and its :class:`PenaltyCheck` (``solve_s`` = the solve alone)."""
    labels = dict(contact_label=contact_label, dirichlet_label=dirichlet_label)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = solve_penalty(bem, eps, gap, S=S, max_iter=max_iter, keep_jacobian=True,
                            **labels)
    solve_s = time.perf_counter() - t0
    msgs = sorted({str(w.message) for w in caught})
    chk = check_penalty_solution(bem, res, gap, S=S, messages=msgs, accept_rel=accept_rel,
                                 accept_eta=accept_eta, **labels)
    return res, replace(chk, solve_s=solve_s)
