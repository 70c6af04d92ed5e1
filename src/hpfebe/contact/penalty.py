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

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..quadrature import gauss_legendre, gauss_lobatto
from ..spaces import lagrange_values


@dataclass
class PenaltyResult:
    """Solution of the penalty contact problem and the Newton diagnostics.

    U : interleaved V_hp^2 coefficients (all dofs, zero on Gamma_D)
    iterations : Newton steps taken; residuals : max-norm of the residual per iterate
    converged, reason : outcome ("converged", "no contact", "max_iter", "cycling",
        "line search failed")
    pressure : callable (elem, t) -> p_eps = (1/eps)(U_n - g_h)_+ >= 0 on contact
        elements (t in [-1, 1]); pressure_nodes : (x, p) at the GLL nodes of Gamma_C
    active_history : number of contact elements in (partial) contact per iterate
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
    active_history: list = field(default_factory=list)
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


def solve_penalty(bem, eps: float, gap, load=None, contact_label: str = "C",
                  dirichlet_label: str = "D", S=None, max_iter: int = 50,
                  tol: float = 1e-10, keep_jacobian: bool = False) -> PenaltyResult:
    """Penalty contact (3.45)-(3.46) with S_hat, by semismooth Newton.

    Parameters
    ----------
    bem : LameBEM of the body (its mesh carries the labels)
    eps : penalty parameter > 0
    gap : float or callable g(x) (x of shape (n, 2)) on Gamma_C, constraint U_n <= g
    load : interleaved vector L(v) on V_hp^2 (tested Neumann data), default 0
    S : S_hat to use (default ``bem.S_hat``; pass it to reuse one matrix for many eps)
    max_iter, tol : Newton limit; stop when max|residual| <= tol * (force scale of the
        current iterate: max of |L|, |S_hat U| and the contact forces |(1/eps) int
        (U_n - g)_+ v_n|, free dofs).  (Not relative to the initial residual: that grows
        like 1/eps and would accept wrong active sets for small eps.)
    keep_jacobian : return the Newton matrix at the final iterate (free dofs) in
        ``PenaltyResult.jacobian``

    A gap that is never closed (g_h >= 0 on Gamma_C and no load pushing into the obstacle)
    gives the zero-contact solution: zero pressure, reason "no contact" if U = 0 solves.
    """
    eps = float(eps)
    if not (np.isfinite(eps) and eps > 0):
        raise ValueError(f"eps (penalty parameter) must be positive, got {eps!r}")
    if int(max_iter) < 1:
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
    fixed = np.zeros(ndof, dtype=bool)
    D = Vs.dofs_on(dirichlet_label) if np.any(mesh.where(dirichlet_label)) else np.array([], int)
    fixed[2 * D] = fixed[2 * D + 1] = True
    free = np.flatnonzero(~fixed)
    # gap interpolated at the GLL nodes of every contact element
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
    term = _ContactTerm(bem, celems, g_nodes)
    Sff = S[np.ix_(free, free)]

    def energy_grad(U, jac=True):
        ec, Fc, Jc, nact = term.assemble(U, jac)
        SU = S @ U
        Jv = 0.5 * U @ SU + ec / eps - f @ U
        G = SU + Fc / eps - f
        # force scale of this iterate for the stopping test
        fs = max(np.abs(f[free]).max(initial=0.0), np.abs(SU[free]).max(initial=0.0),
                 np.abs(Fc[free]).max(initial=0.0) / eps, 1e-300)
        return Jv, G, Jc, nact, fs

    U = np.zeros(ndof)
    Jv, G, Jc, nact, fs = energy_grad(U)
    residuals = [float(np.abs(G[free]).max())]
    energies = [float(Jv)]
    active_hist = [nact]
    seen = {}
    reason, converged, it = "max_iter", False, 0
    if residuals[0] == 0.0 or (nact == 0 and residuals[0] <= tol * fs):
        reason, converged = ("no contact" if nact == 0 else "converged"), True
    else:
        for it in range(1, int(max_iter) + 1):
            A = Sff + Jc[np.ix_(free, free)] / eps
            try:
                dU = -sla.solve(A, G[free], assume_a="sym")
            except (np.linalg.LinAlgError, ValueError):
                reason = "singular Newton matrix (body not fixed?)"
                break
            # for small eps the residual floor is cond(A) * macheps * (contact forces),
            # above tol: stop when Newton cannot change U any more
            if np.abs(dU).max() <= 64 * np.finfo(float).eps * np.abs(U[free]).max():
                reason, converged = ("converged (Newton update at round-off level; the "
                                     "residual is limited by the conditioning)"), True
                break
            # backtracking line search on the convex energy J
            step, ok = 1.0, False
            for _ in range(30):
                Un = U.copy()
                Un[free] += step * dU
                Jn, Gn, Jcn, nactn, fsn = energy_grad(Un)
                if Jn <= Jv + 1e-4 * step * (G[free] @ dU) + 1e-14 * abs(Jv):
                    ok = True
                    break
                step *= 0.5
            if not ok:
                reason = "line search failed"
                break
            U, Jv, G, Jc, nact, fs = Un, Jn, Gn, Jcn, nactn, fsn
            res = float(np.abs(G[free]).max())
            residuals.append(res)
            energies.append(float(Jv))
            active_hist.append(nact)
            if res <= tol * fs:
                reason, converged = "converged", True
                break
            # cycling: an earlier nodal contact pattern returns and the energy (the merit
            # the line search decreases) has not decreased since: no progress is possible.
            # (The residual is no measure here: line-search steps may raise it.)
            key = tuple(np.round(np.concatenate(
                [np.sign(U[2 * d] * n[0] + U[2 * d + 1] * n[1] - gn)
                 for e, p, d, n, idx, gn in term.items]), 0))
            if key in seen and Jv >= energies[seen[key]] - 1e-14 * abs(Jv):
                if step * np.abs(dU).max() <= 1e-8 * np.abs(U[free]).max():
                    # tiny steps, no energy decrease: stagnation at round-off, not cycling
                    reason, converged = ("converged (stagnation at round-off level; the "
                                         "residual is limited by the conditioning)"), True
                else:
                    reason = (f"cycling: active set of iterate {seen[key]} repeated at {it} "
                              "without energy decrease")
                break
            seen[key] = it
    p_fun, p_nodes = term.pressure(U, eps)
    jac = (Sff + Jc[np.ix_(free, free)] / eps) if keep_jacobian else None
    return PenaltyResult(U=U, iterations=it, residuals=residuals, converged=converged,
                         reason=reason, eps=eps, pressure=p_fun, pressure_nodes=p_nodes,
                         energy=float(Jv), active_history=active_hist, jacobian=jac)
