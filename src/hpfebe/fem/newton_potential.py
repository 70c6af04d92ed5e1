"""Newton potential of an initial (plastic) strain on polygonal cells, 2D plane strain
(thesis Section 4.2.4, the volume terms of (4.28)-(4.29)).

With sigma = C : (eps(u) - eps_p) and the in-plane *initial stress* tau = (C : eps_p)_ab
(a, b = 1, 2; plane strain, so the out-of-plane eps_p_33 enters through tr eps_p), the
initial-strain Somigliana identity reads (Telles & Brebbia 1979)

    u(x) = int_Gamma G(x,y) t(y) ds_y - int_Gamma (T_n G(x,.)^T)(y) u(y) ds_y + w(x),
    w(x) = int_Omega sigma*(x,y) : eps_p(y) dy = int_Omega eps_y(G(x,y)) : tau(y) dy,

G the Kelvin fundamental solution of :mod:`hpfebe.bem.lame`, t = sigma n the true traction.
The stress at an interior point needs eps(w), a strongly singular cell integral (Cauchy
principal value plus the free term -C : eps_p(x) of Telles-Brebbia).

**Cell integrals by the divergence theorem.**  For tau constant on a cell c (eps_p
piecewise constant, one value per cell as in the thesis), eps_y(G) : tau = div_y(G tau),
so (exactly, also for x inside c: the excluded disc contributes O(rho log rho))

    int_c eps_y(G(x,y)) : tau_c dy = int_{d c} G(x,y) tau_c n_c(y) ds_y,

i.e. w is the single-layer potential of the edge densities [[tau]] n on the cell skeleton
(on Gamma: tau n).  On a straight edge with constant density the integrals of G and of
grad_x G have closed forms (local coordinates u along the edge, eta across it: log r,
atan(u / eta) and rational terms), so the weakly singular integral (x on or near an edge)
and the strongly singular one (eps(w) at points inside a cell, free term included) are
exact up to round-off - no Duffy or polar splitting is needed.  The stress at a cell point
x is sigma = C : (eps(u)(x) - eps_p(x)); the jump of eps(w) across edges is produced by the
atan terms.  tests/fem/test_newton_potential.py checks w and grad w against an independent
polar (Duffy-type) cell quadrature with scipy and finite differences.

The log-scale constant R of G drops out: every cell is closed, int_{d c} tau_c n ds = 0.

Functions: :func:`edge_integrals` (the closed forms), :func:`initial_stress` (tau from
eps_p), :class:`CellComplex` (cells, oriented edges, skeleton) and
:func:`newton_operators` (matrices tau -> w, grad w at points).  Components of tau are
ordered (tau_11, tau_22, tau_12) per cell.
"""

from __future__ import annotations

import math

import numpy as np

from ..constitutive.materials import lame_constants

TAU_COMPONENTS = 3


def kelvin_constants(E: float, nu: float) -> tuple[float, float]:
    """c1, c2 of G = c1 (-log r I + c2 r r^T / r^2), plane strain (as :mod:`hpfebe.bem.lame`)."""
    lam, mu = lame_constants(E, nu, "strain")
    c1 = (lam + 3.0 * mu) / (4.0 * math.pi * mu * (lam + 2.0 * mu))
    c2 = (lam + mu) / (lam + 3.0 * mu)
    return c1, c2


def initial_stress(eps_p: np.ndarray, E: float, nu: float) -> np.ndarray:
    """tau = (C : eps_p)_ab, a, b in {1, 2}, as (N, 3) = (tau_11, tau_22, tau_12);
    ``eps_p`` (N, 3, 3) (plane strain: eps_p_33 counts through the trace) or (N, 2, 2)."""
    eps_p = np.asarray(eps_p, dtype=float)
    if eps_p.ndim != 3 or eps_p.shape[1:] not in ((3, 3), (2, 2)):
        raise ValueError(f"eps_p must have shape (N, 3, 3) or (N, 2, 2), got {eps_p.shape}")
    lam, mu = lame_constants(E, nu, "strain")
    tr = np.trace(eps_p, axis1=1, axis2=2)
    return np.stack([lam * tr + 2 * mu * eps_p[:, 0, 0], lam * tr + 2 * mu * eps_p[:, 1, 1],
                     2 * mu * eps_p[:, 0, 1]], axis=1)


def _tensor(tau: np.ndarray) -> np.ndarray:
    t = np.empty(tau.shape[:-1] + (2, 2))
    t[..., 0, 0], t[..., 1, 1] = tau[..., 0], tau[..., 1]
    t[..., 0, 1] = t[..., 1, 0] = tau[..., 2]
    return t


