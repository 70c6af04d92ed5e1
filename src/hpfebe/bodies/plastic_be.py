"""An elastoplastic boundary element body (thesis Section 4.2.4, (4.28)-(4.33),
Algorithm 4.2): boundary displacement unknowns with the discrete Steklov-Poincare operator
S_hat of :class:`hpfebe.bem.lame.LameBEM`, the plastic strain piecewise constant on cells
of the work piece (:class:`hpfebe.fem.newton_potential.CellComplex`), updated from the
cell-average strain by the J2 return map (:mod:`hpfebe.constitutive.j2`).

A body of :mod:`hpfebe.bodies`, below the contact problems: it needs the boundary
operators, the Newton potential of :mod:`hpfebe.fem.newton_potential` and the J2 return
map; :class:`PlasticBEBody` is its contact-body wrapper (like
:class:`hpfebe.bodies.body.PlasticFEBody`).

The boundary equation (4.29) and the strain in the cells: the operators of
:mod:`hpfebe.bodies.cell_operators` (:class:`CellStrainOperators`, the base of
:class:`ElastoPlasticBE`).

**Algorithm 4.2** (forward Euler in eps_p, backward Euler for contact): the matrix is
S_hat alone; the plastic strain enters the right-hand side.  ``internal_force(u)``
returns (S_hat u - G tau(eps_p committed), S_hat): a pure function of u and the committed
history (the body protocol of :mod:`hpfebe.bodies.body`), and ``commit(u)`` performs
the return map per cell (cell-average strain) from the committed state with the strain at u -
the plastic strain is one load step behind (explicit), so the result depends on the step
size (tests/bodies/test_plastic_be.py measures it).  ``staggered_step`` iterates the update
within one load step (Algorithm 4.2 step v with eps_p^(k) in b, the fixed point of
:func:`hpfebe.solvers.fixed_point`) - it converges to the implicit solution, linearly
with a rate near 1 - 2 mu / (2 mu + 2/3 H) ... (slow for small hardening).

**Near-perfect plasticity (the thesis material of Section 4.4: E / sigma_Y = 66700,
H = 450).**  Two things matter, both measured (notes in tests/bodies/test_plastic_be.py):

* the forward Euler update is first order in the step and stiff by the elastic predictor:
  a lift increment of 4.2e-4 is ~30 yield strains; the Example 2 stamp reaction is 352
  with 10 increments, 125 with 40, against 24.8 with backward Euler (h = 0.4).  The
  figures therefore use ``scheme="implicit"``: the backward Euler cell strains at u,
  F(e) = e - B u - M tau(RM(e)) = 0, solved by :func:`hpfebe.solvers.newton` with
  Armijo line search and the Jacobian reduced to the plastic cells
  (:class:`_CellStrainProblem`), and the consistent tangent for the contact Newton;
* constant plastic strain on axis-parallel squares locks under isochoric flow (its
  compatible isochoric fields are shears along the grid lines; the punch mechanism runs
  at 45 degrees): 65 / 33 / 18 % too stiff on a punch with 4 / 8 / 16 squares per unit,
  first order - discretisation, not a bug.  Four triangles per square through its centre
  (:func:`crossed_cells`) are within 2.2 % of the B-bar FE body on the same grid.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..bem.lame import LameBEM
from ..checks import array, choice, instance, integer, tolerance
from ..geometry import BoundaryMesh
from ..fem.elasticity import rectangle_mesh
from ..fem.newton_potential import CellComplex, initial_stress
from .body import BEBody
from .cell_kernels import _cell_return_kernel, _plastic_blocks, _times_blocks
from .refined_lu import RefinedLU
from .cell_operators import SHARED_MAX, CellStrainOperators, match_nodes
from ..constitutive.j2 import J2Material, J2State, ReturnMap, embed_plane, return_map, \
    tensor_norm, dev
from ..solvers import Iterate, LineSearch, SingularStep, fixed_point, newton

SCHEMES = ("explicit", "implicit")
#: inner solutions kept per committed state (:meth:`ElastoPlasticBE.implicit_response_lazy`):
#: the contact Newton's refined line search returns to a point it evaluated one to three
#: trials before (measured: 13 of 130 inner solves of the BE/BE run at h = 0.4, theta = 1)
RECENT_SOLVES = 4


# tau_a = sum_ij TAU_SEL[a, i, j] (C : eps_p)_ij, eps = sum_b e_b EPS_SEL[b]
_TAU_SEL = np.zeros((3, 3, 3))
_TAU_SEL[0, 0, 0] = _TAU_SEL[1, 1, 1] = _TAU_SEL[2, 0, 1] = 1.0
_EPS_SEL = np.zeros((3, 3, 3))
_EPS_SEL[0, 0, 0] = _EPS_SEL[1, 1, 1] = 1.0
_EPS_SEL[2, 0, 1] = _EPS_SEL[2, 1, 0] = 0.5


class ElastoPlasticBE(CellStrainOperators):
    """J2 elastoplastic BE body.  ``bem``: :class:`~hpfebe.bem.LameBEM` of degree 1 (plane strain),
    ``cells``: :class:`CellComplex` covering the region where plastic strain may appear
    (the whole work piece or a part of it, its nodes on Gamma coinciding with BEM nodes),
    ``material``: :class:`J2Material` with the BEM's E and nu."""

    kind = "BE"

    def __init__(self, bem: LameBEM, cells: CellComplex, material: J2Material,
                 scheme: str = "explicit"):
        self.scheme = choice("scheme", scheme, SCHEMES)
        instance("material", material, J2Material)
        if isinstance(bem, LameBEM) and not (np.isclose(bem.E, material.E) and
                                             np.isclose(bem.nu, material.nu)):
            raise ValueError(f"material (E={material.E}, nu={material.nu}) must have the "
                             f"bem's E={bem.E}, nu={bem.nu}")
        self.material = material
        super().__init__(bem, cells, material.E, material.nu)
        self.committed = J2State.zeros(cells.ncells)
        self.sigma = np.zeros((cells.ncells, 3, 3))
        self.plastic = np.zeros(cells.ncells, dtype=bool)

    def node_displacements(self, u: np.ndarray) -> np.ndarray:
        """(n, 2) displacement at the cell nodes for the boundary displacement u and the
        committed plastic strain: the P1 trace at nodes on Gamma (BEM nodes), the
        representation formula (:meth:`point_operators`) at the others - the interior
        of the BE body sampled on its cell grid, as the thesis does for its figures."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.ndofs,):
            raise ValueError(f"u must have shape ({self.ndofs},), got {u.shape}")
        mesh = self.bem.mesh
        idx = match_nodes(self.cells.nodes, mesh.nodes, 1e-9 * mesh.diameter)
        node_dof = np.full(len(mesh.nodes), -1)
        node_dof[mesh.elements[:, 0]] = self.bem.V_space.elem_dofs[:, 0]
        node_dof[mesh.elements[:, 1]] = self.bem.V_space.elem_dofs[:, 1]
        out = np.zeros((len(self.cells.nodes), 2))
        on = idx >= 0
        d = node_dof[idx[on]]
        out[on] = np.stack([u[2 * d], u[2 * d + 1]], axis=1)
        if np.any(~on):
            R, Ut = self.point_operators(self.cells.nodes[~on])
            out[~on] = (R @ u + Ut @ self.tau(self.committed.eps_p)).reshape(-1, 2)
        return out

    def cells_at(self, point, tol: float = 1e-9) -> np.ndarray:
        """Indices of the cells containing or touching ``point`` (convex cells)."""
        x = np.asarray(point, dtype=float)
        if x.shape != (2,) or not np.all(np.isfinite(x)):
            raise ValueError(f"point must be two finite coordinates, got {point!r}")
        cx = self.cells
        P = cx.nodes[cx.cells]
        Q = np.roll(P, -1, axis=1)
        cross = (Q[..., 0] - P[..., 0]) * (x[1] - P[..., 1]) - \
            (Q[..., 1] - P[..., 1]) * (x[0] - P[..., 0])
        h = np.sqrt(cx.areas)
        hit = np.flatnonzero(np.all(cross >= -tol * h[:, None] ** 2, axis=1))
        if hit.size == 0:
            raise ValueError(f"point {tuple(x)} lies in no cell")
        return hit

    def value_at(self, key: str, point) -> float:
        """The committed cell field ``key`` of :meth:`fields` at ``point``, averaged over
        the cells touching it (the rule of the FE work piece)."""
        f = self.fields()
        if key not in f:
            raise ValueError(f"key must be one of {sorted(f)}, got {key!r}")
        return float(f[key][self.cells_at(point)].mean())

    # ------------------------------------------------------------------ fields
    def tau(self, eps_p: np.ndarray) -> np.ndarray:
        """(3 ncell,) initial stress of the cell plastic strains (ncell, 3, 3)."""
        return initial_stress(eps_p, self.E, self.nu).ravel()

    def strain(self, u: np.ndarray, eps_p: np.ndarray | None = None) -> np.ndarray:
        """(ncell, 3, 3) total strain (plane strain embedding) at the cell points for the
        boundary displacement u and the cell plastic strain (default: committed)."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.ndofs,):
            raise ValueError(f"u must have shape ({self.ndofs},), got {u.shape}")
        ep = self.committed.eps_p if eps_p is None else eps_p
        g = (self.A_u @ u + self.A_tau @ self.tau(ep)).reshape(-1, 2, 2)
        return embed_plane(0.5 * (g + np.swapaxes(g, 1, 2)))

    def plastic_force(self, eps_p: np.ndarray | None = None) -> np.ndarray:
        """G(eps_p, Phi_i) of (4.29) for every boundary basis function."""
        ep = self.committed.eps_p if eps_p is None else eps_p
        return self.G @ self.tau(ep)

    # ------------------------------------------------------------------ protocol
    def internal_force(self, u: np.ndarray):
        """``scheme="explicit"`` (Algorithm 4.2): (S_hat u - G(eps_p committed), S_hat),
        the plastic strain only on the right-hand side.  ``scheme="implicit"`` (beyond
        the thesis): (S_hat u - G(tau*(u)), K_T) with tau*(u) the backward Euler plastic
        state at the boundary displacement u (:meth:`implicit_response`) and its exact
        derivative K_T = S_hat - G (I - D Sym A_tau)^-1 D Sym A_u (D = (C - C_alg) per
        cell, in-plane)."""
        u = np.asarray(u, dtype=float)
        if self.scheme == "explicit":
            return self.S @ u - self.plastic_force(), self.K
        tau, _, KT = self.implicit_response(u)
        return self.S @ u - self.G @ tau, sp.csr_matrix(KT)

    def internal_force_lazy(self, u: np.ndarray):
        """(f_int(u), a callable returning the tangent at u, CSR as
        :meth:`internal_force`); ``scheme="implicit"``: K_T computed only when called
        (:meth:`implicit_response_lazy`)."""
        u = np.asarray(u, dtype=float)
        if self.scheme == "explicit":
            return self.S @ u - self.plastic_force(), lambda: self.K
        tau, _, tangent = self.implicit_response_lazy(u)
        return self.S @ u - self.G @ tau, lambda: sp.csr_matrix(tangent())

    def _sym_rows(self, X: np.ndarray) -> np.ndarray:
        """Displacement-gradient rows (4 c + 2 i + m) of X -> strain rows (3 c + a),
        a: (eps11, eps22, 2 eps12)."""
        A = X.reshape(self.cells.ncells, 4, -1)
        return np.stack([A[:, 0], A[:, 3], A[:, 1] + A[:, 2]], axis=1).reshape(
            3 * self.cells.ncells, -1)

    def _strain_operators(self):
        """(M, B): cell strains e = B u + M tau (e = (eps11, eps22, 2 eps12) per cell),
        computed once."""
        if getattr(self, "_MB", None) is None:
            self._MB = (self._sym_rows(self.A_tau), self._sym_rows(self.A_u))
        return self._MB

    def implicit_response(self, u: np.ndarray, tol: float = 1e-10, max_iter: int = 50):
        """Backward Euler plastic state at u: the cell strains e solve
        F(e) = e - B u - M tau(RM(e)) = 0 (RM the return map from the committed history,
        tau its initial stress), by :func:`hpfebe.solvers.newton` with Armijo line search
        on ||F||^2 (semismooth: the plastic set changes between iterates).  Its Jacobian
        I - M D (D = d tau / d e = (C - C_alg) in-plane, zero on elastic cells) is reduced
        to the plastic cells: (I - M_pp D_p) de_p = -F_p, de_e = -F_e + M_ep D_p de_p.
        Newton starts from the better (smaller ||F||) of the committed-state strain and the
        linear prediction e_last + (de/du)(u - u_last) from the last solve (measured:
        inner iterations per call 10 -> 4.0: 1911 in 477 calls of the four BE/BE runs of
        Example 2).  Returns (tau, ReturnMap, tangent matrix
        K_T = S_hat - G_p D_p (I - M_pp D_p)^-1 B_p); a non-converged inner solve returns
        NaN tau (the outer Newton then reports divergence and the load step is cut).
        The tangent only when asked for: :meth:`implicit_response_lazy`."""
        tau, rm, tangent = self.implicit_response_lazy(u, tol, max_iter)
        return tau, rm, tangent()

    def implicit_response_lazy(self, u: np.ndarray, tol: float = 1e-10,
                               max_iter: int = 50):
        """(tau, ReturnMap, a callable returning K_T) of :meth:`implicit_response`: the
        Jacobian I - M_pp D_p at the solution, used by the tangent (one double solve
        with the columns B_p, on the callable's first call, not at rejected line-search
        trials of the contact Newton) and by the next call's linear prediction
        (de/du) v = B v + M_p D_p (I - M_pp D_p)^-1 B_p v, one right-hand side instead
        of the columns of de/du, refined from the last Newton step's single-precision
        factors (:func:`_solve_plastic`; no factorisation at the solution).  The last
        :data:`RECENT_SOLVES` solutions at the committed state are kept (a point met
        again returns its solution and restores the prediction base of that time).
        Measured,
        the four BE/BE runs of Example 2 (CPU, interleaved A/B against the double LU at
        every step and solution and the numpy return map, load ~14 on 2 cores):
        12.0 -> 8.2 s, records within 7e-14 relative, iterations identical."""
        u = np.asarray(u, dtype=float)
        key = u.tobytes()
        for k, out, committed, ilast, info in getattr(self, "_icache", None) or ():
            if k == key and committed is self.committed:
                self._ilast, self.inner_info = ilast, info
                return out
        M, B = self._strain_operators()
        prob = _CellStrainProblem(self, M, B @ u)
        starts = [B @ u + M @ self.tau(self.committed.eps_p).ravel()]
        last = getattr(self, "_ilast", None)
        if last is not None:
            starts.append(last[1] + self._strain_derivative_times(last, u - last[0]))
        it0 = min((prob.evaluate(e0) for e0 in starts), key=lambda i: i.merit)
        it, info = newton(prob, it0.x, tol=tol, max_iter=max_iter,
                          line_search=LineSearch(max_halvings=20))
        tau, rm, D, pl = it.data
        self.inner_info = info
        p3 = MD = solve = J = None
        if pl.size:
            p3 = (3 * pl[:, None] + np.arange(3)).ravel()
            MD, J = _plastic_blocks(M, pl, D)

            def solve(rhs, pl=pl, J=J):
                return _solve_plastic(self, pl, J, rhs, exact=True)
        if info.converged:
            self._ilast = (u.copy(), it.x.copy(), p3, MD, solve)
        else:
            tau = np.full_like(tau, np.nan)
        memo = []

        def tangent() -> np.ndarray:
            if not memo:
                if p3 is None:
                    memo.append(self.S)
                else:
                    try:                                                # d e_p / d u
                        X = np.linalg.solve(J, B[p3])
                    except np.linalg.LinAlgError:   # as scipy's lu_factor did: inf/nan
                        X = sla.lu_solve(sla.lu_factor(J, check_finite=False), B[p3],
                                         check_finite=False)
                    memo.append(self.S - _times_blocks(self.G[:, p3], D[pl]) @ X)
            return memo[0]

        out = (tau, rm, tangent)
        recent = [c for c in (getattr(self, "_icache", None) or ())
                  if c[2] is self.committed][1 - RECENT_SOLVES:]
        self._icache = (*recent, (key, out, self.committed, getattr(self, "_ilast", None),
                                  info))
        return out

    def _strain_derivative_times(self, last, v: np.ndarray) -> np.ndarray:
        """(de/du) v at the last solve ``last`` = (u, e, p3, MD, lu):
        B v + MD (I - M_pp D_p)^-1 (B v)_p."""
        _, B = self._strain_operators()
        _, _, p3, MD, solve = last
        Bv = B @ v
        if p3 is None:
            return Bv
        return Bv + MD @ solve(Bv[p3])

    def update(self, u: np.ndarray, eps_p: np.ndarray | None = None):
        """Return map at the cell points from the committed state with the strain of
        (u, eps_p): the :class:`~hpfebe.constitutive.j2.ReturnMap` (a pure function)."""
        return return_map(self.material, self.strain(u, eps_p), self.committed, None)

    def commit(self, u: np.ndarray) -> None:
        """explicit: forward Euler update of the plastic strain from the committed
        state; implicit: the backward Euler state of :meth:`implicit_response`."""
        if self.scheme == "implicit":
            _, rm, _ = self.implicit_response_lazy(u)
        else:
            rm = self.update(u)
        self.committed, self.sigma, self.plastic = rm.state.copy(), rm.sigma, rm.plastic
        self._icache = None

    def staggered_step(self, solve, tol: float = 1e-8, max_iter: int = 200):
        """Algorithm 4.2 within one load step: u^(k+1) = solve(G(eps_p^(k))) (the
        elastic solve with the plastic force on the right-hand side, a callable
        returning u), eps_p^(k+1) from the return map at u^(k+1); fixed point of
        :func:`hpfebe.solvers.fixed_point` on eps_p.  Commits the converged state and
        returns (u, SolverInfo)."""
        state = {}

        def upd(x):
            ep = x.reshape(-1, 3, 3)
            u = solve(self.G @ self.tau(ep))
            rm = return_map(self.material, self.strain(u, ep), self.committed, None)
            state.update(u=u, rm=rm)
            return rm.state.eps_p.ravel()

        x0 = self.committed.eps_p.ravel()
        x, info = fixed_point(upd, x0, tol=tol, max_iter=max_iter, min_iter=1)
        rm = state["rm"]
        if info.converged:
            self.committed, self.sigma, self.plastic = rm.state.copy(), rm.sigma, rm.plastic
        return state["u"], info

    def fields(self) -> dict:
        """Cell fields of the committed state: ||eps_p||, ||dev sigma||, plastic flag."""
        return {"eps_p_norm": tensor_norm(self.committed.eps_p),
                "dev_sigma_norm": tensor_norm(dev(self.sigma)),
                "plastic": self.plastic.astype(float)}


