"""Penalty contact with Tresca or Coulomb friction of one BEM body against a rigid
obstacle (Sections 3.3.1 and 4.2.1-4.2.5; Algorithm 4.1 for one body, elastic, 2D).

Discrete problem (cf. (3.95), with the tangential constitutive law (4.19)-(4.20) in
place of the smoothed (3.86)): find U in V_hp^2 with U = 0 on Gamma_D such that

    <S_hat U, v> + int_{Gamma_C} p_n v_n ds + int_{Gamma_C} t_t v_t ds = L(v)     (*)

for all such v.  Signs and directions (those of :mod:`hpfebe.contact.penalty`):

* n is the outward normal and t the element tangent of Gamma_C (mesh direction,
  counter-clockwise on outer boundaries, n = (t_y, -t_x)); on the bottom side of a
  counter-clockwise block t = (1, 0), n = (0, -1).  U_n = U.n, U_t = U.t, v likewise.
* g is the gap: admissible U_n - g <= 0 (g < 0 is an initial overlap, e.g. the rigid
  plane pushed into the body by d: g = -d).
* p_n = (1/eps_n) (U_n - g)_+ >= 0 is the contact pressure, the negative of the
  thesis's P_n^eps in (3.95)/(4.19).
* t_t is the tangential traction the body exerts on the obstacle along t, the negative
  of the thesis's P_t^eps (4.20): the traction on the body is sigma(u) n = -p_n n - t_t t.

Tangential law: elastic-plastic split of the relative tangential displacement
(Section 4.2.1), g_t = U_t - w = g_t^e + g_t^p, w the prescribed tangential motion of the
obstacle (``obstacle_slip``), g_t^p the accumulated slip (the "tangential
macro-displacement" internal variable of Algorithm 4.1), stored at the contact points.
Return map (backward Euler) in load step j, with g_t^p of step j-1:

    t_trial = (1/eps_t) (U_t - w_j - g_t^p,j-1)
    t_t     = t_trial                    if |t_trial| <= s   (stick)
            = s sign(t_trial)            otherwise            (slip)
    s       = F (Tresca, given bound) or mu_f p_n (Coulomb),

and after convergence of the step g_t^p,j = U_t - w_j - eps_t t_t.  With one load step
(g_t^p,0 = 0) this is t_t = Pi_{s}((U_t - w)/eps_t), the projection of (4.2.5); for
Tresca it is the derivative of the Huber function s Psi_{eps_t s}, i.e. (3.86) with the
penalty parameter eps_t replaced by eps_t F (Remark 4.2.1).  Tresca friction acts on the
whole of Gamma_C (the bound F does not depend on contact); Coulomb friction only where
p_n > 0 ("open" points carry no traction).

Consistent linearisation (4.35) and Section 4.2.5, pointwise:

    d p_n = (1/eps_n) [U_n > g] dU_n
    d t_t = (1/eps_t) dU_t                                   (stick)
          = 0                                                (Tresca slip)
          = mu_f sign(t_trial) (1/eps_n) [U_n > g] dU_n      (Coulomb slip)

so the Newton matrix S_hat + N_n^T D_nn N_n + N_t^T (D_tt N_t + D_tn N_n) is exactly
the (generalised) derivative of the residual; it is non-symmetric for Coulomb.

Integration: Gauss-Legendre quadrature with ``nq`` points (default p_I + 1, exact for
the products of two degree-p_I polynomials in full stick/contact) on every element of
Gamma_C; the contact state (pressure, stick/slip, g_t^p) lives at these quadrature
points.  Why not the exact root splitting of :mod:`penalty`: the friction law carries an
internal variable (g_t^p) that is a pointwise history quantity, not a polynomial, so the
stick/slip interface inside an element is not a root of a known polynomial; with the
state at fixed quadrature points the residual is piecewise linear in U, the Newton
matrix is its exact generalised derivative, and Newton terminates (up to round-off) as
soon as the active and slip sets are right.  The price is a quadrature error of the
kinks where the active or slip set changes inside an element (as in FE plasticity).

Newton (Algorithm 4.1 per load step j = 1..load_steps, load factor lambda_j = j / N:
the Neumann ``load`` and ``obstacle_slip`` are scaled by lambda_j, the gap is geometry
and stays fixed).  Globalisation: backtracking line search on the convex energy

    J(U) = 1/2 U.S U - L(U) + int (1/(2 eps_n)) (U_n - g)_+^2 + F Huber(U_t - w - g_t^p)

for Tresca (the equation is its gradient), and on the merit 1/2 |residual|^2 for Coulomb
(no potential).  Start of each step (``predictor=True``, the default): the solution of
the linear "bonded" problem (every Gauss point in contact and sticking, relative to the
current slip g_t^p) when it has a lower merit than the previous step's U.  Without it,
the first Newton step from U = 0 sees |t_trial| = |w|/eps_t, i.e. full slip, and for
stiff penalties (eps ~ 1e-7 h, the thesis's smallest) the semismooth iteration then
crawls through the stick band of width eps_t s (measured: 25 iterations instead of 1-3
on the 6 x 4 elements, p = 2 block).  The predictor is counted as an iteration.

Diagnostics: per step iterations, residual history (max-norm over the free dofs),
converged flag and reason ("converged", "no load", "max_iter", "singular Newton matrix
...", "diverged ...", "line search failed", "cycling ...").
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..quadrature import gauss_legendre
from ..spaces import lagrange_values

LAWS = ("tresca", "coulomb")
OPEN, STICK, SLIP = 0, 1, 2
STATE_NAMES = {OPEN: "open", STICK: "stick", SLIP: "slip"}


@dataclass
class StepInfo:
    """One load step: load factor, iterations (linear solves: the bonded predictor if it
    was taken, then Newton steps), residual history (max-norm over the free dofs, one
    entry per iterate including the start), outcome."""

    load_factor: float
    iterations: int
    residuals: list
    converged: bool
    reason: str
    predictor_used: bool = False


@dataclass
class FrictionResult:
    """Solution of the frictional penalty contact problem and its diagnostics.

    U : interleaved V_hp^2 coefficients (zero on Gamma_D), after the last step
    converged, reason : overall outcome (the reason names the failed step if any)
    steps : list of StepInfo; iterations / residuals : the same per step, as lists
    Contact state at the Gauss points of Gamma_C (arrays of length n_points):
        points (n, 2), elements, weights (quadrature weights incl. Jacobian),
        p_n >= 0 (pressure), t_t (tangential traction along the element tangent, body
        on obstacle; traction on the body is -p_n n - t_t t), bound (s = F or
        mu_f p_n), state (OPEN=0 / STICK=1 / SLIP=2), slip (accumulated g_t^p),
        gap_function (U_n - g) and rel_slip (U_t - w).
    load_vector, obstacle_motion : the load and obstacle motion w (at the points) of the
        last step (used by ``initial=`` to continue loading)
    """

    U: np.ndarray
    converged: bool
    reason: str
    friction: str
    eps_n: float
    eps_t: float
    steps: list = field(default_factory=list)
    points: np.ndarray = None
    elements: np.ndarray = None
    weights: np.ndarray = None
    p_n: np.ndarray = None
    t_t: np.ndarray = None
    bound: np.ndarray = None
    state: np.ndarray = None
    slip: np.ndarray = None
    gap_function: np.ndarray = None
    rel_slip: np.ndarray = None
    load_vector: np.ndarray = None
    obstacle_motion: np.ndarray = None

    @property
    def iterations(self) -> list:
        return [s.iterations for s in self.steps]

    @property
    def residuals(self) -> list:
        return [s.residuals for s in self.steps]

    @property
    def stick(self) -> np.ndarray:
        return self.state == STICK

    @property
    def slipping(self) -> np.ndarray:
        return self.state == SLIP

    def total_forces(self) -> tuple[float, float]:
        """(int p_n ds, int t_t ds) over Gamma_C."""
        return float(self.weights @ self.p_n), float(self.weights @ self.t_t)


def _positive(name, value, allow_zero=False):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    ok = np.isfinite(v) and (v >= 0 if allow_zero else v > 0)
    if not ok:
        what = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be finite and {what}, got {value!r}")
    return v


def _count(name, value):
    """An integer >= 1 (bools and non-integral values rejected)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer, float)) or \
            not np.isfinite(value) or int(value) != value or int(value) < 1:
        raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def _field(name, value, pts, allow_negative=True):
    """A float or callable x -> values, evaluated at the contact points."""
    if value is None:
        return np.zeros(len(pts))
    if callable(value):
        v = np.asarray(value(pts), dtype=float).reshape(-1)
        if v.shape != (len(pts),):
            raise ValueError(f"{name}(x) must return one value per point, got {v.shape}")
    else:
        try:
            v = np.full(len(pts), float(value))
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a float or a callable, "
                             f"got {value!r}") from None
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be finite on Gamma_C")
    if not allow_negative and np.any(v < 0):
        raise ValueError(f"{name} must be >= 0 on Gamma_C, got min {v.min()!r}")
    return v


