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
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..spaces import P_MAX, eval_basis, gll_tables, n_local
from .assembly import rules
from .integration import _order, point_panels
from .kernels import (INV_2PI, KP_C1, KP_C1_C2, KP_C1_LOG_R, KP_C2, KP_LAMBDA,
                      KP_LAPLACE_LOG_R, KP_MU, _log_rr, _traction_of_G)

# potential kernel ids; kp is the parameter array of the owning operator class
POT_LAME_SL, POT_LAME_DL, POT_LAME_SL_GRAD, POT_LAME_DL_GRAD = 0, 1, 2, 3
POT_LAPLACE_SL, POT_LAPLACE_DL = 4, 5   # kp = [log(R) / (2 pi)]


@njit(cache=True, inline="always")
def _neg_hess(i, j, l, m, rx, ry, r2, r4, c1, c2):
    """-d^2 G_ji / dr_l dr_m (see _lame_grad_kernels)."""
    ri = rx if i == 0 else ry
    rj = rx if j == 0 else ry
    rl = rx if l == 0 else ry
    rm = rx if m == 0 else ry
    dij = 1.0 if i == j else 0.0
    dil = 1.0 if i == l else 0.0
    dim = 1.0 if i == m else 0.0
    djl = 1.0 if j == l else 0.0
    djm = 1.0 if j == m else 0.0
    dlm = 1.0 if l == m else 0.0
    h = (-dij * (dlm / r2 - 2.0 * rl * rm / r4)
         + c2 * (dil * djm + djl * dim) / r2
         - 2.0 * c2 * (dil * rj + djl * ri) * rm / r4
         - 2.0 * c2 * (dim * rj * rl + ri * djm * rl + ri * rj * dlm) / r4
         + 8.0 * c2 * ri * rj * rl * rm / (r4 * r2))
    return -c1 * h


@njit(cache=True, inline="always")
def _lame_grad_kernels(rx, ry, ny0, ny1, lam, mu, c1, c2, double, out):
    """x-gradients of the Lame kernels at r = x - y, out[(i*2 + m)*2 + k]:
    d/dx_m G_ik (double = False) or d/dx_m K_ik, K_ik = [sigma_y(G(x,.) e_i) n_y]_k.
    With g_l = dG_ji/dr_l
        = c1 (-d_ij r_l + c2 (d_il r_j + d_jl r_i) - 2 c2 r_i r_j r_l/|r|^2)/|r|^2
    and its r_m-derivative H_jlm; grad_y = -grad_r, so d/dx_m of D_jl = -g_l is -H_jlm."""
    r2 = rx * rx + ry * ry
    r4 = r2 * r2
    for i in range(2):
        for m in range(2):
            rm = rx if m == 0 else ry
            ri = rx if i == 0 else ry
            if not double:
                for k in range(2):
                    rk = rx if k == 0 else ry
                    dik = 1.0 if i == k else 0.0
                    dim = 1.0 if i == m else 0.0
                    dkm = 1.0 if k == m else 0.0
                    out[(i * 2 + m) * 2 + k] = c1 * (-dik * rm / r2 + c2 * (
                        (dim * rk + ri * dkm) / r2 - 2.0 * ri * rk * rm / r4))
                continue
            # d/dx_m of D_jl = -H_jlm (j, l = 0, 1)
            d00 = _neg_hess(i, 0, 0, m, rx, ry, r2, r4, c1, c2)
            d01 = _neg_hess(i, 0, 1, m, rx, ry, r2, r4, c1, c2)
            d10 = _neg_hess(i, 1, 0, m, rx, ry, r2, r4, c1, c2)
            d11 = _neg_hess(i, 1, 1, m, rx, ry, r2, r4, c1, c2)
            div = d00 + d11
            s00 = lam * div + 2.0 * mu * d00
            s11 = lam * div + 2.0 * mu * d11
            s01 = mu * (d01 + d10)
            out[(i * 2 + m) * 2 + 0] = s00 * ny0 + s01 * ny1
            out[(i * 2 + m) * 2 + 1] = s01 * ny0 + s11 * ny1


