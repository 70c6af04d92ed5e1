"""Gradient of the Laplace single-layer potential evaluated *on* Gamma (numba kernel).

    g(x) = PV int_Gamma grad_x G(x, y) f(y) ds_y,   G = -1/(2 pi) log|x - y|,

for x an interior point of a boundary element e and f in W_hp (Legendre on each element).
The two components used by the BE estimator are the tangential derivative of the single
layer, d/ds_x (V f)(x) = g . t_x (a Cauchy principal value on the element of x), and the
adjoint double layer K' f(x) = g . n_x (regular: n_x is orthogonal to x - y on the
straight element of x).  The length scale R of the kernel drops out of both.

* Own element (y on the straight element of x, x - y = (s_x - s_y) t_e): with reference
  coordinates t (of x) and tau,

      PV int f(tau) / (t - tau) dtau
          = f(t) log((1 + t)/(1 - t)) + int (f(tau) - f(t)) / (t - tau) dtau,

  the last integrand a polynomial of degree p - 2: Gauss with p points is exact.
* Other elements: the integrand is analytic on the element; the element is bisected until
  x is at least one sub-element length away, then Gauss with the order of
  :func:`hpfebe.bem.integration._order` (as in :mod:`hpfebe.bem.potentials`), which keeps
  the accuracy as x approaches a shared vertex.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..bem.integration import NMAX, _order, point_panels
from ..quadrature import rule_tables
from ..spaces import LEGENDRE, P_MAX, eval_basis, gll_tables

INV_2PI = 1.0 / (2.0 * math.pi)


@njit(cache=True, parallel=True)
def _grad_sl_on_gamma(qe, qt, nodes, elements, degrees, dofs, coef, gx, gw, gll_x, gll_b):
    npts = qe.shape[0]
    ne = elements.shape[0]
    nmax = gx.shape[0] - 1
    out = np.zeros((npts, 2))
    pmax = degrees.max() + 1
    for q in prange(npts):
        phi = np.empty(pmax)
        stack = np.empty((128, 2))
        panels = np.empty((128, 3))
        e0 = qe[q]
        a = nodes[elements[e0, 0]]
        b = nodes[elements[e0, 1]]
        ux, uy = b[0] - a[0], b[1] - a[1]
        L0 = math.hypot(ux, uy)
        tq = qt[q]
        s = 0.5 * (tq + 1.0)
        x0 = a[0] + s * ux
        x1 = a[1] + s * uy
        gxx = 0.0
        gyy = 0.0
        # ---- own element: Cauchy principal value, tangential only
        p = degrees[e0]
        eval_basis(LEGENDRE, p, tq, gll_x, gll_b, phi)
        ft = 0.0
        for j in range(p):
            ft += phi[j] * coef[dofs[e0, j]]
        pv = ft * math.log((1.0 + tq) / (1.0 - tq))
        n = p if p > 0 else 1
        for k in range(n):
            tau = 2.0 * gx[n, k] - 1.0
            w = 2.0 * gw[n, k]
            eval_basis(LEGENDRE, p, tau, gll_x, gll_b, phi)
            fv = 0.0
            for j in range(p):
                fv += phi[j] * coef[dofs[e0, j]]
            pv += w * (fv - ft) / (tq - tau)
        gxx += -INV_2PI * pv * ux / L0
        gyy += -INV_2PI * pv * uy / L0
        # ---- other elements
        for e in range(ne):
            if e == e0:
                continue
            a = nodes[elements[e, 0]]
            b = nodes[elements[e, 1]]
            vx, vy = b[0] - a[0], b[1] - a[1]
            L = math.hypot(vx, vy)
            p = degrees[e]
            # x lies on element e0, never on another one: no on-element test (tol_on < 0)
            npan = point_panels(x0, x1, a, b, -1.0, stack, panels)
            for ip in range(npan):
                s0, s1, dist = panels[ip, 0], panels[ip, 1], panels[ip, 2]
                h = (s1 - s0) * L
                n = _order(2.0 * dist / h, p + 1, nmax)
                for k in range(n):
                    ss = s0 + (s1 - s0) * gx[n, k]
                    w = gw[n, k] * h
                    rx = x0 - (a[0] + ss * vx)
                    ry = x1 - (a[1] + ss * vy)
                    r2 = rx * rx + ry * ry
                    eval_basis(LEGENDRE, p, 2.0 * ss - 1.0, gll_x, gll_b, phi)
                    fv = 0.0
                    for j in range(p):
                        fv += phi[j] * coef[dofs[e, j]]
                    c = -INV_2PI * w * fv / r2
                    gxx += c * rx
                    gyy += c * ry
        out[q, 0] = gxx
        out[q, 1] = gyy
    return out


def grad_single_layer_on_gamma(space, coeffs, elem, t) -> np.ndarray:
    """g(x) (shape (n, 2)) at the points of reference coordinates ``t`` (in (-1, 1),
    strictly) on elements ``elem``, for the density ``coeffs`` of the W_hp ``space``."""
    elem = np.ascontiguousarray(np.asarray(elem, dtype=np.int64).ravel())
    t = np.ascontiguousarray(np.broadcast_to(np.asarray(t, dtype=float), elem.shape).ravel())
    if t.size and np.max(np.abs(t)) >= 1.0:
        raise ValueError("t must lie strictly inside (-1, 1) (element interiors)")
    coef = np.ascontiguousarray(np.asarray(coeffs, dtype=float).ravel())
    if coef.size != space.ndof:
        raise ValueError(f"coeffs must have {space.ndof} entries, got {coef.size}")
    mesh = space.mesh
    gx, gw, _, _ = rule_tables(NMAX, n_log=0)
    gll_x, gll_b = gll_tables(P_MAX)
    return _grad_sl_on_gamma(elem, t, mesh.nodes, mesh.elements, mesh.degrees,
                             space.elem_dofs, coef, gx, gw, gll_x, gll_b)