class _FrictionTerm:
    """Trace matrices at the Gauss points of Gamma_C and the pointwise return map."""

    def __init__(self, bem, celems, nq=None):
        mesh, Vs = bem.mesh, bem.V_space
        ndof = 2 * Vs.ndof
        rows_n, rows_t, pts, wts, els = [], [], [], [], []
        for e in celems:
            p = int(mesh.degrees[e])
            m = p + 1 if nq is None else int(nq)
            xq, wq = gauss_legendre(m)
            phi = lagrange_values(p, xq)                       # (m, p+1)
            d = Vs.elem_dofs[e, :p + 1]
            n, t = mesh.normals[e], mesh.tangents[e]
            Nn = np.zeros((m, ndof))
            Nt = np.zeros((m, ndof))
            for c in range(2):
                Nn[:, 2 * d + c] += phi * n[c]
                Nt[:, 2 * d + c] += phi * t[c]
            rows_n.append(Nn)
            rows_t.append(Nt)
            pts.append(mesh.points(np.full(m, e), xq))
            wts.append(wq * 0.5 * mesh.lengths[e])
            els.append(np.full(m, e))
        self.Nn, self.Nt = np.vstack(rows_n), np.vstack(rows_t)
        self.points, self.w = np.vstack(pts), np.concatenate(wts)
        self.elements = np.concatenate(els)

    def evaluate(self, U, law, eps_n, eps_t, g, w, gp, F, mu):
        """Pointwise p_n, t_t, state and the derivatives dp_n/dU_n, dt_t/dU_t,
        dt_t/dU_n, and the trial traction."""
        un = self.Nn @ U - g
        act = un > 0
        p_n = np.where(act, un, 0.0) / eps_n
        dpn = act / eps_n
        trial = (self.Nt @ U - w - gp) / eps_t
        s = F if law == "tresca" else mu * p_n
        stick = np.abs(trial) <= s
        sg = np.sign(trial)
        t_t = np.where(stick, trial, s * sg)
        dtt = np.where(stick, 1.0 / eps_t, 0.0)
        dtn = np.zeros_like(t_t) if law == "tresca" else np.where(stick, 0.0, mu * sg * dpn)
        state = np.where(stick, STICK, SLIP)
        if law == "coulomb":
            state = np.where(act, state, OPEN)
        return dict(un=un, p_n=p_n, dpn=dpn, trial=trial, s=s, t_t=t_t, dtt=dtt, dtn=dtn,
                    state=state)

    def force(self, st):
        return self.Nn.T @ (self.w * st["p_n"]) + self.Nt.T @ (self.w * st["t_t"])

    def jacobian(self, st):
        Wn = (self.w * st["dpn"])[:, None] * self.Nn
        Wt = ((self.w * st["dtt"])[:, None] * self.Nt
              + (self.w * st["dtn"])[:, None] * self.Nn)
        return self.Nn.T @ Wn + self.Nt.T @ Wt

    def energy(self, st, eps_n, eps_t, F):
        """Contact part of the Tresca energy: (1/(2 eps_n)) (U_n-g)_+^2 + F Huber."""
        z = eps_t * st["trial"]
        a = np.abs(z)
        lim = eps_t * F
        hub = np.where(a <= lim, z ** 2 / (2 * eps_t), F * a - 0.5 * eps_t * F ** 2)
        return float(self.w @ (0.5 * eps_n * st["p_n"] ** 2 + hub))


