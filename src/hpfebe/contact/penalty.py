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
import scipy.linalg as sla

from ..nonlinear import Iterate, SingularStep, SolverInfo, newton
from ..quadrature import gauss_legendre, gauss_lobatto
from ..spaces import lagrange_values
from .laws import positive


@dataclass
class PenaltyResult:
    """Solution of the penalty contact problem and the Newton diagnostics.

    U : interleaved V_hp^2 coefficients (all dofs, zero on Gamma_D)
    iterations : Newton steps taken; residuals : max-norm of the residual per iterate
    converged, reason : outcome ("converged", "no contact", "max_iter", "cycling",
        "line search failed")
    pressure : callable (elem, t) -> p_eps = (1/eps)(U_n - g_h)_+ >= 0 on contact
        elements (t in [-1, 1]); pressure_nodes : (x, p) at the GLL nodes of Gamma_C
    info : the SolverInfo of the Newton iteration
    jacobian : only with ``solve_penalty(..., keep_jacobian=True)``: the Newton matrix
        S_hat + (1/eps) J_c(U) at the returned iterate, restricted to the free dofs
        (dense; e.g. for its condition number), else None
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


class _ContactTerm:
    """Exact integration of (U_n - g_h)_+ on the contact elements."""

    def __init__(self, bem, contact_elems, g_nodes):
        mesh, Vs = bem.mesh, bem.V_space
        self.elems = contact_elems
        self.mesh = mesh
        self.ndof = 2 * Vs.ndof
        self.items = []
        for k, e in enumerate(contact_elems):
            p = int(mesh.degrees[e])
            d = Vs.elem_dofs[e, :p + 1]
            n = mesh.normals[e]
            # rows of the local normal-trace operator: U_n at the GLL nodes = N @ U[idx]
            idx = np.concatenate([2 * d[:, None] + np.arange(2)[None, :]]).ravel()
            self.items.append((e, p, d, n, idx, g_nodes[k]))

    def _pieces(self, p, w_nodes):
        """Sub-intervals of [-1, 1] where the degree-p polynomial with GLL nodal values
        w_nodes is positive (exact roots)."""
        xg, _ = gauss_lobatto(p + 1)
        if np.all(w_nodes <= 0) and p == 1:
            return []
        # monomial coefficients by interpolation at the GLL nodes
        c = np.linalg.solve(np.vander(xg, p + 1), w_nodes)
        roots = np.roots(c) if np.any(c[:-1] != 0) else np.array([])
        r = np.sort(np.real(roots[(np.abs(np.imag(roots)) < 1e-12)]))
        br = np.concatenate([[-1.0], r[(r > -1) & (r < 1)], [1.0]])
        out = []
        for a, b in zip(br[:-1], br[1:]):
            if b - a <= 0:
                continue
            mid = 0.5 * (a + b)
            if np.polyval(c, mid) > 0:
                out.append((a, b))
        return out

    def assemble(self, U, with_jacobian=True):
        """(value int (U_n - g)_+^2 / 2, gradient vector, Jacobian (dense) or None,
        number of elements in contact)."""
        F = np.zeros(self.ndof)
        Jm = np.zeros((self.ndof, self.ndof)) if with_jacobian else None
        energy = 0.0
        nact = 0
        for e, p, d, n, idx, gn in self.items:
            L = self.mesh.lengths[e]
            Un_nodes = U[2 * d] * n[0] + U[2 * d + 1] * n[1]
            w = Un_nodes - gn
            pieces = self._pieces(p, w)
            if not pieces:
                continue
            nact += 1
            xq, wq = gauss_legendre(p + 1)
            for a, b in pieces:
                t = a + (b - a) * 0.5 * (xq + 1.0)
                wt = wq * (b - a) * 0.5 * L * 0.5
                phi = lagrange_values(p, t)                 # (nq, p+1)
                val = phi @ w
                Nphi = (phi[:, :, None] * n[None, None, :]).reshape(len(t), -1)  # v_n
                energy += 0.5 * np.sum(wt * val ** 2)
                F[idx] += Nphi.T @ (wt * val)
                if with_jacobian:
                    Jm[np.ix_(idx, idx)] += (Nphi * wt[:, None]).T @ Nphi
        return energy, F, Jm, nact

    def pressure(self, U, eps):
        def p_eps(elem, t):
            for e, p, d, n, idx, gn in self.items:
                if e == elem:
                    w = U[2 * d] * n[0] + U[2 * d + 1] * n[1] - gn
                    return np.maximum(lagrange_values(p, np.atleast_1d(t)) @ w, 0.0) / eps
            raise ValueError(f"elem {elem} is not a contact element")
        xs, ps = [], []
        for e, p, d, n, idx, gn in self.items:
            xg, _ = gauss_lobatto(p + 1)
            xs.append(self.mesh.points(np.full(p + 1, e), xg))
            ps.append(np.maximum(U[2 * d] * n[0] + U[2 * d + 1] * n[1] - gn, 0.0) / eps)
        return p_eps, (np.vstack(xs), np.concatenate(ps))


def _gap_nodes(mesh, celems, gap) -> list:
    """The gap g at the GLL nodes of every contact element (its interpolant g_h)."""
    g_nodes = []
    for e in celems:
        p = int(mesh.degrees[e])
        xg, _ = gauss_lobatto(p + 1)
        pts = mesh.points(np.full(p + 1, e), xg)
        gv = np.full(p + 1, float(gap)) if np.isscalar(gap) else \
            np.asarray(gap(pts), dtype=float).reshape(p + 1)
        if not np.all(np.isfinite(gv)):
            raise ValueError("gap must be finite on Gamma_C")
        g_nodes.append(gv)
    return g_nodes


class _PenaltyProblem:
    """The Newton problem of (3.57)-(3.58) for :func:`hpfebe.nonlinear.newton`: residual
    G = S_hat U + (1/eps) int (U_n - g_h)_+ v_n - L on the free dofs, merit the energy J,
    force scale max(|L|, |S_hat U|, contact forces) of the iterate, and the nodal contact
    pattern for cycling."""

    def __init__(self, term, S, f, free, eps):
        self.term, self.S, self.f, self.free, self.eps = term, S, f, free, eps
        self.Sff = S[np.ix_(free, free)]

    def evaluate(self, U):
        free, eps = self.free, self.eps
        ec, Fc, Jc, nact = self.term.assemble(U, True)
        SU = self.S @ U
        G = SU + Fc / eps - self.f
        J = 0.5 * U @ SU + ec / eps - self.f @ U
        scale = max(np.abs(self.f[free]).max(initial=0.0), np.abs(SU[free]).max(initial=0.0),
                    np.abs(Fc[free]).max(initial=0.0) / eps, 1e-300)
        key = np.signbit(np.concatenate([U[2 * d] * n[0] + U[2 * d + 1] * n[1] - gn
                                         for e, p, d, n, idx, gn in self.term.items]))
        return Iterate(U, G[free], float(J), scale, key.tobytes(), (Jc, nact))

    def jacobian(self, it):
        Jc = it.data[0]
        return self.Sff + Jc[np.ix_(self.free, self.free)] / self.eps

    def step(self, it):
        try:
            d = sla.solve(self.jacobian(it), -it.residual, assume_a="sym")
        except (np.linalg.LinAlgError, ValueError):
            raise SingularStep("singular Newton matrix (body not fixed?)") from None
        dU = np.zeros_like(it.x)
        dU[self.free] = d
        return dU

    def slope(self, it, dU):
        return float(it.residual @ dU[self.free])


def solve_penalty(bem, eps: float, gap, load=None, contact_label: str = "C",
                  dirichlet_label: str = "D", S=None, max_iter: int = 50,
                  tol: float = 1e-10, keep_jacobian: bool = False) -> PenaltyResult:
    """Penalty contact (3.45)-(3.46) with S_hat, by semismooth Newton
    (:func:`hpfebe.nonlinear.newton`: energy line search, round-off stop, cycling).

    Parameters
    ----------
    bem : LameBEM of the body (its mesh carries the labels)
    eps : penalty parameter > 0
    gap : float or callable g(x) (x of shape (n, 2)) on Gamma_C, constraint U_n <= g
    load : interleaved vector L(v) on V_hp^2, default 0
    S : S_hat to use (default ``bem.S_hat``; pass it to reuse one matrix for many eps)
    max_iter, tol : Newton limit; stop when max|residual| <= tol * (force scale of the
        current iterate: max of |L|, |S_hat U| and the contact forces, free dofs; not
        relative to the initial residual, which grows like 1/eps)
    keep_jacobian : return the Newton matrix at the final iterate (free dofs)

    A gap that is never closed gives the zero-contact solution (reason "no contact").
    """
    eps = positive("eps (penalty parameter)", eps)
    if isinstance(max_iter, bool) or int(max_iter) < 1:
        raise ValueError(f"max_iter must be >= 1, got {max_iter!r}")
    mesh, Vs = bem.mesh, bem.V_space
    celems = np.flatnonzero(mesh.where(contact_label))
    if celems.size == 0:
        raise ValueError(f"contact_label {contact_label!r}: no element carries this label")
    S = bem.S_hat if S is None else S
    ndof = 2 * Vs.ndof
    f = np.zeros(ndof) if load is None else np.asarray(load, dtype=float)
    if f.shape != (ndof,):
        raise ValueError(f"load must have {ndof} entries, got {f.shape}")
    labels = (dirichlet_label,) if np.any(mesh.where(dirichlet_label)) else ()
    free = Vs.free_dofs(*labels, components=2) if labels else np.arange(ndof)
    term = _ContactTerm(bem, celems, _gap_nodes(mesh, celems, gap))
    problem = _PenaltyProblem(term, S, f, free, eps)
    it, info = newton(problem, np.zeros(ndof), tol, int(max_iter), norm=np.inf,
                      roundoff_stop=True)
    U, (Jc, nact) = it.x, it.data
    if info.converged and info.iterations == 0 and nact == 0:
        info.reason = "no contact"
    p_fun, p_nodes = term.pressure(U, eps)
    return PenaltyResult(U=U, iterations=info.iterations, residuals=info.residuals,
                         converged=info.converged, reason=info.reason, eps=eps,
                         pressure=p_fun, pressure_nodes=p_nodes, energy=float(it.merit),
                         info=info,
                         jacobian=problem.jacobian(it) if keep_jacobian else None)


def penalty_terms(bem, U, gap, contact_label: str = "C"):
    """(int (U_n - g_h)_+^2 / 2, the vector int (U_n - g_h)_+ v_n over V_hp^2, the number
    of contact elements in (partial) contact), integrated exactly (module doc)."""
    mesh = bem.mesh
    celems = np.flatnonzero(mesh.where(contact_label))
    if celems.size == 0:
        raise ValueError(f"contact_label {contact_label!r}: no element carries this label")
    term = _ContactTerm(bem, celems, _gap_nodes(mesh, celems, gap))
    energy, F, _, nact = term.assemble(np.asarray(U, dtype=float), with_jacobian=False)
    return energy, F, nact


def penalty_residual(bem, U, eps: float, gap, S=None, contact_label: str = "C") -> np.ndarray:
    """S_hat U + (1/eps) int_{Gamma_C} (U_n - g_h)_+ v_n ds on all dofs: the equation
    :func:`solve_penalty` solves (without the load) at a given U."""
    S = bem.S_hat if S is None else S
    return S @ U + penalty_terms(bem, U, gap, contact_label)[1] / eps