def _tau_strain_blocks(X: np.ndarray) -> np.ndarray:
    """(n, 3, 3) blocks D_ab = sum TAU_SEL[a, i, j] X_ijkl EPS_SEL[b, k, l] of the 4th-order
    tensors X (n, 3, 3, 3, 3), by indexing: rows (11, 22, 12), columns e = (eps11, eps22,
    2 eps12) with 0.5 (X_..12 + X_..21) - the einsum over the selectors adds only
    exact zeros to these terms, so the numbers are the same bit for bit."""
    i, j = np.array([0, 1, 0]), np.array([0, 1, 1])
    Y = X[:, i, j]                                               # (n, 3, 3, 3)
    out = np.empty((len(X), 3, 3))
    out[:, :, 0] = Y[:, :, 0, 0]
    out[:, :, 1] = Y[:, :, 1, 1]
    out[:, :, 2] = 0.5 * Y[:, :, 0, 1] + 0.5 * Y[:, :, 1, 0]
    return out


def _solve_plastic(body: "ElastoPlasticBE", pl: np.ndarray, J: np.ndarray,
                   rhs: np.ndarray, exact: bool = False) -> np.ndarray:
    """J x = rhs for the cell-strain Jacobian J on the plastic cells ``pl``: refined from
    the body's last single-precision factors (``body._factor``, :class:`RefinedLU`) when
    they belong to the same plastic set and converge at least 4x per refinement step,
    else from a new factorisation of J (kept for the next call); a J that single
    precision cannot factorise goes to a double LU (singular: :class:`SingularStep`;
    ``exact``: the LU of scipy.linalg.lu_factor, no check, as at the inner solution).
    Measured (the four BE/BE runs of Example 2): 1546 double LU solves and 416 double
    LU factors at the inner solutions -> 1047 single-precision factors, about 800
    refined reuses and 199 double solves for tangents (4-5 refinement steps a solve),
    records within 7e-14 relative."""
    f = getattr(body, "_factor", None)
    if f is not None and np.array_equal(f.pl, pl):
        x = f.solve(rhs, J, max_refine=8, min_rate=0.25)
        if x is not None:
            return x
    f = RefinedLU(J, pl)
    body._factor = f
    if exact:           # the inner solution's J: a double LU if need be, as before
        return f.solve_or_exact(rhs)
    x = f.solve(rhs)
    if x is None:
        try:
            x = np.linalg.solve(J, rhs)
        except np.linalg.LinAlgError as err:
            raise SingularStep(f"cell strain Jacobian singular: {err}") from err
    return x


