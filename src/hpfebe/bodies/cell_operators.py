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

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..bem.lame import LameBEM
from ..bem.potentials import POT_LAME_DL, potential_matrix
from ..checks import array, instance
from ..fem.newton_potential import CellComplex, edge_integrals, kelvin_constants, \
    newton_operators
from ..geometry.containment import INSIDE, ON, classify_points, first_cut

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


@numba.njit(cache=True)
def _side(a0, a1, x, tol):
    """+1 / -1 if x lies left / right of the line a0 -> a1 by more than the distance
    ``tol``, else 0."""
    ex, ey = a1[0] - a0[0], a1[1] - a0[1]
    d = ex * (x[1] - a0[1]) - ey * (x[0] - a0[0])
    t = tol * np.sqrt(ex * ex + ey * ey)
    return 1 if d > t else (-1 if d < -t else 0)


@numba.njit(cache=True)
def _strictly_in(P, x, tol):
    """Whether x lies inside the convex counter-clockwise polygon P (k, 2), farther than
    the distance ``tol`` from the line of every edge."""
    k = P.shape[0]
    for j in range(k):
        if _side(P[j], P[(j + 1) % k], x, tol) != 1:
            return False
    return True


@numba.njit(cache=True)
def _first_overlap(nodes, cells, centroids, tol):
    """The first pair (i, j), i < j, of convex counter-clockwise cells whose interiors
    overlap: a vertex or the centroid of one strictly inside the other, or two edges
    crossing at a point inside both (the ends of each strictly on both sides of the
    other's line; "strictly": farther than the distance ``tol``); (-1, -1) if there is
    none.  Pairs with disjoint bounding boxes are skipped."""
    nc, k = cells.shape
    lo = np.empty((nc, 2))
    hi = np.empty((nc, 2))
    for i in range(nc):
        for m in range(2):
            lo[i, m] = nodes[cells[i, 0], m]
            hi[i, m] = nodes[cells[i, 0], m]
            for j in range(1, k):
                lo[i, m] = min(lo[i, m], nodes[cells[i, j], m])
                hi[i, m] = max(hi[i, m], nodes[cells[i, j], m])
    for i in range(nc):
        Pi = nodes[cells[i]]
        for j in range(i + 1, nc):
            if (lo[j, 0] >= hi[i, 0] or hi[j, 0] <= lo[i, 0] or lo[j, 1] >= hi[i, 1]
                    or hi[j, 1] <= lo[i, 1]):
                continue
            Pj = nodes[cells[j]]
            if _strictly_in(Pi, centroids[j], tol) or _strictly_in(Pj, centroids[i], tol):
                return i, j
            for v in range(k):
                if _strictly_in(Pi, Pj[v], tol) or _strictly_in(Pj, Pi[v], tol):
                    return i, j
            for u in range(k):
                a0, a1 = Pi[u], Pi[(u + 1) % k]
                for v in range(k):
                    b0, b1 = Pj[v], Pj[(v + 1) % k]
                    if _side(a0, a1, b0, tol) * _side(a0, a1, b1, tol) == -1 and \
                            _side(b0, b1, a0, tol) * _side(b0, b1, a1, tol) == -1:
                        return i, j
    return -1, -1


def check_cells(mesh, cx: CellComplex) -> None:
    """ValueError naming ``cells`` unless the cells of ``cx`` are a valid cell complex of
    the body enclosed by the boundary mesh ``mesh``: finite nodes; every cell convex and
    of an area above 1e-12 diam(body)^2 (not degenerate); every vertex inside the body or
    on Gamma, every centroid inside, no boundary element cutting a cell (then every
    cell lies in the closed body, non-convex bodies included); no two cells
    overlapping (a vertex or centroid of one inside another, crossing edges); the cells
    no larger than the body in total; and every cell edge on Gamma a BEM element (its
    ends BEM nodes; the Somigliana identity used on the other edges holds inside the
    body only).  Tolerances: 1e-9 diam(body) for distances, 1e-9 for the sine of a
    reflex angle."""
    diam = mesh.diameter
    tol = 1e-9 * diam
    nodes = array("cells.nodes", cx.nodes, shape=(None, 2))
    P = nodes[cx.cells]                                            # (nc, k, 2), ccw
    if np.any(cx.areas <= 1e-12 * diam ** 2):
        c = int(np.argmin(cx.areas))
        raise ValueError(f"cells must not be degenerate: cell {c} (vertices "
                         f"{P[c].tolist()}) has area {cx.areas[c]:.3g}, against the "
                         f"body's diameter {diam:.3g}")
    E = np.roll(P, -1, axis=1) - P                                 # edge vectors
    F = np.roll(E, -1, axis=1)                                     # the next ones
    turn = E[..., 0] * F[..., 1] - E[..., 1] * F[..., 0]           # |e| |f| sin(angle)
    L = np.linalg.norm(E, axis=-1) * np.linalg.norm(F, axis=-1)
    bad = np.flatnonzero(np.any(turn < -1e-9 * L, axis=1))
    if bad.size:
        raise ValueError(f"cells must be convex polygons: cell {int(bad[0])} (vertices "
                         f"{P[bad[0]].tolist()}) is not")
    where = classify_points(mesh, nodes[np.unique(cx.cells)], tol)
    if np.any(where < ON):
        v = np.unique(cx.cells)[int(np.flatnonzero(where < ON)[0])]
        raise ValueError(f"cells must lie inside the body: cell node {int(v)} at "
                         f"{nodes[v].tolist()} is outside its boundary mesh")
    where = classify_points(mesh, cx.centroids, tol)
    if np.any(where != INSIDE):
        c = int(np.flatnonzero(where != INSIDE)[0])
        raise ValueError(f"cells must lie inside the body: the centroid of cell {c} at "
                         f"{cx.centroids[c].tolist()} is not inside its boundary mesh")
    c, k = first_cut(mesh, nodes, cx.cells, tol)
    if c >= 0:
        raise ValueError(f"cells must lie inside the body: the boundary element {k} "
                         f"({mesh.a[k].tolist()} to {mesh.b[k].tolist()}) cuts cell {c} "
                         f"(vertices {P[c].tolist()})")
    i, j = _first_overlap(np.ascontiguousarray(nodes),      # one specialisation
                          np.ascontiguousarray(cx.cells, dtype=np.int64),
                          np.ascontiguousarray(cx.centroids), tol)
    if i >= 0:
        raise ValueError(f"cells must not overlap: cells {i} (vertices {P[i].tolist()}) "
                         f"and {j} (vertices {P[j].tolist()}) do")
    area = 0.5 * float(np.sum(mesh.a[:, 0] * mesh.b[:, 1] - mesh.b[:, 0] * mesh.a[:, 1]))
    if cx.areas.sum() > area * (1 + 1e-9):
        raise ValueError(f"cells must not overlap: their areas add up to "
                         f"{cx.areas.sum():.6g}, more than the body's {area:.6g}")


