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
evaluated by ``kernel_batch`` once per batch of quadrature points, and by
``kernel_point`` (scalar arguments: a one-point batch call cost ~150 ns) at the single
points of the singular rules; ``logc`` is the (d*d) array of the log coefficients A.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..spaces import eval_basis, n_local
from .kernels import kernel_batch, kernel_point

TOL = 1e-16          # target relative quadrature error per direction
NMAX = 48            # largest Gauss order in tables
ETA = 1.0            # admissibility: dist >= ETA * size


@njit(cache=True)
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
def nearest_ends(aI, bI, aJ, bJ):
    """(rI, rJ): whether the end b (not a) of I, of J, is in the nearest pair of ends."""
    best = 1e300
    rI = False
    rJ = False
    for q in range(4):
        P = bI if q >= 2 else aI
        Q = bJ if q % 2 == 1 else aJ
        dd = (P[0] - Q[0]) ** 2 + (P[1] - Q[1]) ** 2
        if dd < best:
            best = dd
            rI = q >= 2
            rJ = q % 2 == 1
    return rI, rJ


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
        t = ((px - qx) * ux + (py - qy) * uy) / uu if uu > 0.0 else 0.0
        t = min(1.0, max(0.0, t))
        ex = px - qx - t * ux
        ey = py - qy - t * uy
        dd = ex * ex + ey * ey
        if dd < best:
            best = dd
    return math.sqrt(best)


@njit(cache=True)
def contract_block(Kq, Phi, Psi, nx, ny, mt, mr, d, tmp, out):
    """out[k*d + c1, l*d + c2] += sum_a Phi[a, k] sum_b Kq[a*ny + b, c1*d + c2] Psi[b, l]:
    the tensor quadrature sum of a local block, in two stages (inner sum over the trial
    points into ``tmp`` (nx, mr, d*d), then the test points); O(nx ny + nx mt mr) per
    kernel component instead of O(nx ny mt mr).  (The far-field fast path of
    :func:`hpfebe.bem.assembly_kernels._assemble_rows_serial` writes the same sum out over its
    tabulated bases: this helper there - called, inlined, on slices or on indexed 4D
    tables - made the assembly 1.3-1.9x slower at N = 4096, measured.)"""
    dd = d * d
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
def _weighted_basis(kind, p, sgn, u0, u1, L, n, gx, gw, gll_x, gll_b, B):
    """B[a, k] = w_a phi_k(t_a): the local basis at the n Gauss points of the parameter
    piece [u0, u1] of an element of length L (t = sgn (2 s - 1)), times the weights."""
    m = n_local(kind, p)
    for a in range(n):
        s = u0 + (u1 - u0) * gx[n, a]
        eval_basis(kind, p, sgn * (2.0 * s - 1.0), gll_x, gll_b, B[a])
        w = gw[n, a] * (u1 - u0) * L
        for k in range(m):
            B[a, k] *= w