class _CellStrainProblem:
    """The inner problem of :meth:`ElastoPlasticBE.implicit_response` for
    :func:`hpfebe.solvers.newton`: x = cell strains e (3 ncell), residual
    F(e) = e - b - M tau(RM(e)), merit ||F||^2 / 2, key = the plastic set; the scale of
    the stopping test is max|e| + the yield strain sigma_Y / E (sigma_Y capped at 1e-3 E,
    :attr:`J2Material.stress_floor`)."""

    def __init__(self, body: "ElastoPlasticBE", M: np.ndarray, b: np.ndarray):
        self.body, self.M, self.b = body, M, b
        mat, st = body.material, body.committed
        self.eY = mat.stress_floor / mat.E
        self.consts = (mat.mu, mat.kappa, mat.lam, mat.H, mat.theta, mat.sigma_Y)
        self.history = tuple(np.ascontiguousarray(a, dtype=float)
                             for a in (st.eps_p, st.alpha, st.beta))

    def evaluate(self, e: np.ndarray) -> Iterate:
        """F(e) with the return map, tau and the D blocks of every cell from one fused
        kernel (:func:`~hpfebe.bodies.cell_kernels._cell_return_kernel`; measured: 3081
        evaluations of the four BE/BE runs of Example 2 2.8 -> 0.5 s CPU)."""
        (tau, D, plastic, sigma, eps_p, alpha, beta, dgamma, f_trial, normal,
         safe) = _cell_return_kernel(np.ascontiguousarray(e.reshape(-1, 3)),
                                     *self.history, *self.consts)
        rm = ReturnMap(sigma, J2State(eps_p, alpha, beta), None, dgamma, plastic,
                       f_trial, normal, safe)
        tau = tau.ravel()
        F = e - self.b - self.M @ tau
        scale = float(np.abs(e).max(initial=0.0)) + self.eY
        return Iterate(e, F, 0.5 * float(F @ F), scale, key=plastic.tobytes(),
                       data=(tau, rm, D, np.flatnonzero(plastic)))

    def step(self, it: Iterate) -> np.ndarray:
        """Newton direction: J dx = -F with J = I - M D reduced to the plastic cells, by
        :func:`_solve_plastic` (the single-precision factors of the last J refined in
        double when the plastic set is the same)."""
        F, (_, _, D, pl) = it.residual, it.data
        dx = -F
        if pl.size:
            p3 = (3 * pl[:, None] + np.arange(3)).ravel()
            el = np.ones(F.size, dtype=bool)
            el[p3] = False
            el = np.flatnonzero(el)
            MDe, J = _plastic_blocks(self.M, pl, D, el)   # M_ep D_p, I - M_pp D_p
            dp = _solve_plastic(self.body, pl, J, -F[p3])
            dx[el] += MDe @ dp                            # dx = -F: a new array
            dx[p3] = dp
        return dx

    def slope(self, it: Iterate, dx: np.ndarray) -> float:
        return -2.0 * it.merit


