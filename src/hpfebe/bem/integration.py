"""Galerkin integration of boundary integral kernels over pairs of straight elements.

For a test element I and a trial element J the local block is

    B[k, l] = int_I int_J k(x - y) phi_k(x) psi_l(y) ds_y ds_x,

with a kernel split as  k(r) = A log|r| + k_reg(r)  (A constant, possibly zero; k_reg
homogeneous of degree 0 or -1 in r, plus constants).  Three integration cases, one
function each (the split of HILBERT and the ETH 2D parametric BEM code):

* ``coincident_block`` (I = J): the Sauter-Schwab substitution z = |s - sigma|
  turns the square into  int_0^1 dz int_0^(1-z) dt [...]; the log z part is integrated
  by the log-weighted Gauss rule (exact log moments), everything else is a polynomial
  in (z, tau) and integrated exactly by Gauss.  Cauchy-type kernels (degree -1, odd)
  cancel in the sum of the two triangles (principal value) and stay exact.
* ``adjacent_block`` (I, J share a vertex v): on the square of equal physical length
  l = min(|I|, |J|) at v, the Duffy map of each triangle factors |x - y| = u l R(w);
  log u goes to the log rule, the rest is polynomial in u and analytic in w with
  complex singularities at w = exp(+-i theta) (theta the angle at v): integrated by
  Gauss panels graded toward them.  The rest of the longer element is a far pair.
* ``far_block`` (disjoint): tensor Gauss on sub-rectangles of the parameter square,
  bisected until each is separated (distance >= its size); the order per direction
  grows with log(size / distance) through the Bernstein-ellipse radius rho:
  n = ln(1/tol) / (2 ln rho) + (degree + 1)/2.

``kernel`` is an integer id of :mod:`hpfebe.bem.kernels`; the regular part k_reg is
evaluated by ``kernel_batch`` once per batch of quadrature points, ``logc`` is the (d*d)
array of the log coefficients A.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..spaces import eval_basis, n_local
from .kernels import kernel_batch

TOL = 1e-16          # target relative quadrature error per direction
NMAX = 48            # largest Gauss order in tables
ETA = 1.0            # admissibility: dist >= ETA * size


@njit(cache=True, inline="always")
def _order(ratio, deg, nmax):
    """Gauss order for a function analytic outside a singularity at distance ``ratio``
    (relative to the half length of the interval) times a polynomial of degree deg."""
    # Gauss error for (poly of degree deg) x (analytic in the Bernstein ellipse rho):
    # ~ rho^(deg - 2n), so n = (ln(1/TOL) / ln(rho) + deg) / 2
    rho = ratio + math.sqrt(ratio * ratio + 1.0)
    n = int(math.ceil(0.5 * (math.log(1.0 / TOL) / math.log(rho) + deg)))
    return min(max(n, 1), nmax)


@njit(cache=True)
def point_panels(x0, x1, a, b, tol_on, stack, panels):
    """Panels [s0, s1] of the element [a, b] (parameter s in [0, 1]) for integrating a
    kernel singular at the point x: bisected until each panel is at least its own
    length away from x (60 levels at most), so that Gauss of order _order(2 dist / h)
    is accurate on each.  panels[k] = (s0, s1, dist); returns their number, or -1 if x
    lies on the element (distance <= tol_on |I|).  ``stack``, ``panels``: (>= 128, .)."""
    ux, uy = b[0] - a[0], b[1] - a[1]
    L = math.hypot(ux, uy)
    stack[0, 0], stack[0, 1] = 0.0, 1.0
    top = 1
    npan = 0
    while top > 0:
        top -= 1
        s0, s1 = stack[top, 0], stack[top, 1]
        h = (s1 - s0) * L
        t = ((x0 - a[0]) * ux + (x1 - a[1]) * uy) / (L * L)
        t = min(s1, max(s0, t))
        dist = math.hypot(x0 - a[0] - t * ux, x1 - a[1] - t * uy)
        if dist <= tol_on * L:
            return -1
        if dist < h and top < 60 and h > 1e-14 * L:
            m = 0.5 * (s0 + s1)
            stack[top, 0], stack[top, 1] = s0, m
            stack[top + 1, 0], stack[top + 1, 1] = m, s1
            top += 2
            continue
        panels[npan, 0], panels[npan, 1], panels[npan, 2] = s0, s1, dist
        npan += 1
    return npan


@njit(cache=True)
def _seg_dist(ax, ay, bx, by, cx, cy, dx, dy):
    """Distance between the segments [a, b] and [c, d] (assumed not crossing)."""
    best = 1e300
    for k in range(4):
        if k == 0:
            px, py, qx, qy, ux, uy = ax, ay, cx, cy, dx - cx, dy - cy
        elif k == 1:
            px, py, qx, qy, ux, uy = bx, by, cx, cy, dx - cx, dy - cy
        elif k == 2:
            px, py, qx, qy, ux, uy = cx, cy, ax, ay, bx - ax, by - ay
        else:
            px, py, qx, qy, ux, uy = dx, dy, ax, ay, bx - ax, by - ay
        uu = ux * ux + uy * uy
        t = ((px - qx) * ux + (py - qy) * uy) / uu
        t = min(1.0, max(0.0, t))
        ex = px - qx - t * ux
        ey = py - qy - t * uy
        dd = ex * ex + ey * ey
        if dd < best:
            best = dd
    return math.sqrt(best)


@njit(cache=True)
def _tensor_rect(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, s0, s1, g0, g1,
                 kt, pt, kr, pr, nx, ny, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys,
                 out):
    """Tensor Gauss (nx x ny) on [s0,s1] x [g0,g1] of the element parameters; adds the
    block to ``out`` (shape (mt*d, mr*d), row = k*d + c1, col = l*d + c2)."""
    LI = math.hypot(bI[0] - aI[0], bI[1] - aI[1])
    LJ = math.hypot(bJ[0] - aJ[0], bJ[1] - aJ[1])
    mt = n_local(kt, pt)
    mr = n_local(kr, pr)
    for a in range(nx):
        s = s0 + (s1 - s0) * gx[nx, a]
        eval_basis(kt, pt, 2.0 * s - 1.0, gll_x, gll_b, Phi[a])
        wa = gw[nx, a] * (s1 - s0) * LI
        for k in range(mt):
            Phi[a, k] *= wa
    for b in range(ny):
        g = g0 + (g1 - g0) * gx[ny, b]
        eval_basis(kr, pr, 2.0 * g - 1.0, gll_x, gll_b, Psi[b])
        wb = gw[ny, b] * (g1 - g0) * LJ
        for l in range(mr):
            Psi[b, l] *= wb
    dd = d * d
    for a in range(nx):
        s = s0 + (s1 - s0) * gx[nx, a]
        x0 = aI[0] + s * (bI[0] - aI[0])
        x1 = aI[1] + s * (bI[1] - aI[1])
        for b in range(ny):
            g = g0 + (g1 - g0) * gx[ny, b]
            rxs[a * ny + b] = x0 - (aJ[0] + g * (bJ[0] - aJ[0]))
            rys[a * ny + b] = x1 - (aJ[1] + g * (bJ[1] - aJ[1]))
    npts = nx * ny
    kernel_batch(kernel, rxs, rys, npts, nI, nJ, kp, Kq)
    if haslog:
        for q in range(npts):
            lr = 0.5 * math.log(rxs[q] * rxs[q] + rys[q] * rys[q])
            for c in range(dd):
                Kq[q, c] += logc[c] * lr
    # out[k, l] += sum_a Phi[a,k] sum_b Kq[a,b] Psi[b,l]
    for a in range(nx):
        for l in range(mr):
            for c in range(dd):
                acc = 0.0
                for b in range(ny):
                    acc += Kq[a * ny + b, c] * Psi[b, l]
                tmp[a, l, c] = acc
    for k in range(mt):
        for l in range(mr):
            for c1 in range(d):
                for c2 in range(d):
                    acc = 0.0
                    for a in range(nx):
                        acc += Phi[a, k] * tmp[a, l, c1 * d + c2]
                    out[k * d + c1, l * d + c2] += acc


@njit(cache=True)
def far_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, s0, s1, g0, g1,
              kt, pt, kr, pr, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys, stack,
              out):
    """Disjoint (sub)elements: bisect the parameter rectangle until every piece is
    admissible, then tensor Gauss with orders from the distance/size ratio.
    ``stack`` is scratch space of shape (>= 128, 4)."""
    nmax = gx.shape[0] - 1
    LI = math.hypot(bI[0] - aI[0], bI[1] - aI[1])
    LJ = math.hypot(bJ[0] - aJ[0], bJ[1] - aJ[1])
    degt = pt - 1 if kt == 0 else pt
    degr = pr - 1 if kr == 0 else pr
    if s0 == 0.0 and s1 == 1.0 and g0 == 0.0 and g1 == 1.0:
        # well separated pair (the common case): midpoint distance minus the half
        # lengths is a lower bound of the distance, enough to choose the orders
        dlow = (math.hypot(0.5 * (aI[0] + bI[0] - aJ[0] - bJ[0]),
                           0.5 * (aI[1] + bI[1] - aJ[1] - bJ[1])) - 0.5 * (LI + LJ))
        if dlow >= 2.0 * ETA * max(LI, LJ):
            nx = _order(2.0 * dlow / LI, degt, nmax)
            ny = _order(2.0 * dlow / LJ, degr, nmax)
            _tensor_rect(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, 0.0, 1.0,
                         0.0, 1.0, kt, pt, kr, pr, nx, ny, gx, gw, gll_x, gll_b,
                         Phi, Psi, Kq, tmp, rxs, rys, out)
            return
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = s0, s1, g0, g1
    top = 1
    while top > 0:
        top -= 1
        u0, u1, v0, v1 = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
        hx = (u1 - u0) * LI
        hy = (v1 - v0) * LJ
        dist = _seg_dist(aI[0] + u0 * (bI[0] - aI[0]), aI[1] + u0 * (bI[1] - aI[1]),
                         aI[0] + u1 * (bI[0] - aI[0]), aI[1] + u1 * (bI[1] - aI[1]),
                         aJ[0] + v0 * (bJ[0] - aJ[0]), aJ[1] + v0 * (bJ[1] - aJ[1]),
                         aJ[0] + v1 * (bJ[0] - aJ[0]), aJ[1] + v1 * (bJ[1] - aJ[1]))
        if dist >= ETA * max(hx, hy) or top > 120:
            nx = _order(2.0 * dist / hx, degt, nmax)
            ny = _order(2.0 * dist / hy, degr, nmax)
            _tensor_rect(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, u0, u1, v0, v1,
                         kt, pt, kr, pr, nx, ny, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp,
                         rxs, rys, out)
            continue
        split_x = hx > 0.5 * hy
        split_y = hy > 0.5 * hx
        um = 0.5 * (u0 + u1)
        vm = 0.5 * (v0 + v1)
        if split_x and split_y:
            for q in range(4):
                stack[top, 0] = u0 if q < 2 else um
                stack[top, 1] = um if q < 2 else u1
                stack[top, 2] = v0 if q % 2 == 0 else vm
                stack[top, 3] = vm if q % 2 == 0 else v1
                top += 1
        elif split_x:
            stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = u0, um, v0, v1
            stack[top + 1, 0], stack[top + 1, 1] = um, u1
            stack[top + 1, 2], stack[top + 1, 3] = v0, v1
            top += 2
        else:
            stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = u0, u1, v0, vm
            stack[top + 1, 0], stack[top + 1, 1] = u0, u1
            stack[top + 1, 2], stack[top + 1, 3] = vm, v1
            top += 2


@njit(cache=True, inline="always")
def _add_point(w, phi, psi, mt, mr, d, Kq, out):
    """out[k, l] += w phi_k psi_l k(r) for one quadrature point (kernel values in Kq[0])."""
    for k in range(mt):
        for l in range(mr):
            f = w * phi[k] * psi[l]
            for c1 in range(d):
                for c2 in range(d):
                    out[k * d + c1, l * d + c2] += f * Kq[0, c1 * d + c2]


@njit(cache=True)
def coincident_block(kernel, logc, haslog, kp, d, aI, bI, nI, kt, pt, kr, pr,
                     gx, gw, lx, lw, gll_x, gll_b, phi, psi, Kq, rxs, rys, out):
    """I = J (straight): Sauter-Schwab in z = |s - sigma| with the exact log rule."""
    L = math.hypot(bI[0] - aI[0], bI[1] - aI[1])
    ex = (bI[0] - aI[0]) / L
    ey = (bI[1] - aI[1]) / L
    mt = n_local(kt, pt)
    mr = n_local(kr, pr)
    degt = pt - 1 if kt == 0 else pt
    degr = pr - 1 if kr == 0 else pr
    deg = degt + degr
    ntau = deg // 2 + 1
    nz = (deg + 3) // 2 + 1
    nl = (deg + 3) // 2 + 1
    dd = d * d
    logL = math.log(L)
    # regular part: Gauss in z and tau; log z part: log rule in z
    for part in range(2):
        nzz = nz if part == 0 else nl
        for iz in range(nzz):
            if part == 0:
                z = gx[nz, iz]
                wz = gw[nz, iz]
            else:
                z = lx[nl, iz]
                wz = -lw[nl, iz]     # int log z f = - sum lw f
            for it in range(ntau):
                t = (1.0 - z) * gx[ntau, it]
                w = wz * gw[ntau, it] * (1.0 - z) * L * L
                for side in range(2):
                    if side == 0:
                        s, g, sgn = t + z, t, 1.0
                    else:
                        s, g, sgn = t, t + z, -1.0
                    eval_basis(kt, pt, 2.0 * s - 1.0, gll_x, gll_b, phi)
                    eval_basis(kr, pr, 2.0 * g - 1.0, gll_x, gll_b, psi)
                    if part == 0:
                        rxs[0] = sgn * z * L * ex
                        rys[0] = sgn * z * L * ey
                        kernel_batch(kernel, rxs, rys, 1, nI, nI, kp, Kq)
                        if haslog:
                            for c in range(dd):
                                Kq[0, c] += logc[c] * logL
                    else:
                        for c in range(dd):
                            Kq[0, c] = logc[c]
                    _add_point(w, phi, psi, mt, mr, d, Kq, out)
            if part == 1 and not haslog:
                break


@njit(cache=True)
def _graded_rule(zr, zi, deg, gx, gw, xs, ws):
    """Composite Gauss rule on [0, 1] for a polynomial of degree deg times a function
    analytic except at zr +- i zi: panels bisected until admissible, order per panel from
    its Bernstein-ellipse radius.  Returns the number of points written to xs, ws."""
    nmax = gx.shape[0] - 1
    stack = np.empty((64, 2))
    stack[0, 0], stack[0, 1] = 0.0, 1.0
    top = 1
    npts = 0
    while top > 0:
        top -= 1
        a, b = stack[top, 0], stack[top, 1]
        h = b - a
        # distance of the singularity to the panel
        cx = min(b, max(a, zr))
        dist = math.hypot(zr - cx, zi)
        if dist >= ETA * h or top > 60 or h < 1e-12:
            # Bernstein radius of the singularity for this panel
            zeta = complex((2.0 * zr - a - b) / h, 2.0 * zi / h)
            root = np.sqrt(zeta * zeta - 1.0)
            rho = max(abs(zeta + root), abs(zeta - root))
            n = int(math.ceil(0.5 * (math.log(1.0 / TOL) / math.log(rho) + deg)))
            n = min(max(n, 1), nmax)
            if npts + n > xs.shape[0]:
                n = xs.shape[0] - npts
            for q in range(n):
                xs[npts + q] = a + h * gx[n, q]
                ws[npts + q] = h * gw[n, q]
            npts += n
            continue
        m = 0.5 * (a + b)
        stack[top, 0], stack[top, 1] = a, m
        stack[top + 1, 0], stack[top + 1, 1] = m, b
        top += 2
    return npts


@njit(cache=True)
def adjacent_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, vI, vJ,
                   kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b,
                   phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack, out):
    """I and J share a vertex: vI = 0 if it is I's start, 1 if its end; likewise vJ."""
    LI = math.hypot(bI[0] - aI[0], bI[1] - aI[1])
    LJ = math.hypot(bJ[0] - aJ[0], bJ[1] - aJ[1])
    ell = min(LI, LJ)
    # unit directions from the shared vertex into I and J
    sI = 1.0 if vI == 0 else -1.0
    sJ = 1.0 if vJ == 0 else -1.0
    dIx, dIy = sI * (bI[0] - aI[0]) / LI, sI * (bI[1] - aI[1]) / LI
    dJx, dJy = sJ * (bJ[0] - aJ[0]) / LJ, sJ * (bJ[1] - aJ[1]) / LJ
    cth = max(-1.0, min(1.0, dIx * dJx + dIy * dJy))
    sth = math.sqrt(max(0.0, 1.0 - cth * cth))
    mt = n_local(kt, pt)
    mr = n_local(kr, pr)
    degt = pt - 1 if kt == 0 else pt
    degr = pr - 1 if kr == 0 else pr
    deg = degt + degr
    nu = (deg + 3) // 2 + 1
    nl = (deg + 3) // 2 + 1
    dd = d * d
    fI = ell / LI   # fraction of I (and J) inside the Duffy square
    fJ = ell / LJ
    for tri in range(2):
        degw = degr if tri == 0 else degt
        nw = _graded_rule(cth, sth, degw, gx, gw, wx, ww)
        for part in range(2):
            if part == 1 and not haslog:
                break
            nuu = nu if part == 0 else nl
            for iu in range(nuu):
                if part == 0:
                    u = gx[nu, iu]
                    wu = gw[nu, iu]
                else:
                    u = lx[nl, iu]
                    wu = -lw[nl, iu]
                for iw in range(nw):
                    w = wx[iw]
                    # local distances from v (fractions of ell) on I and J
                    if tri == 0:
                        a_loc, b_loc = u, u * w
                    else:
                        a_loc, b_loc = u * w, u
                    wt = wu * ww[iw] * u * ell * ell
                    s = a_loc * fI if vI == 0 else 1.0 - a_loc * fI
                    g = b_loc * fJ if vJ == 0 else 1.0 - b_loc * fJ
                    eval_basis(kt, pt, 2.0 * s - 1.0, gll_x, gll_b, phi)
                    eval_basis(kr, pr, 2.0 * g - 1.0, gll_x, gll_b, psi)
                    if part == 0:
                        rxs[0] = ell * (a_loc * dIx - b_loc * dJx)
                        rys[0] = ell * (a_loc * dIy - b_loc * dJy)
                        kernel_batch(kernel, rxs, rys, 1, nI, nJ, kp, Kq)
                        if haslog:
                            if tri == 0:
                                R = math.hypot(dIx - w * dJx, dIy - w * dJy)
                            else:
                                R = math.hypot(w * dIx - dJx, w * dIy - dJy)
                            lr = math.log(ell * R)
                            for c in range(dd):
                                Kq[0, c] += logc[c] * lr
                    else:
                        for c in range(dd):
                            Kq[0, c] = logc[c]
                    _add_point(wt, phi, psi, mt, mr, d, Kq, out)
    # the part of the longer element outside the Duffy square is a far pair
    if LI > LJ * (1.0 + 1e-13):
        s0, s1 = (fI, 1.0) if vI == 0 else (0.0, 1.0 - fI)
        far_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, s0, s1, 0.0, 1.0,
                  kt, pt, kr, pr, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys, stack,
                  out)
    elif LJ > LI * (1.0 + 1e-13):
        g0, g1 = (fJ, 1.0) if vJ == 0 else (0.0, 1.0 - fJ)
        far_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, 0.0, 1.0, g0, g1,
                  kt, pt, kr, pr, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys, stack,
                  out)