@njit(cache=True)
def far_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, s0, s1, g0, g1, rI, rJ,
              kt, pt, kr, pr, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys, wx, ww,
              stack, out):
    """Disjoint (sub)elements, parameters [s0, s1] x [g0, g1]; adds the block to ``out``
    (shape (mt*d, mr*d), row = k*d + c1, col = l*d + c2).  ``rI`` (``rJ``): the parameter
    s of I (sigma of J) runs from its end b, not a, so that points near that end - where
    the pair is nearest - are exact in relative terms (s = 1 - 1e-8 is not).

    Parallel elements facing each other closer than their overlap go to
    :func:`parallel_block` (cost O(log(size / distance))).  Otherwise the parameter
    rectangle is bisected until every piece is admissible (distance >= ETA * size),
    each piece then integrated by tensor Gauss with orders from its distance/size ratio:
    near a point-like nearest set the pieces are graded toward it, O(log(size/distance))
    of them.  ``stack`` is scratch space of shape (>= 128, 4), ``wx``, ``ww`` of length
    >= 64 * NMAX."""
    nmax = gx.shape[0] - 1
    LI = math.hypot(bI[0] - aI[0], bI[1] - aI[1])
    LJ = math.hypot(bJ[0] - aJ[0], bJ[1] - aJ[1])
    # start points P, end points Q of the parametrisations; basis at t = sgn (2 s - 1)
    PI, QI, tI = (bI, aI, -1.0) if rI else (aI, bI, 1.0)
    PJ, QJ, tJ = (bJ, aJ, -1.0) if rJ else (aJ, bJ, 1.0)
    degt = pt - 1 if kt == 0 else pt
    degr = pr - 1 if kr == 0 else pr
    mt = n_local(kt, pt)
    mr = n_local(kr, pr)
    if _facing(PI, QI, PJ, QJ, s0, s1, g0, g1):
        # (tested first: a call with ~30 array arguments costs microseconds)
        parallel_block(kernel, logc, haslog, kp, d, PI, QI, nI, PJ, QJ, nJ, s0, s1, g0, g1,
                       tI, tJ, kt, pt, kr, pr, gx, gw, gll_x, gll_b, Phi[0], Psi[0], Kq,
                       rxs, rys, wx, ww, out)
        return
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = s0, s1, g0, g1
    top = 1
    whole = s0 == 0.0 and s1 == 1.0 and g0 == 0.0 and g1 == 1.0
    while top > 0:
        top -= 1
        u0, u1, v0, v1 = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
        hx = (u1 - u0) * LI
        hy = (v1 - v0) * LJ
        if hx <= 0.0 or hy <= 0.0:
            # a piece of zero measure (no contribution): the remainder of an adjacent
            # pair whose lengths differ by rounding only, halved below the spacing of
            # the doubles (N >= 8192 on a circle: the Duffy square leaves ~1e-13 L)
            continue
        nx = 0
        if whole:
            # well separated pair (the common case): midpoint distance minus the half
            # lengths is a lower bound of the distance, enough to choose the orders
            whole = False
            dlow = (math.hypot(0.5 * (aI[0] + bI[0] - aJ[0] - bJ[0]),
                               0.5 * (aI[1] + bI[1] - aJ[1] - bJ[1])) - 0.5 * (LI + LJ))
            if dlow >= 2.0 * ETA * max(LI, LJ):
                nx = _order(2.0 * dlow / LI, degt, nmax)
                ny = _order(2.0 * dlow / LJ, degr, nmax)
        if nx == 0:
            dist = _seg_dist(PI[0] + u0 * (QI[0] - PI[0]), PI[1] + u0 * (QI[1] - PI[1]),
                             PI[0] + u1 * (QI[0] - PI[0]), PI[1] + u1 * (QI[1] - PI[1]),
                             PJ[0] + v0 * (QJ[0] - PJ[0]), PJ[1] + v0 * (QJ[1] - PJ[1]),
                             PJ[0] + v1 * (QJ[0] - PJ[0]), PJ[1] + v1 * (QJ[1] - PJ[1]))
            if dist >= ETA * max(hx, hy) or top > 120:
                nx = _order(2.0 * dist / hx, degt, nmax)
                ny = _order(2.0 * dist / hy, degr, nmax)
        if nx > 0:
            # tensor Gauss nx x ny on [u0, u1] x [v0, v1]: weighted basis values, kernel
            # at the nx*ny points in one batch, two-stage contraction
            _weighted_basis(kt, pt, tI, u0, u1, LI, nx, gx, gw, gll_x, gll_b, Phi)
            _weighted_basis(kr, pr, tJ, v0, v1, LJ, ny, gx, gw, gll_x, gll_b, Psi)
            # r = (P_I - P_J) + s (Q_I - P_I) - sigma (Q_J - P_J): no absolute coordinates,
            # whose rounding is 1e-16 of the domain size, not of the distance
            for a in range(nx):
                s = u0 + (u1 - u0) * gx[nx, a]
                x0 = (PI[0] - PJ[0]) + s * (QI[0] - PI[0])
                x1 = (PI[1] - PJ[1]) + s * (QI[1] - PI[1])
                for b in range(ny):
                    g = v0 + (v1 - v0) * gx[ny, b]
                    rxs[a * ny + b] = x0 - g * (QJ[0] - PJ[0])
                    rys[a * ny + b] = x1 - g * (QJ[1] - PJ[1])
            npts = nx * ny
            kernel_batch(kernel, rxs, rys, npts, nI, nJ, kp, Kq)
            if haslog:
                for q in range(npts):
                    lr = 0.5 * math.log(rxs[q] * rxs[q] + rys[q] * rys[q])
                    for c in range(d * d):
                        Kq[q, c] += logc[c] * lr
            contract_block(Kq, Phi, Psi, nx, ny, mt, mr, d, tmp, out)
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


PARALLEL_TOL = 1e-13   # |sin(angle)| below which two elements count as parallel