def solve_friction(bem, eps_n: float, eps_t: float, gap, friction: str = "tresca",
                   F=None, mu_f=None, obstacle_slip=None, load=None, load_steps: int = 1,
                   contact_label: str = "C", dirichlet_label: str = "D",
                   max_iter: int = 50, tol: float = 1e-10, S=None,
                   nq: int | None = None, initial=None,
                   predictor: bool = True) -> FrictionResult:
    """Frictional penalty contact of a :class:`LameBEM` body with a rigid obstacle.

    Parameters
    ----------
    bem : LameBEM (its mesh carries the labels)
    eps_n, eps_t : normal and tangential penalty parameters (> 0)
    gap : float or callable g(x) on Gamma_C; constraint U_n <= g (module doc)
    friction : "tresca" (give F >= 0, float or callable of x) or "coulomb" (give
        mu_f >= 0)
    obstacle_slip : tangential displacement w of the obstacle along the element tangent
        of Gamma_C (float or callable of x), reached at the last load step; default 0
    load : interleaved vector L(v) on V_hp^2, reached at the last load step; default 0
    load_steps : number N of equal load increments (lambda_j = j / N scales load and
        obstacle_slip); the slip g_t^p is carried from step to step
    max_iter, tol : Newton limit per step; a step stops when max|residual| <= tol *
        max(|L_j|, |residual at U = 0|, |S_hat U|) over the free dofs
    S : S_hat to reuse (default ``bem.S_hat``); nq : Gauss points per contact element
        (default p_I + 1)
    predictor : start each load step from the "bonded" predictor (one linear solve with
        every point in contact and sticking) when it lowers the merit function (module
        doc); False: plain Newton from the previous step's U (U = 0 at the start)
    initial : a FrictionResult of the same body, law and contact points to continue
        from (non-proportional loading, e.g. unloading): U, the slip g_t^p, the load and
        the obstacle motion start from its final values and are ramped linearly to
        ``load`` / ``obstacle_slip`` over the load steps
    """
    eps_n = _positive("eps_n", eps_n)
    eps_t = _positive("eps_t", eps_t)
    if not isinstance(friction, str) or friction.lower() not in LAWS:
        raise ValueError(f"friction must be one of {LAWS}, got {friction!r}")
    law = friction.lower()
    if law == "tresca":
        if F is None:
            raise ValueError("F (Tresca friction bound) is required for friction='tresca'")
        if mu_f is not None:
            raise ValueError("mu_f is the Coulomb coefficient; Tresca takes F")
    else:
        if mu_f is None:
            raise ValueError("mu_f (Coulomb coefficient) is required for "
                             "friction='coulomb'")
        if F is not None:
            raise ValueError("F is the Tresca bound; Coulomb takes mu_f")
        mu = _positive("mu_f", mu_f, allow_zero=True)
    max_iter = _count("max_iter", max_iter)
    load_steps = _count("load_steps", load_steps)
    tol = _positive("tol", tol)
    if nq is not None:
        nq = _count("nq", nq)
    mesh, Vs = bem.mesh, bem.V_space
    celems = np.flatnonzero(mesh.where(contact_label))
    if celems.size == 0:
        raise ValueError(f"contact_label {contact_label!r}: no element carries this label")
    ndof = 2 * Vs.ndof
    S = bem.S_hat if S is None else np.asarray(S, dtype=float)
    if S.shape != (ndof, ndof):
        raise ValueError(f"S must have shape {(ndof, ndof)}, got {S.shape}")
    f = np.zeros(ndof) if load is None else np.asarray(load, dtype=float)
    if f.shape != (ndof,):
        raise ValueError(f"load must have {ndof} entries, got {f.shape}")
    if not np.all(np.isfinite(f)):
        raise ValueError("load must be finite")
    fixed = np.zeros(ndof, dtype=bool)
    if np.any(mesh.where(dirichlet_label)):
        D = Vs.dofs_on(dirichlet_label)
        fixed[2 * D] = fixed[2 * D + 1] = True
    free = np.flatnonzero(~fixed)

    term = _FrictionTerm(bem, celems, nq)
    g = _field("gap", gap, term.points)
    w_full = _field("obstacle_slip", obstacle_slip, term.points)
    if law == "tresca":
        Fv = _field("F", F, term.points, allow_negative=False)
        mu = 0.0
    else:
        Fv = None
    Sff = S[np.ix_(free, free)]

    U = np.zeros(ndof)
    gp = np.zeros(len(term.w))
    f0, w0 = np.zeros(ndof), np.zeros(len(term.w))
    if initial is not None:
        if not isinstance(initial, FrictionResult) or initial.U.shape != (ndof,) or \
                initial.points.shape != term.points.shape or \
                not np.allclose(initial.points, term.points) or initial.friction != law:
            raise ValueError("initial must be a FrictionResult of the same body, contact "
                             "points and friction law")
        if not initial.converged:
            raise ValueError(f"initial did not converge ({initial.reason}); not a state "
                             "to continue from")
        U, gp = initial.U.copy(), initial.slip.copy()
        f0, w0 = initial.load_vector.copy(), initial.obstacle_motion.copy()
    steps = []
    overall_ok, overall_reason = True, "converged"
    N = load_steps
    for j in range(1, N + 1):
        lam = j / N
        fj, wj = f0 + lam * (f - f0), w0 + lam * (w_full - w0)

        def state_of(V):
            st = term.evaluate(V, law, eps_n, eps_t, g, wj, gp, Fv, mu)
            G = S @ V + term.force(st) - fj
            return st, G

        def merit(V, st, G):
            if law == "tresca":
                return 0.5 * V @ (S @ V) - fj @ V + term.energy(st, eps_n, eps_t, Fv)
            return 0.5 * float(G[free] @ G[free])

        st, G = state_of(np.zeros(ndof))
        scale = max(np.abs(fj).max(initial=0.0), np.abs(G[free]).max(initial=0.0), 1e-300)
        st, G = state_of(U)
        res = [float(np.abs(G[free]).max())]
        reason, ok, it, used_pred = "max_iter", False, 0, False
        if res[0] == 0.0 or res[0] <= tol * scale:
            ok = True
            reason = "no load" if res[0] == 0.0 and not np.any(U) else "converged"
        elif predictor:
            # bonded predictor (one linear solve, counted as an iteration): every point
            # in contact and sticking; taken as the start when it lowers the merit
            stb = dict(st, dpn=np.full(len(term.w), 1.0 / eps_n),
                       dtt=np.full(len(term.w), 1.0 / eps_t), dtn=np.zeros(len(term.w)))
            Ab = Sff + term.jacobian(stb)[np.ix_(free, free)]
            rhs = fj + term.Nn.T @ (term.w * g / eps_n) \
                + term.Nt.T @ (term.w * (wj + gp) / eps_t)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", sla.LinAlgWarning)
                    Ub = U.copy()
                    Ub[free] = sla.solve(Ab, (rhs - S[:, fixed] @ U[fixed])[free])
                stp, Gp = state_of(Ub)
                if np.all(np.isfinite(Gp)) and merit(Ub, stp, Gp) < merit(U, st, G):
                    U, st, G, used_pred, it = Ub, stp, Gp, True, 1
                    res.append(float(np.abs(G[free]).max()))
                    if res[-1] <= tol * max(scale, np.abs(Sff @ U[free]).max()):
                        reason, ok = "converged", True
            except (np.linalg.LinAlgError, ValueError, sla.LinAlgWarning):
                pass
        if not ok:
            seen = {}
            phi = merit(U, st, G)
            for it in range(1 + used_pred, max_iter + 1):
                A = Sff + term.jacobian(st)[np.ix_(free, free)]
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("error", sla.LinAlgWarning)
                        dU = -sla.solve(A, G[free], check_finite=True)
                    if not np.all(np.isfinite(dU)):
                        raise np.linalg.LinAlgError
                except (np.linalg.LinAlgError, ValueError, sla.LinAlgWarning):
                    reason = "singular Newton matrix (body not fixed?)"
                    break
                # directional derivative of the merit along dU (Newton: -2 phi for the
                # residual merit, G.dU for the energy)
                slope = G[free] @ dU if law == "tresca" else -2.0 * phi
                step, accepted = 1.0, False
                for _ in range(30):
                    Un = U.copy()
                    Un[free] += step * dU
                    stn, Gn = state_of(Un)
                    phin = merit(Un, stn, Gn)
                    if np.isfinite(phin) and \
                            phin <= phi + 1e-4 * step * slope + 1e-14 * abs(phi):
                        accepted = True
                        break
                    step *= 0.5
                if not accepted:
                    reason = "line search failed"
                    break
                U, st, G, phi = Un, stn, Gn, phin
                r = float(np.abs(G[free]).max())
                res.append(r)
                if not np.isfinite(r) or r > 1e12 * max(res[0], scale):
                    reason = f"diverged: residual {r:.3e} at iteration {it}"
                    break
                if r <= tol * max(scale, np.abs(Sff @ U[free]).max()):
                    reason, ok = "converged", True
                    break
                # cycling: a contact state seen before without progress in the merit
                # (energy for Tresca, which may decrease while the residual grows)
                key = st["state"].tobytes() + np.signbit(st["trial"]).tobytes()
                if key in seen and phi >= seen[key][1] - 1e-12 * abs(seen[key][1]):
                    reason = (f"cycling: contact state of iterate {seen[key][0]} repeated "
                              f"at {it} without decrease of the merit function")
                    break
                seen.setdefault(key, (it, phi))
        steps.append(StepInfo(load_factor=lam, iterations=it, residuals=res,
                              converged=ok, reason=reason, predictor_used=used_pred))
        # return map update of the internal variable (slip) with the converged state
        gp = term.Nt @ U - wj - eps_t * st["t_t"]
        if not ok:
            overall_ok = False
            overall_reason = f"load step {j}/{N}: {reason}"
            break
    return FrictionResult(
        U=U, converged=overall_ok, reason=overall_reason, friction=law, eps_n=eps_n,
        eps_t=eps_t, steps=steps, points=term.points, elements=term.elements,
        weights=term.w, p_n=st["p_n"], t_t=st["t_t"], bound=np.asarray(st["s"], float),
        state=st["state"], slip=gp, gap_function=st["un"], rel_slip=term.Nt @ U - wj,
        load_vector=fj, obstacle_motion=wj)