def edge_integrals(x: np.ndarray, a: np.ndarray, b: np.ndarray, c1: float, c2: float,
                   gradient: bool = True):
    """Closed-form integrals over straight segments [a_s, b_s] for points x_p:

        IG[p, s, i, k]     = int_s G_ik(x_p - y) ds_y,           G with R = 1,
        IdG[p, s, i, k, m] = int_s d/dx_m G_ik(x_p - y) ds_y     (if ``gradient``).

    ``x`` (P, 2), ``a``, ``b`` (S, 2).  IG is continuous in x (also on the segment); IdG
    is not defined on the segment itself (the jump of the single-layer gradient)."""
    x = np.asarray(x, dtype=float)[:, None, :]
    a, b = np.asarray(a, dtype=float)[None], np.asarray(b, dtype=float)[None]
    d = b - a
    L = np.hypot(d[..., 0], d[..., 1])
    if np.any(L[0] <= 0):
        raise ValueError("segments must have positive length")
    t = d / L[..., None]
    nh = np.stack([-t[..., 1], t[..., 0]], axis=-1)
    xa = x - a
    xi = np.einsum("psk,psk->ps", xa, np.broadcast_to(t, xa.shape))
    eta = np.einsum("psk,psk->ps", xa, np.broadcast_to(nh, xa.shape))
    u1, u0 = xi, xi - L
    r2_1, r2_0 = u1 ** 2 + eta ** 2, u0 ** 2 + eta ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        lr1 = np.where(r2_1 > 0, 0.5 * np.log(np.where(r2_1 > 0, r2_1, 1.0)), 0.0)
        lr0 = np.where(r2_0 > 0, 0.5 * np.log(np.where(r2_0 > 0, r2_0, 1.0)), 0.0)
        dth = np.arctan2(eta * (u1 - u0), eta ** 2 + u0 * u1)   # atan(u1/eta) - atan(u0/eta)
        dlog = lr1 - lr0
        I0 = u1 * lr1 - u0 * lr0 - L + eta * dth
        Iuu = L - eta * dth
        Iue = eta * dlog
        Iee = eta * dth
    tt = t[..., :, None] * t[..., None, :]
    tn = t[..., :, None] * nh[..., None, :]
    nn = nh[..., :, None] * nh[..., None, :]
    eye = np.eye(2)
    IG = c1 * (-I0[..., None, None] * eye + c2 * (Iuu[..., None, None] * tt
               + Iue[..., None, None] * (tn + np.swapaxes(tn, -1, -2))
               + Iee[..., None, None] * nn))
    if not gradient:
        return IG
    with np.errstate(divide="ignore", invalid="ignore"):
        q1 = np.where(r2_1 > 0, 1.0 / np.where(r2_1 > 0, r2_1, 1.0), 0.0)
        q0 = np.where(r2_0 > 0, 1.0 / np.where(r2_0 > 0, r2_0, 1.0), 0.0)
    Ju, Je = dlog, dth
    J0 = 0.5 * eta * (u1 * q1 - u0 * q0) + 0.5 * dth            # int eta^3 / r^4
    J2 = 0.5 * dth - 0.5 * eta * (u1 * q1 - u0 * q0)            # int u^2 eta / r^4
    J1 = -0.5 * eta ** 2 * (q1 - q0)                            # int u eta^2 / r^4
    J3 = dlog + 0.5 * eta ** 2 * (q1 - q0)                      # int u^3 / r^4
    J = Ju[..., None] * t + Je[..., None] * nh                  # int r_m / r^2
    e = np.stack(np.broadcast_arrays(t, nh), axis=0)            # (2, 1|P, S, 2) frame
    T3 = np.zeros(J.shape[:-1] + (2, 2, 2))
    for (ia, ib, ic), Jk in (((0, 0, 0), J3), ((0, 0, 1), J2), ((0, 1, 0), J2),
                             ((1, 0, 0), J2), ((0, 1, 1), J1), ((1, 0, 1), J1),
                             ((1, 1, 0), J1), ((1, 1, 1), J0)):
        T3 += Jk[..., None, None, None] * np.einsum("...i,...k,...m->...ikm",
                                                    e[ia], e[ib], e[ic])
    IdG = c1 * (-np.einsum("ik,psm->psikm", eye, J)
                + c2 * (np.einsum("im,psk->psikm", eye, J) + np.einsum("km,psi->psikm", eye, J))
                - 2.0 * c2 * T3)
    return IG, IdG