class DirichletSolver:
    """The elastic solve of Algorithm 4.2 for a body without contact: boundary dofs
    ``fixed`` prescribed to lam * ``values``, the free dofs loaded by lam * ``f_ext`` and
    the plastic force g:  S_hat_ff u_f = g_f + lam f_ext_f - S_hat_fc u_c  (S_hat_ff
    factorised once; the prescribed dofs must remove the rigid motions)."""

    def __init__(self, body: ElastoPlasticBE, fixed, values, f_ext=None):
        instance("body", body, ElastoPlasticBE)
        n = body.ndofs
        self.fixed = array("fixed", fixed, ndim=1, dtype=np.int64)   # 1.5 is no dof
        if self.fixed.size == 0 or self.fixed.min() < 0 or self.fixed.max() >= n:
            raise ValueError(f"fixed must be a non-empty list of dofs in [0, {n})")
        if np.unique(self.fixed).size != self.fixed.size:
            raise ValueError("fixed must not contain duplicates")
        values = array("values", values)
        if values.shape not in ((), self.fixed.shape):
            raise ValueError(f"values must be a scalar or one value per fixed dof "
                             f"({self.fixed.size}), got shape {values.shape}")
        self.values = np.broadcast_to(values, self.fixed.shape).copy()
        self.f_ext = np.zeros(n) if f_ext is None else array("f_ext", f_ext, shape=(n,))
        self.free = np.setdiff1d(np.arange(n), self.fixed)
        S = body.S
        self.S_fc = S[np.ix_(self.free, self.fixed)]
        self.cho = sla.cho_factor(S[np.ix_(self.free, self.free)])
        self.n, self.lam = n, 0.0

    def __call__(self, g: np.ndarray) -> np.ndarray:
        u = np.zeros(self.n)
        u[self.fixed] = self.lam * self.values
        rhs = g[self.free] + self.lam * self.f_ext[self.free] - self.S_fc @ u[self.fixed]
        u[self.free] = sla.cho_solve(self.cho, rhs)
        return u


