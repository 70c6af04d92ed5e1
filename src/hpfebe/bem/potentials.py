"""Generic evaluation of boundary potentials at points off Gamma (representation formulas).

    P f(x) = int_Gamma k(x - y, n_y) f(y) ds_y,   f in W_hp^d or V_hp^d (interleaved),

for a potential kernel given by an integer id (``POT_*`` below, dispatched by
:func:`pot_kernel`, like the kernel ids of :mod:`hpfebe.bem.kernels`: numba's disk cache
cannot hold functions specialised on function-typed arguments) that writes the full
(nout x d) kernel matrix row-major (out[a * d + c]), r = x - y, log part included.
Each element is bisected until the point is at least one sub-element length away, then
Gauss with an order that grows with log(size / distance) (the rule of
:func:`hpfebe.bem.integration._order`), so the accuracy holds uniformly up to (not on)
the boundary.

Speed (the same sums, bitwise): most point-element pairs are far (one panel, the whole
element); for them the Gauss points, weights and density values per element and order
are tabulated once per call (:func:`_far_tables`) and the order is read off thresholds
of ``_order`` (:func:`_order_thresholds`), the Laplace kernels are inlined, and the
points are split over numba.get_num_threads() Python threads running a nogil kernel
(:func:`_potential_rows`; no parfor to compile).  Representation formula of
Example 2 (50,181 points x 1,040 elements, single thread): SL 7.2 -> 1.6 s, DL 8.3 ->
1.2 s.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit

from .. import checks
from ..spaces import LEGENDRE, P_MAX, eval_basis, gll_tables, n_local
from .assembly import rules
from .integration import _order, point_panels
from .kernels import (INV_2PI, KP_C1, KP_C1_C2, KP_C1_LOG_R, KP_C2, KP_LAMBDA,
                      KP_LAPLACE_LOG_R, KP_MU, _log_rr, _traction_of_G)
from .threads import n_threads, run_chunks

# potential kernel ids; kp is the parameter array of the owning operator class
POT_LAME_SL, POT_LAME_DL, POT_LAME_SL_GRAD, POT_LAME_DL_GRAD = 0, 1, 2, 3
POT_LAPLACE_SL, POT_LAPLACE_DL = 4, 5   # kp = [log(R) / (2 pi)]


@njit(cache=True, inline="always")
def _hess_G(u0, u1, c2):
    """|r|^2 / c1 d^2 G_ij / dr_l dr_m at r = |r| u, for (i, j) and (l, m) each in
    (00, 01, 11) (symmetric in both pairs): with G_ij = c1 (-d_ij log|r| + c2 r_i r_j /
    |r|^2) + const,

        = -d_ij (d_lm - 2 u_l u_m) + c2 (d_il d_jm + d_jl d_im)
          - 2 c2 (d_il u_j u_m + d_jl u_i u_m + d_im u_j u_l + d_jm u_i u_l + d_lm u_i u_j)
          + 8 c2 u_i u_j u_l u_m,

    the nine distinct values written out (the delta products resolved)."""
    u00, u01, u11 = u0 * u0, u0 * u1, u1 * u1
    h0000 = -(1.0 - 2.0 * u00) + 2.0 * c2 - 10.0 * c2 * u00 + 8.0 * c2 * u00 * u00
    h0001 = 2.0 * u01 - 4.0 * c2 * u01 + 8.0 * c2 * u00 * u01
    h0011 = -(1.0 - 2.0 * u11) - 2.0 * c2 * u00 + 8.0 * c2 * u00 * u11
    h0100 = -6.0 * c2 * u01 + 8.0 * c2 * u01 * u00
    h0101 = c2 - 2.0 * c2 * (u00 + u11) + 8.0 * c2 * u01 * u01
    h0111 = -6.0 * c2 * u01 + 8.0 * c2 * u01 * u11
    h1100 = -(1.0 - 2.0 * u00) - 2.0 * c2 * u11 + 8.0 * c2 * u11 * u00
    h1101 = 2.0 * u01 - 4.0 * c2 * u01 + 8.0 * c2 * u11 * u01
    h1111 = -(1.0 - 2.0 * u11) + 2.0 * c2 - 10.0 * c2 * u11 + 8.0 * c2 * u11 * u11
    return ((h0000, h0001, h0011), (h0100, h0101, h0111), (h1100, h1101, h1111))


@njit(cache=True, inline="always")
def _lame_grad_kernels(rx, ry, ny0, ny1, lam, mu, c1, c2, double, out):
    """x-gradients of the Lame kernels at r = x - y, out[(i*2 + m)*2 + k]:
    d/dx_m G_ik (double = False) or d/dx_m K_ik, K_ik = [sigma_y(G(x,.) e_i) n_y]_k.
    With g_l = dG_ji/dr_l
        = c1 (-d_ij r_l + c2 (d_il r_j + d_jl r_i) - 2 c2 r_i r_j r_l/|r|^2)/|r|^2
    and its r_m-derivative H_jlm (:func:`_hess_G`); grad_y = -grad_r, so d/dx_m of
    D_jl = -g_l is -H_jlm."""
    r2 = rx * rx + ry * ry
    r4 = r2 * r2
    if not double:
        for i in range(2):
            for m in range(2):
                rm = rx if m == 0 else ry
                ri = rx if i == 0 else ry
                for k in range(2):
                    rk = rx if k == 0 else ry
                    dik = 1.0 if i == k else 0.0
                    dim = 1.0 if i == m else 0.0
                    dkm = 1.0 if k == m else 0.0
                    out[(i * 2 + m) * 2 + k] = c1 * (-dik * rm / r2 + c2 * (
                        (dim * rk + ri * dkm) / r2 - 2.0 * ri * rk * rm / r4))
        return
    inv = 1.0 / math.sqrt(r2)
    H = _hess_G(rx * inv, ry * inv, c2)
    rho = -c1 / r2
    for i in range(2):
        for m in range(2):
            # d/dx_m of D_jl is -H_{i j l m}; pair index of (i, j): i + j
            a0, a1, b0, b1 = i, i + 1, m, m + 1
            d00 = rho * H[a0][b0]
            d01 = rho * H[a0][b1]
            d10 = rho * H[a1][b0]
            d11 = rho * H[a1][b1]
            div = d00 + d11
            s00 = lam * div + 2.0 * mu * d00
            s11 = lam * div + 2.0 * mu * d11
            s01 = mu * (d01 + d10)
            out[(i * 2 + m) * 2 + 0] = s00 * ny0 + s01 * ny1
            out[(i * 2 + m) * 2 + 1] = s01 * ny0 + s11 * ny1


@njit(cache=True, inline="always")
def _laplace_sl(rx, ry, kp):
    """Laplace single-layer kernel G(r) = log(R) / (2 pi) - log|r| / (2 pi)."""
    return kp[KP_LAPLACE_LOG_R] - INV_2PI * 0.5 * math.log(rx * rx + ry * ry)


@njit(cache=True, inline="always")
def _laplace_dl(rx, ry, ny0, ny1):
    """Laplace double-layer kernel d_{n_y} G(r) = r . n_y / (2 pi |r|^2)."""
    return INV_2PI * (rx * ny0 + ry * ny1) / (rx * rx + ry * ry)


@njit(cache=True)
def pot_kernel(kid, rx, ry, ny0, ny1, kp, out):
    """Full kernel at r = x - y (x off Gamma): Laplace G and d_{n_y} G (kp = [log(R)/(2 pi)]),
    Lame G (single layer, kp of :func:`hpfebe.bem.lame.kernel_params`, indices KP_* of
    :mod:`.kernels`), its y-traction (double layer), or the x-gradients of both (nout = 4:
    rows (i, m) = d/dx_m of component i)."""
    if kid == POT_LAPLACE_SL:
        out[0] = _laplace_sl(rx, ry, kp)
    elif kid == POT_LAPLACE_DL:
        out[0] = _laplace_dl(rx, ry, ny0, ny1)
    elif kid == POT_LAME_SL:
        _log_rr(rx, ry, kp[KP_C1_LOG_R] - 0.5 * kp[KP_C1] * math.log(rx * rx + ry * ry),
                kp[KP_C1_C2], out)
    elif kid == POT_LAME_DL:
        _traction_of_G(rx, ry, ny0, ny1, kp[KP_LAMBDA], kp[KP_MU], kp[KP_C1], kp[KP_C2], out)
    elif kid == POT_LAME_SL_GRAD:
        _lame_grad_kernels(rx, ry, ny0, ny1, kp[KP_LAMBDA], kp[KP_MU], kp[KP_C1], kp[KP_C2],
                           False, out)
    elif kid == POT_LAME_DL_GRAD:
        _lame_grad_kernels(rx, ry, ny0, ny1, kp[KP_LAMBDA], kp[KP_MU], kp[KP_C1], kp[KP_C2],
                           True, out)
    else:
        raise ValueError("unknown potential kernel id")


@lru_cache(maxsize=None)
def _far_basis(kind: int, pmax: int, nf: int):
    """(off, tab): tab[p, off[n] + k, j] = basis function j of degree p (``eval_basis``)
    at the k-th n-point Gauss node of the whole element, n <= nf (zero for j beyond the
    local basis)."""
    gx = rules()[0]
    gll_x, gll_b = gll_tables(P_MAX)
    off = np.concatenate([[0, 0], np.cumsum(np.arange(1, nf + 1))]).astype(np.int64)
    tab = np.zeros((pmax + 1, off[-1], pmax + 1))
    for p in range(1, pmax + 1):
        for n in range(1, nf + 1):
            for k in range(n):
                s = 0.0 + (1.0 - 0.0) * gx[n, k]      # as the panel loop forms it
                eval_basis(kind, p, 2.0 * s - 1.0, gll_x, gll_b, tab[p, off[n] + k])
    tab.setflags(write=False)
    return off, tab


def _far_tables(mesh, space, coef, nf: int):
    """(off, Y, FV) of the far pairs (the point at least one element length away: the
    whole element is one panel, s in [0, 1]): for element e and Gauss order n <= nf, the
    Gauss points Y[e, off[n] + k] = a + s (b - a) and the density values FV[e, off[n] +
    k] = f(y) - the very floating-point operations of the panel loop of
    :func:`_potential_rows`, so a far pair reads them instead of recomputing them for
    every evaluation point (bitwise the same sums)."""
    gx = rules()[0]
    off, tab = _far_basis(space.kind, int(mesh.degrees.max()), nf)
    m = int(off[-1])
    s = np.concatenate([0.0 + (1.0 - 0.0) * gx[n, :n] for n in range(1, nf + 1)])
    a = mesh.nodes[mesh.elements[:, 0]]
    u = mesh.nodes[mesh.elements[:, 1]] - a
    Y = np.empty((len(a), m, 2))
    Y[:, :, 0] = a[:, 0, None] + s[None, :] * u[:, 0, None]
    Y[:, :, 1] = a[:, 1, None] + s[None, :] * u[:, 1, None]
    phi = tab[mesh.degrees]                                  # (ne, m, pmax + 1)
    dofs = space.elem_dofs
    nl = mesh.degrees + (0 if space.kind == 0 else 1)         # n_local per element
    FV = np.zeros((len(a), m, coef.shape[1]))
    for j in range(dofs.shape[1]):
        on = (dofs[:, j] >= 0) & (j < nl)
        FV[on] += phi[on, :, j, None] * coef[dofs[on, j]][:, None, :]
    return off, np.ascontiguousarray(Y), FV


@lru_cache(maxsize=None)
def _order_thresholds(dmax: int, nf: int, nmax: int) -> np.ndarray:
    """thr2[deg, n]: the square of the smallest ratio >= 2 with _order(ratio, deg, nmax)
    <= n (inf if none), by bisection on :func:`hpfebe.bem.integration._order` itself to
    a relative 1e-13.  A far pair reads its order off these unless its ratio lies within
    a relative 1e-9 of one (then _order is called): the order of the direct call either
    way."""
    thr2 = np.full((dmax + 1, nf + 1), np.inf)
    for deg in range(dmax + 1):
        for n in range(1, nf + 1):
            lo, hi = 2.0, 1e300
            if _order(lo, deg, nmax) <= n:
                thr2[deg, n] = lo * lo
                continue
            if _order(hi, deg, nmax) > n:
                continue
            while hi - lo > 1e-13 * hi:
                mid = math.sqrt(lo) * math.sqrt(hi)
                if not lo < mid < hi:
                    mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if _order(mid, deg, nmax) <= n else (mid, hi)
            thr2[deg, n] = hi * hi
    thr2.setflags(write=False)
    return thr2


@njit(cache=True, inline="always")
def _far_order(dx, dy, L, deg, nmax, nf, thr2):
    """Gauss order of the far pair (point at offset (dx, dy) from its nearest point on
    an element of length L: one panel), or -1 for a near pair: exactly
    ``_order(2 hypot(dx, dy) / L, deg, nmax)`` when hypot(dx, dy) >= L (the test of
    point_panels), read off ``thr2`` unless within round-off of a threshold."""
    d2 = dx * dx + dy * dy
    L2 = L * L
    if d2 < L2 * (1.0 - 1e-9):
        return -1
    if d2 <= L2 * (1.0 + 1e-9):         # round-off band: the exact test
        dist = math.hypot(dx, dy)
        if dist < L:
            return -1
        return _order(2.0 * dist / L, deg, nmax)
    r2 = 4.0 * d2 / L2
    for n in range(1, nf + 1):
        t = thr2[deg, n]
        if t <= r2:
            if r2 <= t * (1.0 + 1e-9) or (n > 1 and r2 >= thr2[deg, n - 1] * (1.0 - 1e-9)):
                return _order(2.0 * math.hypot(dx, dy) / L, deg, nmax)
            return n
    return _order(2.0 * math.hypot(dx, dy) / L, deg, nmax)


@njit(cache=True, nogil=True)
def _element_geometry(nodes, elements, gw, nf, off):
    """geo[e] = (b - a, L = |b - a|, a) of each element and Wt[e, off[n] + k] = gw[n, k] L,
    the Gauss weights of the far pairs (the h = (1 - 0) L of the panel loop)."""
    ne = elements.shape[0]
    geo = np.empty((ne, 5))
    Wt = np.empty((ne, off[nf + 1]))
    for e in range(ne):
        a = nodes[elements[e, 0]]
        b = nodes[elements[e, 1]]
        geo[e, 0], geo[e, 1] = b[0] - a[0], b[1] - a[1]
        geo[e, 2] = math.hypot(geo[e, 0], geo[e, 1])
        geo[e, 3], geo[e, 4] = a[0], a[1]
        for n in range(1, nf + 1):
            for k in range(n):
                Wt[e, off[n] + k] = gw[n, k] * geo[e, 2]
    return geo, Wt


@njit(cache=True, nogil=True, inline="always")
def _panel_node(kid, kp, x0, x1, a, ux, uy, s0, s1, xi, w, normal, kind, p, gll_x, gll_b,
                kv, phi):
    """One Gauss node s = s0 + (s1 - s0) xi of a panel of the element a + s (ux, uy): the
    kernel values at x - y(s) into ``kv``, the basis values at 2 s - 1 into ``phi``;
    returns its weight ``w`` (the node loop of both near-pair kernels below)."""
    s = s0 + (s1 - s0) * xi
    rx = x0 - (a[0] + s * ux)
    ry = x1 - (a[1] + s * uy)
    pot_kernel(kid, rx, ry, normal[0], normal[1], kp, kv)
    eval_basis(kind, p, 2.0 * s - 1.0, gll_x, gll_b, phi)
    return w


@njit(cache=True, nogil=True)
def _potential_rows(kid, kp, d, nout, pts, rows, nodes, elements, normals, degrees, kind,
                    dofs, coef, gx, gw, gll_x, gll_b, nf, off, Y, FV, thr2, out):
    """out[q] for q in ``rows``: the potential at pts[q] (NaN on Gamma), summed element
    by element.  A far pair (the point at least one element length away: one panel, the
    whole element) with an order n <= nf reads the Gauss points and density values of
    :func:`_far_tables` and its order from :func:`_order_thresholds` (nf = 0: no
    tables); the others are bisected (:func:`hpfebe.bem.integration.point_panels`), with
    the order :func:`hpfebe.bem.integration._order` per panel.  The same sums in the same
    order either way."""
    nmax = gx.shape[0] - 1
    ne = elements.shape[0]
    phi = np.empty(degrees.max() + 1)
    kv = np.empty(nout * d)
    fv = np.empty(d)
    acc = np.empty(nout)
    stack = np.empty((128, 2))
    panels = np.empty((128, 3))
    scalar_sl = kid == POT_LAPLACE_SL and d == 1 and nout == 1
    scalar_dl = kid == POT_LAPLACE_DL and d == 1 and nout == 1
    geo, Wt = _element_geometry(nodes, elements, gw, nf, off)
    for q in rows:
        x0, x1 = pts[q, 0], pts[q, 1]
        for r in range(nout):
            acc[r] = 0.0
        onb = False
        for e in range(ne):
            # scalars, no array views (their reference counting costs more than the
            # rest of a far pair)
            ux, uy, L, ax, ay = geo[e, 0], geo[e, 1], geo[e, 2], geo[e, 3], geo[e, 4]
            p = degrees[e]
            deg = p - 1 if kind == 0 else p
            n = -1
            if nf > 0:      # first step of point_panels: the distance to the element
                t = min(1.0, max(0.0, ((x0 - ax) * ux + (x1 - ay) * uy) / (L * L)))
                n = _far_order(x0 - ax - t * ux, x1 - ay - t * uy, L, deg, nmax, nf, thr2)
            if 0 < n <= nf:
                i0 = off[n]
                n0, n1 = normals[e, 0], normals[e, 1]
                if scalar_sl:                   # Laplace: the hot loops, inlined
                    a0 = acc[0]
                    for k in range(n):
                        kv0 = _laplace_sl(x0 - Y[e, i0 + k, 0], x1 - Y[e, i0 + k, 1], kp)
                        a0 += Wt[e, i0 + k] * (0.0 + kv0 * FV[e, i0 + k, 0])
                    acc[0] = a0
                    continue
                if scalar_dl:
                    a0 = acc[0]
                    for k in range(n):
                        kv0 = _laplace_dl(x0 - Y[e, i0 + k, 0], x1 - Y[e, i0 + k, 1], n0, n1)
                        a0 += Wt[e, i0 + k] * (0.0 + kv0 * FV[e, i0 + k, 0])
                    acc[0] = a0
                    continue
                for k in range(n):
                    pot_kernel(kid, x0 - Y[e, i0 + k, 0], x1 - Y[e, i0 + k, 1], n0, n1, kp,
                               kv)
                    w = Wt[e, i0 + k]
                    for r in range(nout):
                        sacc = 0.0
                        for c in range(d):
                            sacc += kv[r * d + c] * FV[e, i0 + k, c]
                        acc[r] += w * sacc
                continue
            a = nodes[elements[e, 0]]
            b = nodes[elements[e, 1]]
            nl = n_local(kind, p)
            npan = point_panels(x0, x1, a, b, 1e-13, stack, panels)
            if npan < 0:
                onb = True      # x on Gamma: the potential is not defined there
                break
            for ip in range(npan):
                s0, s1, dist = panels[ip, 0], panels[ip, 1], panels[ip, 2]
                h = (s1 - s0) * L
                n = _order(2.0 * dist / h, deg, nmax)
                for k in range(n):
                    w = _panel_node(kid, kp, x0, x1, a, ux, uy, s0, s1, gx[n, k],
                                    gw[n, k] * h, normals[e], kind, p, gll_x, gll_b, kv,
                                    phi)
                    for c in range(d):
                        fv[c] = 0.0
                    for j in range(nl):
                        g = dofs[e, j]
                        if g >= 0:
                            for c in range(d):
                                fv[c] += phi[j] * coef[g, c]
                    for r in range(nout):
                        sacc = 0.0
                        for c in range(d):
                            sacc += kv[r * d + c] * fv[c]
                        acc[r] += w * sacc
        for r in range(nout):
            out[q, r] = math.nan if onb else acc[r]


_NO_THRESHOLDS = np.zeros((0, 0))
_NO_THRESHOLDS.setflags(write=False)
MIN_TABLE_POINTS = 32       # fewer points: no far tables (building them costs more)
MIN_PAIRS_PER_THREAD = 20000


def _potential(kid, kp, d, nout, pts, mesh, space, coef, gx, gw, gll_x, gll_b):
    """The values (n_points, nout) of :func:`_potential_rows` for all points, in chunks on
    numba.get_num_threads() Python threads (nogil kernel, disjoint rows; no parfor to
    compile)."""
    npts, ne = pts.shape[0], mesh.n_elements
    nmax = gx.shape[0] - 1
    pmax = int(mesh.degrees.max())
    nf = min(nmax, int(_order(2.0, pmax + 1, nmax)) + 1) if npts >= MIN_TABLE_POINTS else 0
    if nf > 0:
        off, Y, FV = _far_tables(mesh, space, coef, nf)
        thr2 = _order_thresholds(pmax + 1, nf, nmax)
    else:   # no tables; thr2 read-only like the cached one (one numba specialisation)
        off, Y, FV, thr2 = (np.zeros(2, np.int64), np.zeros((0, 0, 2)),
                            np.zeros((0, 0, d)), _NO_THRESHOLDS)
    out = np.empty((npts, nout))
    args = (int(kid), kp, d, nout, pts)
    tail = (mesh.nodes, mesh.elements, np.ascontiguousarray(mesh.normals), mesh.degrees,
            space.kind, space.elem_dofs, coef, gx, gw, gll_x, gll_b, nf, off, Y, FV, thr2,
            out)
    rows = np.arange(npts)
    nt = min(n_threads(npts * ne, MIN_PAIRS_PER_THREAD), npts)
    if nt <= 1:
        _potential_rows(*args, rows, *tail)
        return out
    run_chunks(lambda c: _potential_rows(*args, c, *tail), np.array_split(rows, 4 * nt), nt)
    return out


class PointOnBoundaryError(ValueError, FloatingPointError):
    """A potential asked for at a point of Gamma, where the representation formula does
    not hold (the double layer jumps, the kernels are singular): a ValueError naming the
    point (and a FloatingPointError, what it was before)."""


def evaluation_points(points) -> np.ndarray:
    """``points`` as a C-contiguous (n, 2) float array (one point (x, y) may be given
    flat), finite; ValueError naming the first bad point."""
    pts = checks.array("points", points, finite=False)
    pts = np.ascontiguousarray(np.atleast_2d(pts))
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
    bad = ~np.all(np.isfinite(pts), axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(f"points must be finite: point {k} = {tuple(pts[k].tolist())} "
                         "has a non-finite (NaN or inf) coordinate")
    return pts


def density(name: str, coeffs, space, d: int) -> np.ndarray:
    """The coefficients ``coeffs`` of a density in ``space`` with ``d`` components as a
    C-contiguous (ndof, d) array: given flat (ndof * d,), interleaved, or as (ndof, d);
    finite.  ValueError naming ``name``, the length it must have and the one it has."""
    n = space.ndof
    c = checks.array(name, coeffs)
    if c.shape not in ((n * d,), (n, d)):
        which = "W_hp" if space.kind == LEGENDRE else "V_hp"
        comps = f"{d} x " if d > 1 else ""
        raise ValueError(f"{name} must have {n * d} entries ({comps}{n} {which} dofs"
                         f"{', interleaved' if d > 1 else ''}), got shape {c.shape}")
    return np.ascontiguousarray(c.reshape(n, d))


def evaluate_potential(kid: int, kp, d: int, points, space, coeffs, nout: int | None = None,
                       name: str = "coeffs") -> np.ndarray:
    """Values (n_points, nout) of int k(x - y, n_y) f(y) ds_y, f = sum coeffs * basis of
    ``space`` (``coeffs`` of shape (ndof, d) or (ndof * d,), interleaved; ``name``: the
    caller's name of it, for the error messages); ``nout`` defaults to d.  Raises
    :class:`PointOnBoundaryError` (a ValueError) if a point lies on Gamma."""
    nout = d if nout is None else int(nout)
    pts = evaluation_points(points)
    coef = density(name, coeffs, space, d)
    mesh = space.mesh
    gx, gw, _, _ = rules()
    gll_x, gll_b = gll_tables(P_MAX)
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    out = _potential(int(kid), kp, d, nout, pts, mesh, space, coef, gx, gw, gll_x, gll_b)
    if not np.all(np.isfinite(out)):    # finite points and density: NaN rows are on Gamma
        on = np.flatnonzero(~np.all(np.isfinite(out), axis=1))
        k = int(on[0])
        raise PointOnBoundaryError(
            f"points must lie off the boundary Gamma, where the representation formula "
            f"does not hold: point {k} = {tuple(pts[k].tolist())} lies on Gamma "
            f"({on.size} of {len(pts)} points do); use the boundary data there")
    return out


@njit(cache=True, nogil=True)
def _potential_matrix_rows(kid, kp, d, nout, pts, nodes, elements, normals, degrees, kind,
                           dofs, ndof, gx, gw, gll_x, gll_b):
    """out[q, r, g, c]: component r of the potential at pts[q] of the density with the
    single coefficient 1 at dof g, component c - every column of :func:`_potential_rows`
    in one pass over the point-element pairs (the panel loop of its near pairs, whose sums
    its far pairs reproduce: the column's sum w (kv f) with f the basis value, in the
    same order, bit for bit); out[q] is NaN for a point on Gamma."""
    nmax = gx.shape[0] - 1
    ne = elements.shape[0]
    phi = np.empty(degrees.max() + 1)
    kv = np.empty(nout * d)
    stack = np.empty((128, 2))
    panels = np.empty((128, 3))
    out = np.zeros((pts.shape[0], nout, ndof, d))
    for q in range(pts.shape[0]):
        x0, x1 = pts[q, 0], pts[q, 1]
        for e in range(ne):
            a = nodes[elements[e, 0]]
            b = nodes[elements[e, 1]]
            ux, uy = b[0] - a[0], b[1] - a[1]
            L = math.hypot(ux, uy)
            p = degrees[e]
            deg = p - 1 if kind == 0 else p
            nl = n_local(kind, p)
            npan = point_panels(x0, x1, a, b, 1e-13, stack, panels)
            if npan < 0:
                out[q] = math.nan
                break
            for ip in range(npan):
                s0, s1, dist = panels[ip, 0], panels[ip, 1], panels[ip, 2]
                h = (s1 - s0) * L
                n = _order(2.0 * dist / h, deg, nmax)
                for k in range(n):
                    w = _panel_node(kid, kp, x0, x1, a, ux, uy, s0, s1, gx[n, k],
                                    gw[n, k] * h, normals[e], kind, p, gll_x, gll_b, kv,
                                    phi)
                    for j in range(nl):
                        g = dofs[e, j]
                        if g >= 0:
                            for r in range(nout):
                                for c in range(d):
                                    out[q, r, g, c] += w * (kv[r * d + c] * phi[j])
    return out


def potential_matrix(kid: int, kp, d: int, points, space, nout: int | None = None):
    """The matrix (n_points nout, ndof d) of the potential ``kid`` of
    :func:`evaluate_potential`: row nout q + r, column d g + c (interleaved, as its
    coefficients) is component r at points[q] of the density with coefficient 1 at dof g,
    component c - the columns of ``evaluate_potential(kid, kp, d, points, space, e_k)``
    bit for bit, in one pass instead of one per column.  Raises
    :class:`PointOnBoundaryError` if a point lies on Gamma."""
    nout = d if nout is None else int(nout)
    pts = evaluation_points(points)
    mesh = space.mesh
    gx, gw, _, _ = rules()
    gll_x, gll_b = gll_tables(P_MAX)
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    out = _potential_matrix_rows(int(kid), kp, int(d), nout, pts, mesh.nodes, mesh.elements,
                                 np.ascontiguousarray(mesh.normals), mesh.degrees,
                                 space.kind, space.elem_dofs, int(space.ndof), gx, gw,
                                 gll_x, gll_b)
    bad = ~np.all(np.isfinite(out.reshape(len(pts), -1)), axis=1)
    if np.any(bad):
        on = np.flatnonzero(bad)
        k = int(on[0])
        raise PointOnBoundaryError(
            f"points must lie off the boundary Gamma, where the representation formula "
            f"does not hold: point {k} = {tuple(pts[k].tolist())} lies on Gamma "
            f"({on.size} of {len(pts)} points do); use the boundary data there")
    return out.reshape(len(pts) * nout, space.ndof * d)