def match_nodes(points: np.ndarray, nodes: np.ndarray, tol: float) -> np.ndarray:
    """Index of the BEM node equal to each point (within tol), -1 if none."""
    d = np.linalg.norm(points[:, None, :] - nodes[None, :, :], axis=-1)
    j = np.argmin(d, axis=1)
    return np.where(d[np.arange(len(points)), j] <= tol, j, -1)


SHARED = ("S", "K", "A_u", "A_tau", "G", "_PB")
SHARED_MAX = 2
_SHARED: list = []


def _shared(bem, cells, E: float, nu: float) -> dict | None:
    """The operators built before for the same ``bem`` and ``cells`` objects and elastic
    constants (the BE/BE runs of one mesh for every theta, whose work pieces
    :func:`hpfebe.bodies.plastic_be.rectangle_work_piece` gives the same bem and cells),
    or None.  The last SHARED_MAX are kept, read-only."""
    for b, c, e, n, ops in _SHARED:
        if b is bem and c is cells and e == float(E) and n == float(nu):
            return ops
    return None


class CellStrainOperators:
    """The operators of a BE body of degree 1 (``bem``, plane strain) with piecewise
    constant initial strain on ``cells`` (its nodes on Gamma coinciding with BEM nodes),
    elastic constants E, nu: ``A_u``, ``A_tau`` (cell-average displacement gradients
    g = A_u u + A_tau tau, rows 4 c + 2 i + m), ``G`` (the plastic force of (4.29)),
    S = S_hat, :meth:`point_operators` (the displacement at interior points)."""

    def __init__(self, bem: LameBEM, cells: CellComplex, E: float, nu: float):
        instance("bem", bem, LameBEM, "a LameBEM (2D elasticity)")
        instance("cells", cells, CellComplex)
        if bem.plane != "strain":
            raise ValueError(f"bem must be plane strain (J2 body), got plane={bem.plane!r}")
        if not np.all(bem.mesh.degrees == 1):
            raise ValueError("bem must have degree 1 on every element (P1 displacements)")
        shared = _shared(bem, cells, E, nu)
        if shared is None:
            check_cells(bem.mesh, cells)
        self.bem, self.cells = bem, cells
        self.E, self.nu = E, nu
        self.ndofs = 2 * bem.V_space.ndof
        self.points = cells.centroids
        if shared is not None:
            for name, value in shared.items():
                setattr(self, name, value)
            return
        self.S = bem.S_hat
        self.K = sp.csr_matrix(self.S)
        self._build()
        ops = {name: getattr(self, name) for name in SHARED}
        for name in ("A_u", "A_tau", "G"):
            ops[name].setflags(write=False)
        for X in ops["_PB"]:
            X.setflags(write=False)
        _SHARED.append((bem, cells, float(E), float(nu), ops))
        del _SHARED[:-SHARED_MAX]

    def _P(self, Y: np.ndarray) -> np.ndarray:
        """Constrained V^{-1} (zero total force, as LameBEM.Psi) applied to columns Y."""
        bem = self.bem
        X = sla.cho_solve(bem.V_cho, Y)
        if bem.constrained:
            C = bem.constraints
            VC = sla.cho_solve(bem.V_cho, C)
            X = X - VC @ np.linalg.solve(C.T @ VC, C.T @ X)
        return X

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
        mid = 0.5 * (cx.nodes[cx.edges[:, 0]] + cx.nodes[cx.edges[:, 1]])
        along = ~on & (classify_points(mesh, mid, tol) == ON)
        if np.any(along):
            e = int(np.flatnonzero(along)[0])
            raise ValueError(f"cells must meet Gamma in whole BEM elements: the edge "
                             f"{cx.nodes[cx.edges[e]].tolist()} of cell "
                             f"{int(cx.edge_cell[e])} lies on Gamma but is no BEM element "
                             "(its ends must be the two nodes of one element)")
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
        Y = np.atleast_2d(np.asarray(Y, dtype=float))
        SL = self._single_layer(Y)                                       # (2Y, nW)
        DL = -potential_matrix(POT_LAME_DL, bem.kp, 2, Y, bem.V_space)   # (2Y, nV)
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