def staggered_path(body: ElastoPlasticBE, solver: DirichletSolver, factors,
                   tol: float = 1e-8, max_iter: int = 200):
    """Algorithm 4.2 for a body without contact: for every load factor (increasing),
    :meth:`ElastoPlasticBE.staggered_step` (eps_p iterated to the fixed point, then
    committed).  ``max_iter=1`` is the one-pass forward Euler of the thesis (eps_p
    updated once per load step; reported as not converged by the fixed point, accepted
    here).  Returns (u, list of SolverInfo); stops at the first step whose fixed point
    did not converge (with ``max_iter`` > 1)."""
    instance("solver", solver, DirichletSolver)
    factors = array("factors", factors, ndim=1, min_size=1)
    if np.any(np.diff(factors) <= 0):
        raise ValueError(f"factors must be an increasing sequence of load factors, got "
                         f"{factors.tolist()}")
    tol, max_iter = tolerance("tol", tol), integer("max_iter", max_iter, lo=1)
    infos, u = [], np.zeros(body.ndofs)
    for lam in factors:
        solver.lam = float(lam)
        if max_iter == 1:
            u = solver(body.plastic_force())
            body.commit(u)
            continue
        u, info = body.staggered_step(solver, tol=tol, max_iter=max_iter)
        info.load_factor = float(lam)
        infos.append(info)
        if not info.converged:
            break
    return u, infos