@njit(cache=True)
def _facing(aI, bI, aJ, bJ, s0, s1, g0, g1):
    """Whether the parameter pieces [s0, s1] of I and [g0, g1] of J lie on distinct
    parallel lines, distance delta apart, and their projections on the common direction
    overlap or leave a gap below delta: the nearest set is a segment, or a point as close
    as delta - the pairs of :func:`parallel_block` (the bisection would need
    O(length / delta), resp. O(log(length / delta)) 2D pieces, each with ~200 points)."""
    ux, uy = bI[0] - aI[0], bI[1] - aI[1]
    vx, vy = bJ[0] - aJ[0], bJ[1] - aJ[1]
    LI = math.hypot(ux, uy)
    if abs(ux * vy - uy * vx) > PARALLEL_TOL * LI * math.hypot(vx, vy):
        return False
    tx, ty = ux / LI, uy / LI
    ea = (aJ[0] - aI[0]) * tx + (aJ[1] - aI[1]) * ty
    vt = vx * tx + vy * ty
    delta = math.hypot((aJ[0] - aI[0]) - ea * tx, (aJ[1] - aI[1]) - ea * ty)
    eta0 = min(ea + g0 * vt, ea + g1 * vt)
    eta1 = max(ea + g0 * vt, ea + g1 * vt)
    return delta > 0.0 and min(s1 * LI, eta1) - max(s0 * LI, eta0) > -delta


