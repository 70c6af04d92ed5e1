"""hp-Nitsche FE/BE coupling for the Poisson interface problem (Section 2.2).

Find U = (U1, U2) in V_hp = V1_hp x V2_hp with a_h(U, Phi) = l(Phi) for all Phi, (2.3),

    a_h(U, Phi) = (grad U1, grad Phi1)_Omega1 + <S_hat U2, Phi2>_Sigma2
                  - <dn U1, [Phi]>_GI - <[U], dn Phi1>_GI
                  + <lambda_Nit h1^-1 p1^alpha [U], [Phi]>_GI,                    (2.4)
    l(Phi)      = (f, Phi1)_Omega1 + <t_hat, Phi>_GN,

[U] = U1 - U2 on Gamma_I, dn = grad . n1 with n1 the outer normal of Omega1 (the one-sided
flux {dn Phi} := dn Phi1 of [31]); h1, p1: size and degree of the FE element K at x.

Algebraic form (Section 2.2.4), dofs not on Gamma_D only:

    [ A1 - F11 - F11^T + lambda_nit P11     F21^T - lambda_nit P12 ] [U1]   [f1]
    [ F21 - lambda_nit P12^T                S_hat + lambda_nit P22 ] [U2] = [f2]

    F11 = N^T W Dn,  F21 = B^T W Dn,  P11 = N^T W_s N,  P12 = N^T W_s B,  P22 = B^T W_s B,

with N, Dn, B the FE values, FE normal derivatives and BE values (V_hp trace matrix) at the
Gauss points of the common refinement (:mod:`.interface`), W the weights and
W_s = W h1^-1 p1^alpha.  Everything except the factor lambda_nit = lambda_Nit is assembled
once (``NitscheFEBE.__init__``), so a lambda_Nit sweep only rescales the penalty blocks
(``blocks(lambda_nit)``).

alpha and h1: the thesis does not state the alpha of its experiments, and defines h_K as
the diameter of K.  The defaults DEFAULT_ALPHA = 0 and h1 = the length of K's edge on
Gamma_I (``h_def="edge"``; for the square elements of the examples the side, diam K / sqrt 2)
are the choices that reproduce the thesis's FE errors: with them Table 2.2 (p = 1, 2, 3,
h^-1 = 2) and Table 2.4 (h^-1 = 4, 8, 16) come out equal to all printed digits, while
alpha = 2 or h_def="diameter" change the p = 2, 3 errors by 10-60 % (experiments/ch2_*.py
record the comparison).  alpha = 2, the choice that makes the bound of Lemma 2.2.3
p-independent, is available as a parameter.

Solver (``solve``): the FE block is large and sparse, S_hat is small and dense.  The whole
system is factorised once per lambda by a sparse LU (SuperLU in symmetric mode,
:mod:`hpfebe.solvers.sparse_lu`) with the n2 x n2 BE block stored as a
dense block inside the sparse matrix: the FE block is never densified, and the fill the
dense block causes stays within its n2 rows and columns (static condensation onto the BE
dofs would need one FE solve per coupled BE dof).  The relative residual of the full
system is computed and returned; a singular or inaccurate solve raises.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp

from ..bem import LaplaceBEM
from ..fem.meshes import FEDomain, tensor_block_mesh
from ..fem.poisson import PoissonFE
from ..geometry import BoundaryMesh
from ..quadrature import gauss_legendre
from ..solvers import SolverInfo
from ..solvers.sparse_lu import solve_checked
from .interface import interface_rule

log = logging.getLogger(__name__)

DEFAULT_ALPHA = 0.0
DEFAULT_LAMBDA = 10.0
DEFAULT_H_DEF = "edge"


@dataclass(frozen=True)
class InterfaceProblem:
    """An FE/BE interface problem (2.2) with known solution (the thesis's two:
    :mod:`hpfebe.scenes.interface`).

    Meshes: the FE mesh of size 1/h_inv is the per-block tensor grid of
    :func:`~hpfebe.fem.meshes.tensor_block_mesh` on the blocks ``xbreaks`` x ``ybreaks``
    inside ``in_omega1``; the BE mesh of size 1/h_inv puts ``ceil(|side| h_inv)`` equal
    elements on each side of the polygon dOmega2 (``be_vertices``, labels ``be_labels``:
    "D" on Gamma_D, "I" on the interface).  FE boundary facets are labelled by
    ``fe_label``: "D", "I" (on dOmega2) or "N".

    ``u(x, y)``, ``grad_u(x, y) -> (ux, uy)`` and ``f(x, y)`` (None: f = 0) are vectorised.
    ``singular_points``: where grad u is unbounded (error integrals are graded there).
    """

    name: str
    u: Callable
    grad_u: Callable
    f: Callable | None
    xbreaks: tuple
    ybreaks: tuple
    in_omega1: Callable
    in_omega2: Callable
    fe_label: Callable
    be_vertices: tuple
    be_labels: tuple
    singular_points: tuple = ()

    def fe_domain(self, h_inv: float) -> FEDomain:
        """FE mesh of Omega1 with cells of size <= 1/h_inv (class doc)."""
        return tensor_block_mesh(self.xbreaks, self.ybreaks, h_inv, self.in_omega1,
                                 self.fe_label)

    def omega2_domain(self, h_inv: float) -> FEDomain:
        """Rectangle mesh of Omega2 of size 1/h_inv (for the BE-part domain errors)."""
        v = np.asarray(self.be_vertices, dtype=float)
        return tensor_block_mesh(np.unique(v[:, 0]), np.unique(v[:, 1]), h_inv,
                                 self.in_omega2, lambda x, y: np.full(np.shape(x), "B"))

    def be_mesh(self, h_inv: float, p: int) -> BoundaryMesh:
        """Boundary mesh of dOmega2 with elements of size <= 1/h_inv and degree p."""
        if not (np.isfinite(h_inv) and h_inv > 0):
            raise ValueError(f"h_inv must be positive, got {h_inv!r}")
        v = np.asarray(self.be_vertices, dtype=float)
        sides = np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
        n = [max(1, int(np.ceil(L * h_inv - 1e-9))) for L in sides]
        return BoundaryMesh.polygon(v, n=n, labels=list(self.be_labels), p=p)


@dataclass
class NitscheSolution:
    """Solution of (2.3): U1 (FE, all dofs of ``fe``), U2 (BE, all dofs of ``V_space``),
    and diagnostics (``info``: residual, timings, sizes; ``solver``: the
    :class:`hpfebe.solvers.SolverInfo` of the direct solve, residuals relative to the
    right-hand side)."""

    lambda_nit: float
    U1: np.ndarray
    U2: np.ndarray
    info: dict = field(default_factory=dict)
    solver: SolverInfo | None = None


class NitscheFEBE:
    """The coupled system (2.3)-(2.4) of one pair of meshes and degrees.

    Parameters
    ----------
    problem
        InterfaceProblem (geometry, exact solution, data)
    fe_h_inv, be_h_inv
        inverse mesh sizes of the FE mesh of Omega1 and the BE mesh of
        dOmega2 (non-matching on Gamma_I in general)
    p_fe, p_be
        polynomial degrees p1 (FE) and p2 (BE; default p1)
    alpha
        exponent of p1 in the penalty term (2.4)
    h_def
        "diameter" (h_K = diam K, Section 2.1) or "edge" (edge length on Gamma_I)
    """

    def __init__(self, problem: InterfaceProblem, fe_h_inv: float, be_h_inv: float,
                 p_fe: int, p_be: int | None = None, alpha: float = DEFAULT_ALPHA,
                 h_def: str = DEFAULT_H_DEF):
        if not isinstance(problem, InterfaceProblem):
            raise ValueError(f"problem must be an InterfaceProblem, got {problem!r}")
        if not np.isfinite(alpha):
            raise ValueError(f"alpha must be a finite number, got {alpha!r}")
        for name, p in (("p_fe", p_fe), ("p_be", p_be)):
            if p is None and name == "p_be":
                continue
            if (isinstance(p, (bool, np.bool_))
                    or not isinstance(p, (int, float, np.integer, np.floating))
                    or not np.isfinite(p) or p != int(p) or p < 1):
                raise ValueError(f"{name} must be an integer >= 1, got {p!r}")
        p_be = p_fe if p_be is None else p_be
        for name, h in (("fe_h_inv", fe_h_inv), ("be_h_inv", be_h_inv)):
            if isinstance(h, (bool, np.bool_)) or not (
                    isinstance(h, (int, float, np.integer, np.floating))
                    and np.isfinite(h) and h > 0):
                raise ValueError(f"{name} must be a positive number, got {h!r}")
        self.problem, self.alpha, self.h_def = problem, float(alpha), h_def
        self.p_fe, self.p_be = int(p_fe), int(p_be)
        self.fe_h_inv, self.be_h_inv = float(fe_h_inv), float(be_h_inv)
        t = {}
        t0 = time.perf_counter()
        self.domain = problem.fe_domain(fe_h_inv)
        self.fe = PoissonFE(self.domain, self.p_fe)
        A = self.fe.K
        t["fe_stiffness"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        self.be_mesh = problem.be_mesh(be_h_inv, self.p_be)
        self.bem = LaplaceBEM(self.be_mesh)
        V = self.bem.V_space
        S_hat = self.bem.S_hat
        t["be_S_hat"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        fixed2 = V.dofs_on("D")
        mask = np.ones(V.ndof, dtype=bool)
        mask[fixed2] = False
        self.free1, self.free2 = self.fe.free, np.flatnonzero(mask)
        # Gauss points per piece: exact for the mass (p1 + p2) and flux (2 p1) terms
        order = max(self.p_fe, self.p_be) + 1
        self.rule = rule = interface_rule(self.domain, self.be_mesh, order, h_def)
        N, Gx, Gy = self.fe.eval_matrices(rule.x, rule.fe_cell)
        # FE normal derivatives at the interface points (all FE dofs; also for coercivity)
        self.Dn = Dn = sp.diags(rule.n1[:, 0]) @ Gx + sp.diags(rule.n1[:, 1]) @ Gy
        Bv = V.trace_matrix(rule.be_elem, rule.t_be)
        sigma = self.fe.p ** self.alpha / rule.h1           # h1^-1 p1^alpha
        W, Ws = sp.diags(rule.w), sp.diags(rule.w * sigma)
        f1, f2 = self.free1, self.free2
        NT, BT = N.T.tocsr(), Bv.T.tocsr()
        self.A1 = A[f1][:, f1].tocsr()
        self.S = np.ascontiguousarray(S_hat[np.ix_(f2, f2)])
        self.F11 = (NT @ W @ Dn).tocsr()[f1][:, f1]
        self.F21 = (BT @ W @ Dn).tocsr()[f2][:, f1]
        self.P11 = (NT @ Ws @ N).tocsr()[f1][:, f1]
        self.P12 = (NT @ Ws @ Bv).tocsr()[f1][:, f2]
        self.P22 = (BT @ Ws @ Bv).toarray()[np.ix_(f2, f2)]
        t["coupling"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        self.b1 = (self.fe.load(problem.f)
                   + self.fe.neumann_load(problem.grad_u, ("N",)))[f1]
        self.b2 = self._be_neumann_load()[f2]
        t["rhs"] = time.perf_counter() - t0
        self.timings = t
        self.n1, self.n2 = len(f1), len(f2)
        log.debug("Nitsche %s: FE h^-1=%g p=%d (%d dofs), BE h^-1=%g p=%d (%d dofs), "
                  "%d interface pieces", problem.name, fe_h_inv, self.p_fe, self.n1,
                  be_h_inv, self.p_be, self.n2, rule.n_pieces)

    @property
    def ndof(self) -> int:
        """Number of unknowns (FE + BE, Dirichlet dofs excluded)."""
        return self.n1 + self.n2

    def _be_neumann_load(self) -> np.ndarray:
        """<t_hat, Phi2> on BE elements labelled "N" (t_hat = grad u . n2, n2 outward
        for Omega2).  Zero for the thesis's examples (no BE Neumann part)."""
        mesh, V = self.be_mesh, self.bem.V_space
        out = np.zeros(V.ndof)
        els = np.flatnonzero(mesh.where("N"))
        if els.size == 0:
            return out
        xq, wq = gauss_legendre(self.p_be + 6)
        e = np.repeat(els, len(xq))
        t = np.tile(xq, len(els))
        x = mesh.points(e, t)
        gx, gy = self.problem.grad_u(x[:, 0], x[:, 1])
        n = mesh.normals[e]
        g = (gx * n[:, 0] + gy * n[:, 1]) * np.tile(wq, len(els)) * mesh.lengths[e] / 2
        return V.trace_matrix(e, t).T @ g

    # ----------------------------------------------------------------- the system
    def blocks(self, lambda_nit: float):
        """K11 (sparse), K12 (sparse), K22 (dense) of the system for lambda_Nit."""
        lambda_nit = self._check_lambda(lambda_nit)
        K11 = (self.A1 - self.F11 - self.F11.T + lambda_nit * self.P11).tocsc()
        K12 = (self.F21.T - lambda_nit * self.P12).tocsc()
        K22 = self.S + lambda_nit * self.P22
        return K11, K12, K22

    def matrix(self, lambda_nit: float, blocks=None) -> sp.csr_matrix:
        """The whole system matrix (sparse, BE block stored densely) - for checks;
        ``blocks``: ``self.blocks(lambda_nit)`` if already at hand."""
        K11, K12, K22 = self.blocks(lambda_nit) if blocks is None else blocks
        return sp.bmat([[K11, K12], [K12.T, sp.csr_matrix(K22)]]).tocsr()

    @staticmethod
    def _check_lambda(lambda_nit) -> float:
        value = float(lambda_nit)
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"lambda_nit (lambda_Nit) must be a finite number >= 0, "
                             f"got {lambda_nit!r}")
        return value

    def solve(self, lambda_nit: float = DEFAULT_LAMBDA) -> NitscheSolution:
        """Solve (2.3) by one sparse LU of the coupled system (module doc).

        Parameters
        ----------
        lambda_nit : float
            the Nitsche parameter lambda_Nit (default :data:`DEFAULT_LAMBDA` = 10)

        Returns
        -------
        NitscheSolution
            U1 (FE, all dofs), U2 (BE, all V_hp dofs), ``info`` (residual, timings,
            sizes) and ``solver`` (the SolverInfo of the direct solve).

        Raises
        ------
        numpy.linalg.LinAlgError
            if the coupled system is singular or its relative residual exceeds 1e-6.
        """
        t0 = time.perf_counter()
        lambda_nit = self._check_lambda(lambda_nit)
        K11, K12, K22 = blocks = self.blocks(lambda_nit)
        K21 = K12.T.tocsr()
        try:
            x, _, lu_kind = solve_checked(self.matrix(lambda_nit, blocks),
                                          np.concatenate([self.b1, self.b2]))
        except RuntimeError as exc:
            raise np.linalg.LinAlgError(f"coupled system singular for lambda_Nit="
                                        f"{lambda_nit}: {exc}") from exc
        U1, U2 = x[:self.n1], x[self.n1:]
        r1 = K11 @ U1 + K12 @ U2 - self.b1
        r2 = K21 @ U1 + K22 @ U2 - self.b2
        bnorm = np.sqrt(self.b1 @ self.b1 + self.b2 @ self.b2)
        res = float(np.sqrt(r1 @ r1 + r2 @ r2) / max(bnorm, np.finfo(float).tiny))
        if not (np.all(np.isfinite(U1)) and np.all(np.isfinite(U2))):
            raise FloatingPointError(f"solution not finite for lambda_Nit={lambda_nit}")
        if res > 1e-6:
            raise np.linalg.LinAlgError(f"coupled solve inaccurate for lambda_Nit="
                                        f"{lambda_nit}: relative residual {res:.2e}")
        full1 = np.zeros(self.fe.ndof)
        full1[self.free1] = U1
        full2 = np.zeros(self.bem.V_space.ndof)
        full2[self.free2] = U2
        info = {"residual": res, "solve_s": time.perf_counter() - t0, "n_fe": self.n1,
                "n_be": self.n2, **self.timings}
        info["lu"] = lu_kind
        solver = SolverInfo(True, f"converged (sparse LU, {lu_kind}; relative residual "
                            "checked)", 1, [1.0, res])
        return NitscheSolution(float(lambda_nit), full1, full2, info, solver)