class PlasticBEBody(BEBody):
    """An :class:`ElastoPlasticBE` as a contact body (kind "BE", the BEBody geometry of
    its boundary mesh): internal_force(u) = (S_hat u - G(eps_p committed), S_hat) and
    commit(u) the forward Euler update of eps_p - Algorithm 4.2: backward Euler (Newton)
    for the contact, forward Euler for the plasticity, only the contact blocks of the
    matrix (4.33) change.  With ``scheme="implicit"`` the body's backward Euler force and
    consistent tangent instead (beyond the thesis)."""

    linear = False

    def __init__(self, be: ElastoPlasticBE):
        instance("be", be, ElastoPlasticBE)
        super().__init__(be.bem, S=be.S)
        self.plastic = be

    def internal_force(self, u):
        f, T = self.plastic.internal_force(u)
        return f, (self.S if self.plastic.scheme == "explicit" else T.toarray())

    def internal_force_lazy(self, u):
        """(f_int, the dense tangent or a callable returning it): ``scheme="implicit"``:
        K_T only when asked for (:meth:`ElastoPlasticBE.implicit_response_lazy`)."""
        be = self.plastic
        if be.scheme == "explicit":
            return self.internal_force(u)
        u = np.asarray(u, dtype=float)
        tau, _, tangent = be.implicit_response_lazy(u)
        return be.S @ u - be.G @ tau, tangent

    def commit(self, u) -> None:
        self.plastic.commit(u)


