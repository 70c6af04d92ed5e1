"""Generic evaluation of boundary potentials at points off Gamma (representation formulas).

    P f(x) = int_Gamma k(x - y, n_y) f(y) ds_y,   f in W_hp^d or V_hp^d (interleaved),

for a numba kernel ``kernel(rx, ry, ny0, ny1, kp, out)`` writing the full (nout x d) kernel
matrix row-major (out[a * d + c]); r = x - y.  Specialised by the kernel like
:func:`hpfebe.bem.assembly.assemble`.  Each element is bisected until the point is at
least one sub-element length away, then Gauss with an order that grows with
log(size / distance) (the rule of :func:`hpfebe.bem.integration._order`), so the
accuracy holds uniformly up to (not on) the boundary.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..quadrature import rule_tables
from ..spaces import P_MAX, eval_basis, gll_tables, n_local
from .integration import NMAX, _order


@njit(cache=True, parallel=True)
def _potential(kernel, kp, d, nout, pts, nodes, elements, normals, degrees, kind, dofs,
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
        stack = np.empty((64, 2))
        x0, x1 = pts[q, 0], pts[q, 1]
        acc = np.zeros(nout)
        for e in range(ne):
            a = nodes[elements[e, 0]]
            b = nodes[elements[e, 1]]
            ux, uy = b[0] - a[0], b[1] - a[1]
            L = math.hypot(ux, uy)
            p = degrees[e]
            nl = n_local(kind, p)
            deg = p - 1 if kind == 0 else p
            stack[0, 0], stack[0, 1] = 0.0, 1.0
            top = 1
            while top > 0:
                top -= 1
                s0, s1 = stack[top, 0], stack[top, 1]
                h = (s1 - s0) * L
                t = ((x0 - a[0]) * ux + (x1 - a[1]) * uy) / (L * L)
                t = min(s1, max(s0, t))
                dist = math.hypot(x0 - a[0] - t * ux, x1 - a[1] - t * uy)
                if dist < h and top < 60 and h > 1e-14 * L:
                    m = 0.5 * (s0 + s1)
                    stack[top, 0], stack[top, 1] = s0, m
                    stack[top + 1, 0], stack[top + 1, 1] = m, s1
                    top += 2
                    continue
                n = _order(2.0 * dist / h, deg, nmax)
                for k in range(n):
                    s = s0 + (s1 - s0) * gx[n, k]
                    w = gw[n, k] * h
                    rx = x0 - (a[0] + s * ux)
                    ry = x1 - (a[1] + s * uy)
                    kernel(rx, ry, normals[e, 0], normals[e, 1], kp, kv)
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
            out[q, r] = acc[r]
    return out


def evaluate_potential(kernel, kp, d: int, points, space, coeffs, nout: int | None = None
                       ) -> np.ndarray:
    """Values (n_points, nout) of int k(x - y, n_y) f(y) ds_y, f = sum coeffs * basis of
    ``space`` (``coeffs`` of shape (ndof, d) or (ndof * d,), interleaved); ``nout``
    defaults to d.  Raises FloatingPointError if a point lies on Gamma."""
    nout = d if nout is None else int(nout)
    pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, dtype=float)))
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
    coef = np.ascontiguousarray(np.asarray(coeffs, dtype=float).reshape(-1, d))
    if coef.shape[0] != space.ndof:
        raise ValueError(f"coeffs must have {space.ndof * d} entries, got {coef.size}")
    mesh = space.mesh
    gx, gw, _, _ = rule_tables(NMAX)
    gll_x, gll_b = gll_tables(P_MAX)
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    out = _potential(kernel, kp, d, nout, pts, mesh.nodes, mesh.elements,
                     np.ascontiguousarray(mesh.normals), mesh.degrees, space.kind,
                     space.elem_dofs, coef, gx, gw, gll_x, gll_b)
    if not np.all(np.isfinite(out)):
        raise FloatingPointError("potential evaluated on the boundary Gamma")
    return out
