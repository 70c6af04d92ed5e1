"""The boundary element operators of an elastoplastic BE body (thesis Section 4.2.4,
(4.28)-(4.33)): the plastic force G of the boundary equation (4.29) and the map from the
boundary displacement u and the cell initial stresses tau to the cell-average
displacement gradients, through the initial-strain Somigliana identity
(:class:`CellStrainOperators`, the base of
:class:`hpfebe.bodies.plastic_be.ElastoPlasticBE`).

**The boundary equation (4.29).**  With tau = C : eps_p (in-plane), the weak form of
div sigma = 0, sigma = C : (eps(u) - eps_p), tested with the elastic extension Phi~ of a
boundary function Phi (div C eps(Phi~) = 0), is

    <S u, Phi> - G(eps_p, Phi) = <t, Phi>,
    G(eps_p, Phi) = (C : eps_p, eps(Phi~))_Omega = sum_cells int_{d c} (tau_c n_c) . Phi~ ds,

(divergence theorem cell by cell, tau constant per cell) - the thesis's
G = -<N(div(C : eps_p)), Phi> + <(C : eps_p) n, Phi>: the cell edges on Gamma give
<tau n, Phi> (Phi~ = Phi there), the interior edges the Newton-potential part through
Phi~(y) = (V~ Psi(Phi) - K~ Phi)(y) (Somigliana with the discrete Dirichlet-to-Neumann
traction Psi, :meth:`LameBEM.representation`).  A uniform eps_p gives exactly
G = <tau n, Phi>, and u = eps_p x solves S_hat u = G (S_hat reproduces linear fields on
a polygon), so the uniform initial-strain problem is solved exactly (tested).

**The strain in the cells.**  The return map works with the cell average
eps_c = |c|^-1 int_{d c} sym(u x n) ds of the strain (one state per cell), u on the cell
edges from the initial-strain Somigliana identity u = V~ t - K~ u + w (w the Newton
potential, :func:`newton_operators`; the true traction from the first-kind equation
<V t, psi> = <(K + M/2) u, psi> - <w, psi>, with the zero-total-force projection of
LameBEM since t is in equilibrium), i.e. u = Phi~[u] - V~ P <w, .> + w on interior edges
and the P1 trace on Gamma:

    g_c = A_u u + A_tau tau  (rows 4 c + 2 i + m, g = cell-average grad u),
    G   = (area-weighted A_u)^T,

so G and the strain map are adjoint by construction.  This matters: with the strain
evaluated at the centroids instead (a first version), the map eps_p -> -dev sigma / 2 mu
had eigenvalues down to -0.19 (spurious modes; the explicit update blew up for small
hardening); with the cell averages its spectrum lies in [0, 1] as for the continuous
operator (measured, N = 4 punch).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..bem.lame import LameBEM
from ..bem.potentials import POT_LAME_DL, evaluate_potential
from ..fem.newton_potential import CellComplex, edge_integrals, kelvin_constants, \
    newton_operators

GAUSS_EDGE = 4


def _graded_rule(levels: int = 4, order: int = 8):
    """Composite Gauss rule on [0, 1] graded geometrically (ratio 1/4) towards both
    ends: w on Gamma behaves like r log r at the nodes where interior cell edges meet
    Gamma, which plain Gauss integrates only to ~1e-5."""
    left = 0.25 ** np.arange(levels, 0, -1) * 0.5                # 1/2 4^-k
    br = np.concatenate([[0.0], left, [0.5], 1.0 - left[::-1], [1.0]])
    gx, gw = np.polynomial.legendre.leggauss(order)
    a, b = br[:-1, None], br[1:, None]
    return (a + 0.5 * (gx + 1) * (b - a)).ravel(), (0.5 * gw * (b - a)).ravel()


def match_nodes(points: np.ndarray, nodes: np.ndarray, tol: float) -> np.ndarray:
    """Index of the BEM node equal to each point (within tol), -1 if none."""
    d = np.linalg.norm(points[:, None, :] - nodes[None, :, :], axis=-1)
    j = np.argmin(d, axis=1)
    return np.where(d[np.arange(len(points)), j] <= tol, j, -1)


class CellStrainOperators:
    """The operators of a BE body of degree 1 (``bem``, plane strain) with piecewise
    constant initial strain on ``cells`` (its nodes on Gamma coinciding with BEM nodes),
    elastic constants E, nu: ``A_u``, ``A_tau`` (cell-average displacement gradients
    g = A_u u + A_tau tau, rows 4 c + 2 i + m), ``G`` (the plastic force of (4.29)),
    S = S_hat, :meth:`point_operators` (the displacement at interior points)."""

    def __init__(self, bem: LameBEM, cells: CellComplex, E: float, nu: float):
        if not isinstance(bem, LameBEM):
            raise ValueError(f"bem must be a LameBEM (2D elasticity), got {type(bem).__name__}")
        if not isinstance(cells, CellComplex):
            raise ValueError(f"cells must be a CellComplex, got {type(cells).__name__}")
        if bem.plane != "strain":
            raise ValueError(f"bem must be plane strain (J2 body), got plane={bem.plane!r}")
        if not np.all(bem.mesh.degrees == 1):
            raise ValueError("bem must have degree 1 on every element (P1 displacements)")
        self.bem, self.cells = bem, cells
        self.E, self.nu = E, nu
        self.ndofs = 2 * bem.V_space.ndof
        self.S = bem.S_hat
        self.K = sp.csr_matrix(self.S)
        self.points = cells.centroids
        self._build()

    def _P(self, Y: np.ndarray) -> np.ndarray:
        """Constrained V^{-1} (zero total force, as LameBEM.Psi) applied to columns Y."""
        bem = self.bem
        X = sla.cho_solve(bem.V_cho, Y)
        if bem.constrained:
            C = bem.constraints
            VC = sla.cho_solve(bem.V_cho, C)
            X = X - VC @ np.linalg.solve(C.T @ VC, C.T @ X)
        return X

    def _columns(self, fn, n: int, pts: np.ndarray, width: int) -> np.ndarray:
        """Matrix whose column k is fn(pts, e_k) flattened (one vectorised potential
        evaluation per basis function)."""
        out = np.empty((len(pts) * width, n))
        e = np.zeros(n)
        for k in range(n):
            e[k] = 1.0
            out[:, k] = fn(pts, e).ravel()
            e[k] = 0.0
        return out

    def _build(self):
        """The cell-average displacement gradients g_c = |c|^-1 int_{d c} u (x) n ds
        (rows 4 c + 2 i + m) as A_u u + A_tau tau, and G = (area-weighted A_u)^T."""
        bem, cx = self.bem, self.cells
        mesh = bem.mesh
        nV = 2 * bem.V_space.ndof
        nc, nc3 = cx.ncells, 3 * cx.ncells
        tol = 1e-9 * mesh.diameter
        # --- cell edges on Gamma (both end nodes BEM nodes joined by a BEM element)
        ia = match_nodes(cx.nodes[cx.edges[:, 0]], mesh.nodes, tol)
        ib = match_nodes(cx.nodes[cx.edges[:, 1]], mesh.nodes, tol)
        el = {(int(a), int(b)) for a, b in mesh.elements}
        on = np.array([(a, b) in el or (b, a) in el for a, b in zip(ia, ib)])
        on &= (ia >= 0) & (ib >= 0) & cx.boundary_edge
        if not np.any(on):
            raise ValueError("cells must share edges with the BEM boundary (no cell edge "
                             "lies on Gamma: node coordinates do not match)")
        node_dof = np.full(len(mesh.nodes), -1)
        node_dof[mesh.elements[:, 0]] = bem.V_space.elem_dofs[:, 0]
        node_dof[mesh.elements[:, 1]] = bem.V_space.elem_dofs[:, 1]
        # edge weights: |c|^-1 int_e (.) n_m ds  ->  row factor n_m L_e / |c|
        fac = (cx.lengths / cx.areas[cx.edge_cell])[:, None] * cx.normals     # (S, 2)
        A_u = np.zeros((nc, 2, 2, nV))
        A_tau = np.zeros((nc, 2, 2, nc3))
        # Gamma edges: the P1 trace, int_e u ds = L/2 (u_A + u_B)
        e_on = np.flatnonzero(on)
        for ends in (ia[on], ib[on]):
            for i in range(2):
                np.add.at(A_u, (cx.edge_cell[e_on], i, slice(None), 2 * node_dof[ends] + i),
                          0.5 * fac[e_on])
        # interior edges: u(y) = Phi~[u](y) - SL(P G_w tau)(y) + w(y), Gauss points on
        # each geometric edge once (shared by two cells)
        off = np.flatnonzero(~on)
        if off.size:
            key = np.sort(cx.edges[off], axis=1)
            uniq, inv = np.unique(key, axis=0, return_inverse=True)
            inv = inv.ravel()
            gx, gw = np.polynomial.legendre.leggauss(GAUSS_EDGE)
            s, w = 0.5 * (gx + 1), 0.5 * gw
            a, b = cx.nodes[uniq[:, 0]], cx.nodes[uniq[:, 1]]
            Y = (a[:, None] + s[None, :, None] * (b - a)[:, None]).reshape(-1, 2)
            R, Ut = self.point_operators(Y)
            Ut = Ut.reshape(len(uniq), len(s), 2, nc3)
            Uu = R.reshape(len(uniq), len(s), 2, nV)
            cells_off = cx.edge_cell[off]
            np.add.at(A_u, cells_off, np.einsum("eqiv,q,em->eimv", Uu[inv], w, fac[off]))
            np.add.at(A_tau, cells_off, np.einsum("eqit,q,em->eimt", Ut[inv], w, fac[off]))
        self.A_u = A_u.reshape(4 * nc, nV)
        self.A_tau = A_tau.reshape(4 * nc, nc3)
        # G_v = sum_c |c| tau_c : g_c(phi_v)   (tau : g = t11 g11 + t22 g22 + t12 (g12 + g21))
        T = np.zeros((nc, 2, 2, nc, 3))
        c = np.arange(nc)
        T[c, 0, 0, c, 0] = T[c, 1, 1, c, 1] = T[c, 0, 1, c, 2] = T[c, 1, 0, c, 2] = 1.0
        T *= cx.areas[:, None, None, None, None]
        self.G = self.A_u.T @ T.reshape(4 * nc, nc3)

    def point_operators(self, Y: np.ndarray):
        """(R, U_tau), each with rows 2 k + i: u(Y_k) = R u + U_tau tau at interior
        points Y (the initial-strain Somigliana identity, module doc:
        u = V~ Psi(u) - K~ u + w - V~ P <w, .>)."""
        bem = self.bem
        nV = 2 * bem.V_space.ndof
        Y = np.atleast_2d(np.asarray(Y, dtype=float))
        SL = self._single_layer(Y)                                       # (2Y, nW)
        DL = -self._columns(lambda p, e: evaluate_potential(POT_LAME_DL, bem.kp, 2, p,
                                                            bem.V_space, e), nV, Y, 2)
        if getattr(self, "_PB", None) is None:
            self._PB = (self._P(bem.B), self._P(self._boundary_w()))
        Nw, _ = newton_operators(self.cells, Y, self.E, self.nu, gradient=False)
        return DL + SL @ self._PB[0], Nw - SL @ self._PB[1]

    def _single_layer(self, Y: np.ndarray) -> np.ndarray:
        """(2 len(Y), nW): the single-layer potential V~ psi at points Y of every P0
        basis function, by the closed-form segment integrals (with the log R term of
        :mod:`hpfebe.bem.lame`)."""
        bem, mesh = self.bem, self.bem.mesh
        c1, c2 = kelvin_constants(self.E, self.nu)
        IG = edge_integrals(Y, mesh.a, mesh.b, c1, c2, gradient=False)      # (P, S, 2, 2)
        IG = IG + c1 * np.log(bem.scale) * mesh.lengths[None, :, None, None] * np.eye(2)
        out = np.zeros((len(Y), 2, 2 * bem.W_space.ndof))
        d = bem.W_space.elem_dofs[:, 0]
        for k in range(2):
            out[:, :, 2 * d + k] = IG[:, :, :, k].transpose(0, 2, 1)
        return out.reshape(2 * len(Y), -1)

    def _boundary_w(self) -> np.ndarray:
        """<w, psi_j> on the boundary elements (P0 traction space), graded Gauss (w is
        like r log r where interior cell edges meet Gamma)."""
        bem, cx, mesh = self.bem, self.cells, self.bem.mesh
        nW, nc3 = 2 * bem.W_space.ndof, 3 * cx.ncells
        s, w = _graded_rule()
        Yb = (mesh.a[:, None] + s[None, :, None] * (mesh.b - mesh.a)[:, None]).reshape(-1, 2)
        Nw, _ = newton_operators(cx, Yb, self.E, self.nu, gradient=False)
        Nw = Nw.reshape(mesh.n_elements, len(s), 2, nc3)
        Gw = np.zeros((nW, nc3))
        wdof = bem.W_space.elem_dofs[:, 0]
        for c in range(2):
            Gw[2 * wdof + c] = np.einsum("eqt,q,e->et", Nw[:, :, c], w, mesh.lengths)
        return Gw