@njit(cache=True)
def parallel_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, s0, s1, g0, g1,
                   tI, tJ, kt, pt, kr, pr, gx, gw, gll_x, gll_b, phi, psi, Kq, rxs, rys, wx, ww,
                   out):
    """Parallel disjoint (sub)elements on lines a distance |w| apart whose projections
    overlap or nearly touch (issue 10: the two sides of a slit d apart; :func:`_facing`
    tells which pairs), added to ``out``.

    With xi = arc length along I from a_I (unit direction t) and eta the coordinate of
    the point of J projected on the same line, r = x - y = (xi - eta) t - w, w the
    constant offset of J's line: the kernel depends on z = xi - eta alone,

        B[k, l] = int k(z t - w) F_kl(z) dz,
        F_kl(z) = int_{eta_a(z)}^{eta_b(z)} phi_k(xi(eta + z)) psi_l(eta) d eta,

    F piecewise polynomial of degree deg_t + deg_r + 1 in z (breakpoints where an end of I
    meets an end of J) integrated exactly by Gauss in eta, and the outer integral by the
    composite rule :func:`_graded_rule` graded toward the complex singularity z = +-i|w|:
    O(log(length / |w|)) points, where the bisection of the parameter square needs
    O(length / |w|) pieces along its diagonal.  The elements run from a to b here; the
    basis functions are evaluated at t = tI (2 s - 1), tJ (2 sigma - 1) (tI = -1: the
    caller reversed I, see :func:`far_block`)."""
    ux, uy = bI[0] - aI[0], bI[1] - aI[1]
    vx, vy = bJ[0] - aJ[0], bJ[1] - aJ[1]
    LI = math.hypot(ux, uy)
    tx, ty = ux / LI, uy / LI
    ea = (aJ[0] - aI[0]) * tx + (aJ[1] - aI[1]) * ty      # eta of a_J
    vt = vx * tx + vy * ty                                 # +-L_J: d eta / d g
    wx_ = (aJ[0] - aI[0]) - ea * tx                        # offset of J's line from I's
    wy_ = (aJ[1] - aI[1]) - ea * ty
    delta = math.hypot(wx_, wy_)
    xi0, xi1 = s0 * LI, s1 * LI
    eta0 = min(ea + g0 * vt, ea + g1 * vt)
    eta1 = max(ea + g0 * vt, ea + g1 * vt)
    mt = n_local(kt, pt)
    mr = n_local(kr, pr)
    degt = pt - 1 if kt == 0 else pt
    degr = pr - 1 if kr == 0 else pr
    neta = (degt + degr) // 2 + 1              # Gauss in eta: exact for the product
    dd = d * d
    # z pieces: [xi0 - eta1, xi1 - eta0] split where an end of I meets an end of J and
    # at z = 0 (nearest to the singularity); each piece is parametrised from its end
    # nearer to z = 0, so that z is exact in relative terms where the kernel varies on
    # the scale |w| (z = za + hz x with za far from 0 loses digits: 4e-12 at |w| = 1e-6)
    zs = np.empty(5)
    zs[0], zs[1], zs[2], zs[3] = xi0 - eta1, xi0 - eta0, xi1 - eta1, xi1 - eta0
    zs[4] = min(max(0.0, zs[0]), zs[3])
    for q in range(1, 5):       # insertion sort, as zs.sort() (whose quicksort compiled
        zq = zs[q]              # three more functions: 1.2 s of a cold start)
        r = q
        while r > 0 and zq < zs[r - 1]:
            zs[r] = zs[r - 1]
            r -= 1
        zs[r] = zq
    for piece in range(4):
        za, zb = zs[piece], zs[piece + 1]
        hz = zb - za
        if not hz > 0.0:
            continue
        sgn = 1.0 if abs(za) <= abs(zb) else -1.0
        z0 = za if sgn > 0 else zb
        nz = _graded_rule(-sgn * z0 / hz, delta / hz, degt + degr + 1, gx, gw, wx, ww)
        for iz in range(nz):
            z = z0 + sgn * hz * wx[iz]
            wz = hz * ww[iz]
            ta = max(eta0, xi0 - z)
            tb = min(eta1, xi1 - z)
            if not tb > ta:
                continue
            rxs[0] = z * tx - wx_
            rys[0] = z * ty - wy_
            kernel_point(kernel, rxs[0], rys[0], nI[0], nI[1], nJ[0], nJ[1], kp, Kq)
            if haslog:
                lr = 0.5 * math.log(rxs[0] * rxs[0] + rys[0] * rys[0])
                for c in range(dd):
                    Kq[0, c] += logc[c] * lr
            for ie in range(neta):
                eta = ta + (tb - ta) * gx[neta, ie]
                eval_basis(kt, pt, tI * (2.0 * (eta + z) / LI - 1.0), gll_x, gll_b, phi)
                eval_basis(kr, pr, tJ * (2.0 * (eta - ea) / vt - 1.0), gll_x, gll_b, psi)
                _add_point(wz * (tb - ta) * gw[neta, ie], phi, psi, mt, mr, d, Kq, out)


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
    # regular part: Gauss in z and tau; log z part: log rule in z.  The two parts are
    # written out here and in adjacent_block, with the one-point kernel_point call:
    # the same code in inline="always" helpers made V + K + W
    # 1.2x slower at N = 64, p = 1 (issue 14; these pairs dominate small N)
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
                        kernel_point(kernel, rxs[0], rys[0], nI[0], nI[1], nI[0], nI[1], kp, Kq)
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
            # the log u part is logc times a polynomial of degree degw in w (no
            # singularity in w): Gauss with degw // 2 + 1 points is exact, where the
            # graded rule of part 0 spends ~11-13
            nwp = nw if part == 0 else degw // 2 + 1
            for iu in range(nuu):
                if part == 0:
                    u = gx[nu, iu]
                    wu = gw[nu, iu]
                else:
                    u = lx[nl, iu]
                    wu = -lw[nl, iu]
                for iw in range(nwp):
                    if part == 0:
                        w = wx[iw]
                        wt = wu * ww[iw] * u * ell * ell
                    else:
                        w = gx[nwp, iw]
                        wt = wu * gw[nwp, iw] * u * ell * ell
                    # local distances from v (fractions of ell) on I and J
                    if tri == 0:
                        a_loc, b_loc = u, u * w
                    else:
                        a_loc, b_loc = u * w, u
                    s = a_loc * fI if vI == 0 else 1.0 - a_loc * fI
                    g = b_loc * fJ if vJ == 0 else 1.0 - b_loc * fJ
                    eval_basis(kt, pt, 2.0 * s - 1.0, gll_x, gll_b, phi)
                    eval_basis(kr, pr, 2.0 * g - 1.0, gll_x, gll_b, psi)
                    if part == 0:
                        rxs[0] = ell * (a_loc * dIx - b_loc * dJx)
                        rys[0] = ell * (a_loc * dIy - b_loc * dJy)
                        kernel_point(kernel, rxs[0], rys[0], nI[0], nI[1], nJ[0], nJ[1], kp, Kq)
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
    # parametrised from the shared vertex (rI, rJ of far_block): exact near it
    # (one call site: LLVM inlines far_block into each, and each copy is compile time)
    longer_I = LI > LJ * (1.0 + 1e-13)
    if longer_I or LJ > LI * (1.0 + 1e-13):
        s0 = fI if longer_I else 0.0
        g0 = 0.0 if longer_I else fJ
        far_block(kernel, logc, haslog, kp, d, aI, bI, nI, aJ, bJ, nJ, s0, 1.0, g0, 1.0,
                  vI == 1, vJ == 1,
                  kt, pt, kr, pr, gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys, wx, ww,
                  stack, out)