SIDES = ("bottom", "right", "top", "left")


CELL_KINDS = ("quad", "crossed")


def crossed_cells(nodes: np.ndarray, quads: np.ndarray) -> CellComplex:
    """Every quadrilateral split into four triangles through its centroid ("crossed"
    or union-jack cells).  Piecewise constant plastic strain on axis-parallel
    rectangles locks under isochoric flow: its compatible isochoric fields are shears
    along the grid lines only, while the plastic mechanisms of a punch run at 45
    degrees; the crossed triangles contain them (measured on the punch without contact,
    thesis material: reaction 9.09 on 4 x 32 crossed triangles against 11.09 on 128
    squares, FE B-bar Q1 8.90)."""
    nodes, quads = np.asarray(nodes, dtype=float), np.asarray(quads)
    if quads.ndim != 2 or quads.shape[1] != 4:
        raise ValueError(f"quads must have shape (n, 4), got {quads.shape}")
    c = nodes[quads].mean(axis=1)
    ci = len(nodes) + np.arange(len(quads))
    tris = np.concatenate([np.stack([quads[:, k], quads[:, (k + 1) % 4], ci], axis=1)
                           for k in range(4)])
    return CellComplex(np.vstack([nodes, c]), tris)


def rectangle_work_piece(box, nx: int, ny: int, material: J2Material,
                         scheme: str = "explicit", cells: str = "quad",
                         cell_rows: int | None = None) -> ElastoPlasticBE:
    """The BE work piece on ``box`` = (x0, x1, y0, y1): a degree-1 LameBEM (plane
    strain, sides labelled bottom/right/top/left as the FE meshes of
    :mod:`hpfebe.scenes.stamping`) and nx x ny rectangular cells carrying eps_p
    (``cells="crossed"``: each split into four triangles, :func:`crossed_cells`);
    ``cell_rows``: only the top ``cell_rows`` rows of cells (the region where plastic
    strain can appear; default all ny).  A work piece of the same geometry and elastic
    constants as one of the last SHARED_MAX (another theta) shares their LameBEM, cells
    and operators (assembled once; measured: the theta = 0 BE/BE run at h = 0.4
    5.4 -> 4.6 s CPU)."""
    nx, ny = integer("nx", nx, lo=1), integer("ny", ny, lo=1)
    choice("cells", cells, CELL_KINDS)
    rows = integer("cell_rows", ny if cell_rows is None else cell_rows, lo=1, hi=ny)
    x0, x1, y0, y1 = (float(v) for v in array("box", box, shape=(4,)))
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"box must be (x0, x1, y0, y1) with x1 > x0, y1 > y0, got {box!r}")
    key = (x0, x1, y0, y1, int(nx), int(ny), cells, int(rows), float(material.E),
           float(material.nu))
    for k, bem, cx in _WORK_PIECES:
        if k == key:        # the same geometry (another theta): its operators are shared
            return ElastoPlasticBE(bem, cx, material, scheme)
    mesh = BoundaryMesh.polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)],
                                n=[nx, ny, nx, ny], labels=list(SIDES))
    bem = LameBEM(mesh, material.E, material.nu, "strain")
    yc = y1 - (y1 - y0) * int(rows) / ny
    m = rectangle_mesh(x0, x1, yc, y1, int(nx), int(rows), "quad")
    cx = (CellComplex(m.p.T, m.t.T) if cells == "quad" else crossed_cells(m.p.T, m.t.T))
    be = ElastoPlasticBE(bem, cx, material, scheme)
    _WORK_PIECES.append((key, bem, cx))
    del _WORK_PIECES[:-SHARED_MAX]
    return be


# (key, bem, cells) of the last work pieces of rectangle_work_piece: one with the same
# geometry and elastic constants reuses them, and so the operators of
# :class:`CellStrainOperators` (assembled once for the BE/BE runs of every theta)
_WORK_PIECES: list = []