class CellComplex:
    """Polygonal cells (triangles, quadrilaterals, ...) of a region Omega_p where the
    plastic strain lives: ``nodes`` (n, 2), ``cells`` (ncell, k) vertex indices (either
    orientation; made counter-clockwise).  Attributes: ``edges`` (ncell * k, 2) the
    directed cell edges (start, end node) with outward ``normals`` and ``lengths``,
    ``edge_cell`` (owning cell), ``boundary_edge`` (edge used by one cell only: on the
    outer boundary of Omega_p), ``centroids`` (ncell, 2), ``areas``."""

    def __init__(self, nodes, cells):
        nodes = np.asarray(nodes, dtype=float)
        cells = np.asarray(cells)
        if nodes.ndim != 2 or nodes.shape[1] != 2:
            raise ValueError(f"nodes must have shape (n, 2), got {nodes.shape}")
        if cells.ndim != 2 or cells.shape[1] < 3 or not np.issubdtype(cells.dtype, np.integer):
            raise ValueError(f"cells must be an integer array (ncell, k >= 3), got "
                             f"{cells.shape} {cells.dtype}")
        if cells.min() < 0 or cells.max() >= len(nodes):
            raise ValueError("cells must index nodes")
        P = nodes[cells]                                          # (nc, k, 2)
        Q = np.roll(P, -1, axis=1)
        area2 = np.sum(P[..., 0] * Q[..., 1] - Q[..., 0] * P[..., 1], axis=1)
        if np.any(np.abs(area2) <= 1e-14 * np.max(np.ptp(nodes, axis=0)) ** 2):
            raise ValueError("cells must have positive area (degenerate cell found)")
        cells = np.where((area2 < 0)[:, None], cells[:, ::-1], cells)
        self.nodes, self.cells = nodes, cells
        self.areas = 0.5 * np.abs(area2)
        P = nodes[cells]
        Q = np.roll(P, -1, axis=1)
        cross = P[..., 0] * Q[..., 1] - Q[..., 0] * P[..., 1]
        self.centroids = np.einsum("ck,cki->ci", cross, P + Q) / (6.0 * self.areas[:, None])
        nc, k = cells.shape
        self.edges = np.stack([cells, np.roll(cells, -1, axis=1)], axis=-1).reshape(-1, 2)
        self.edge_cell = np.repeat(np.arange(nc), k)
        d = nodes[self.edges[:, 1]] - nodes[self.edges[:, 0]]
        self.lengths = np.hypot(d[:, 0], d[:, 1])
        self.normals = np.stack([d[:, 1], -d[:, 0]], axis=1) / self.lengths[:, None]
        key = np.sort(self.edges, axis=1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        self.boundary_edge = cnt[inv.ravel()] == 1

    @property
    def ncells(self) -> int:
        return len(self.cells)

    def density_operator(self, edge_ids: np.ndarray) -> np.ndarray:
        """(len(edge_ids), 2, ncell, 3): tau -> tau_c n on the listed cell edges."""
        edge_ids = np.asarray(edge_ids)
        n = self.normals[edge_ids]
        D = np.zeros((len(edge_ids), 2, self.ncells, TAU_COMPONENTS))
        c = self.edge_cell[edge_ids]
        r = np.arange(len(edge_ids))
        D[r, 0, c, 0] = n[:, 0]          # (tau n)_1 = tau11 n1 + tau12 n2
        D[r, 0, c, 2] = n[:, 1]
        D[r, 1, c, 1] = n[:, 1]          # (tau n)_2 = tau12 n1 + tau22 n2
        D[r, 1, c, 2] = n[:, 0]
        return D


def newton_operators(cx: CellComplex, points, E: float, nu: float, gradient: bool = True,
                     chunk: int = 128):
    """Matrices of tau (3 ncell, per cell (tau11, tau22, tau12)) -> the Newton potential
    at ``points`` (P, 2):

        Nw (2P, 3 ncell):  w(x_p) = int_Omega sigma*(x_p, y) : eps_p(y) dy,
        Ng (4P, 3 ncell):  dw_i/dx_m (x_p), row 4 p + 2 i + m   (if ``gradient``),

    by :func:`edge_integrals` on the cell edges (module docstring), vectorised over
    points (in chunks of ``chunk``) and edges."""
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts)):
        raise ValueError(f"points must be a finite (P, 2) array, got shape {pts.shape}")
    c1, c2 = kelvin_constants(E, nu)
    a = cx.nodes[cx.edges[:, 0]]
    b = cx.nodes[cx.edges[:, 1]]
    nc, k = cx.cells.shape
    n = cx.normals
    Dl = np.zeros((len(n), 2, TAU_COMPONENTS))              # tau n = Dl @ tau (per edge)
    Dl[:, 0, 0], Dl[:, 0, 2], Dl[:, 1, 1], Dl[:, 1, 2] = n[:, 0], n[:, 1], n[:, 1], n[:, 0]
    P = len(pts)
    Nw = np.zeros((P, 2, nc, TAU_COMPONENTS))
    Ng = np.zeros((P, 2, 2, nc, TAU_COMPONENTS)) if gradient else None
    for s in range(0, P, chunk):
        sl = slice(s, min(s + chunk, P))
        res = edge_integrals(pts[sl], a, b, c1, c2, gradient)
        IG = res[0] if gradient else res
        W = np.einsum("psik,skt->psit", IG, Dl)
        Nw[sl] = np.moveaxis(W.reshape(W.shape[0], nc, k, 2, TAU_COMPONENTS).sum(axis=2), 1, 2)
        if gradient:
            Gm = np.einsum("psikm,skt->psimt", res[1], Dl)
            Gm = Gm.reshape(Gm.shape[0], nc, k, 2, 2, TAU_COMPONENTS).sum(axis=2)
            Ng[sl] = np.moveaxis(Gm, 1, 3)
    Nw = Nw.reshape(2 * P, -1)
    if not gradient:
        return Nw, None
    return Nw, Ng.reshape(4 * P, -1)