@njit(cache=True)
def pot_kernel(kid, rx, ry, ny0, ny1, kp, out):
    """Full kernel at r = x - y (x off Gamma): Laplace G and d_{n_y} G (kp = [log(R)/(2 pi)]),
    Lame G (single layer, kp of :func:`hpfebe.bem.lame.kernel_params`, indices KP_* of
    :mod:`.kernels`), its y-traction (double layer), or the x-gradients of both (nout = 4:
    rows (i, m) = d/dx_m of component i)."""
    if kid == POT_LAPLACE_SL:
        out[0] = kp[KP_LAPLACE_LOG_R] - INV_2PI * 0.5 * math.log(rx * rx + ry * ry)
    elif kid == POT_LAPLACE_DL:
        out[0] = INV_2PI * (rx * ny0 + ry * ny1) / (rx * rx + ry * ry)
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


@njit(cache=True, parallel=True)
def _potential(kid, kp, d, nout, pts, nodes, elements, normals, degrees, kind, dofs,
               coef, gx, gw, gll_x, gll_b):
    npts = pts.shape[0]
    ne = elements.shape[0]
    nmax = gx.shape[0] - 1
    out = np.zeros((npts, nout))
    pmax = degrees.max() + 1
    for q in prange(npts):
        phi = np.empty(pmax)
        kv = np.empty(nout * d)
        fv = np.empty(d)
        stack = np.empty((128, 2))
        panels = np.empty((128, 3))
        x0, x1 = pts[q, 0], pts[q, 1]
        acc = np.zeros(nout)
        onb = False
        for e in range(ne):
            a = nodes[elements[e, 0]]
            b = nodes[elements[e, 1]]
            ux, uy = b[0] - a[0], b[1] - a[1]
            L = math.hypot(ux, uy)
            p = degrees[e]
            nl = n_local(kind, p)
            deg = p - 1 if kind == 0 else p
            npan = point_panels(x0, x1, a, b, 1e-13, stack, panels)
            if npan < 0:
                onb = True      # x on Gamma: the potential is not defined there
                break
            for ip in range(npan):
                s0, s1, dist = panels[ip, 0], panels[ip, 1], panels[ip, 2]
                h = (s1 - s0) * L
                n = _order(2.0 * dist / h, deg, nmax)
                for k in range(n):
                    s = s0 + (s1 - s0) * gx[n, k]
                    w = gw[n, k] * h
                    rx = x0 - (a[0] + s * ux)
                    ry = x1 - (a[1] + s * uy)
                    pot_kernel(kid, rx, ry, normals[e, 0], normals[e, 1], kp, kv)
                    eval_basis(kind, p, 2.0 * s - 1.0, gll_x, gll_b, phi)
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
    return out


def evaluate_potential(kid: int, kp, d: int, points, space, coeffs, nout: int | None = None
                       ) -> np.ndarray:
    """Values (n_points, nout) of int k(x - y, n_y) f(y) ds_y, f = sum coeffs * basis of
    ``space`` (``coeffs`` of shape (ndof, d) or (ndof * d,), interleaved); ``nout``
    defaults to d.  Raises FloatingPointError if a point lies on Gamma."""
    nout = d if nout is None else int(nout)
    pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, dtype=float)))
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
    bad = ~np.all(np.isfinite(pts), axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(f"points must be finite: point {k} = {tuple(pts[k])} has a "
                         "non-finite (NaN or inf) coordinate")
    coef = np.ascontiguousarray(np.asarray(coeffs, dtype=float).reshape(-1, d))
    if coef.shape[0] != space.ndof:
        raise ValueError(f"coeffs must have {space.ndof * d} entries, got {coef.size}")
    mesh = space.mesh
    gx, gw, _, _ = rules()
    gll_x, gll_b = gll_tables(P_MAX)
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    out = _potential(int(kid), kp, d, nout, pts, mesh.nodes, mesh.elements,
                     np.ascontiguousarray(mesh.normals), mesh.degrees, space.kind,
                     space.elem_dofs, coef, gx, gw, gll_x, gll_b)
    if not np.all(np.isfinite(out)):
        raise FloatingPointError("potential evaluated on the boundary Gamma")
    return out
