"""Closed forms of one element pair for the lowest-order (p = 1) operators: the integrals
I (single layer), J0, J1 (double layer) and Q (the Lame operators' r r^T / r^2), by the
corner sums (V1), (K1), (Q1) for near pairs and the truncated series (Q2) for far ones.
The matrices built from them: :mod:`.lowest_order` (Laplace V, K, W) and
:mod:`.lowest_order_lame` (Lame V, K, Vt, W).

Notation.  Test element E_i = [a_i, b_i], trial element E_j = [a_j, b_j], lengths L_i,
L_j, unit directions u = (b_i - a_i)/L_i, v = (b_j - a_j)/L_j, outward normal of E_j
n_j = -i v (the rotation (v_2, -v_1) of :attr:`BoundaryMesh.normals`).  With the
midpoints m_i, m_j and centred parameters s in [-L_i/2, L_i/2], t in [-L_j/2, L_j/2],

    x - y = w(s, t) = w_m + s u - t v,        w_m = m_i - m_j.

Both kernels are real parts of analytic functions of w:

    log|x - y| = Re log w,        (x - y) . n_j / |x - y|^2 = Re(n_j / w).

Since d^2/ds dt F(w(s, t)) = -u v F''(w), the integral of F'' over the parameter
rectangle is -(u v)^(-1) sum_c s_c F(w_c) over its four corners w_c = x_c - y_c
(x_c in {a_i, b_i}, y_c in {a_j, b_j}, s_c = +1 for (b_i, b_j) and (a_i, a_j), -1
otherwise), for any branch of log that is continuous on the image of the rectangle (the
set E_i - E_j, convex, and without 0 unless the elements intersect).  Measuring every
argument from w_m (log(w_c / w_m), principal value) is such a branch, and the constant
log w_m drops out of the sums (sum_c s_c w_c = 0, sum_c s_c w_c^2 = -2 u v L_i L_j):

  single layer (F = w^2 (log w - 3/2) / 2), I = int int log|x - y| ds_y ds_x,

    I = L_i L_j (log|w_m| - 3/2) - Re[ (2 u v)^(-1) sum_c s_c w_c^2 log(w_c / w_m) ],   (V1)

    V_ij = -(I - L_i L_j log R) / (2 pi);  identical elements: I = L^2 (log L - 3/2);

  double layer, J0 = int int 1/w and J1 = int int t / w (by s, then t, in closed form),

    J0 = -(u v)^(-1) sum_c s_c w_c log(w_c / w_m),                                     (K1)
    J1 = -(u v^2)^(-1) [ sum_c s_c w_c (w_c / 2 + t_c v) log(w_c / w_m) + u v L_i L_j / 2 ],

    K_i,a_j = Re[n_j (J0/2 - J1/L_j)] / (2 pi),   K_i,b_j = Re[n_j (J0/2 + J1/L_j)] / (2 pi)

(hats 1/2 -+ t/L_j).  The pair (j, i) has the corners -w_c, the same logarithms, and the
roles of (u, s) and (v, t) exchanged: one set of four logarithms gives V_ij, the K entries
of (i, j) and those of (j, i).  A corner w_c = 0 (a shared vertex) contributes 0 (the
limit of w^2 log w and w log w); adjacent elements at any angle, parallel and collinear
pairs need no other case.  Collinear pairs have K = 0 exactly ((x - y) . n_j = 0), and
are set so.

Cancellation.  The corner terms are of size |w_c|^2 |log|, the results of size L_i L_j
(V) and smaller (K): the sums are paired along the shorter element (:func:`_pair_sums`,
which removes the loss L_j / L_i of very different sizes), and what remains grows with
|w_m| / L, most for J1 (~ (|w_m| / L)^3: over random pairs with sizes within a factor
20, measured worst 3.9e-13 of L_i L_j / |w_m| at q = 1/4, 1.9e-12 at q = 1/8, against
the series).  Well separated pairs, q = (L_i + L_j) / (2 |w_m|) < Q_NEAR, and nearly
parallel ones with q < Q_SMOOTH (see accuracy below) therefore use the Taylor expansion in
w_m instead (a multipole expansion; with a = u L_i / (2 w_m), b = -v L_j / (2 w_m) and
the moments E[alpha^m] = 1/(m+1) (m even) of the uniform distribution on [-1, 1]):

    I / (L_i L_j) = log|w_m| + Re sum_{m, j even, m+j >= 2} cV_mj a^m b^j,
        cV_mj = -C(m+j, m) / ((m+j) (m+1) (j+1)),
    J0 = (L_i L_j / w_m) sum_{m, j even} c0_mj a^m b^j,   c0_mj = C(m+j, m) / ((m+1)(j+1)),
    J1 / L_j = (L_i L_j / (2 w_m)) sum_{m even, j odd} c1_mj a^m b^j,
        c1_mj = -C(m+j, m) / ((m+1)(j+2)),

truncated at total degree m + j <= n.  The tail is bounded by sum_{k>n} E[(|alpha| |a| +
|beta| |b|)^k] <= 2 q^(n+1) / ((n+3)(1 - q)) (relative to L_i L_j / |w_m|, and the
single layer's terms have an extra 1/k), so n is the least order with that bound below
SERIES_TOL: no logarithm but log|w_m|, and no cancellation (all terms decrease).

Accuracy against the general quadrature path (tests/bem/test_bem_lowest_order.py): at most
4.3e-15 of the largest entry on squares (N = 16 ... 256), an L-shape, slits of width
1e-2 ... 1e-8, a 3 degree wedge, a star and a 12 times graded mesh.  On smooth curves
(curvature radius rho) the K entries of neighbours are ~ L / rho smaller than L_i L_j /
|w_m| (the kernel is of the order of the curvature), and the closed form's error relative
to them that much larger (a 4096-gon: 2e-13 .. 4e-13 of the entry at q = 1/4 ... 1/2);
nearly parallel pairs off one line with q < Q_SMOOTH therefore take the series too
(2e-15 .. 2e-14 there), and w_m is formed from differences of nearby nodes (exact) so
that it has full relative accuracy (0.5 (a_i + b_i) - 0.5 (a_j + b_j) cost 3e-12 of
these entries).  Against mpmath on the 4096-gon the K entries at node offsets 3 .. 6 are
then within 1e-14 of the largest entry, where the general path's Gauss fast path is off
by 2.5e-13 .. 4.3e-13: the 1e-12 difference of the two paths there is the general one's.

Lame operators (:mod:`hpfebe.bem.lame`: G = c1 {-log(r/R) I + c2 r r^T/r^2}, the
hypersingular kernel Vt = Et {-log(r/R) I + r r^T/r^2}).  Besides I they need one complex
integral per pair,

    Q = int int w / conj(w) ds_y ds_x,   since  r r^T / r^2 = 1/2 I + 1/2 [[Re q, Im q],
                                                                 [Im q, -Re q]],  q = w / conj w.

Corner sum: with wb = conj(w), F(w, wb) = w g(wb) + h(wb) has d^2 F / ds dt = w / wb for
g(z) = -(z log z - z) / (ub vb), h(z) = c (z^2 log z / 2 - 3 z^2 / 4), c = (u vb + ub v) /
(ub vb)^2 (ub = conj u; check: d^2F/dsdt = -g'(wb) (u vb + ub v) - ub vb (w g'' + h'')
with g'' = -1 / (ub vb wb) and h'' = c log wb).  Summing F over the corners as in (V1),
with log wb_c = log wb_m + conj(l_c), l_c = log(w_c / w_m): the constant log wb_m
multiplies -(ub vb)^(-1) sum s_c |w_c|^2 + c/2 sum s_c wb_c^2 = 2 Re(u vb) L_i L_j / (ub
vb) - 2 Re(u vb) L_i L_j / (ub vb) = 0 (sum s_c |w_c|^2 = -2 Re(u vb) L_i L_j, sum s_c
wb_c^2 = -2 ub vb L_i L_j), so the same branch as (V1) serves, and

    conj Q = -(u v)^(-1) sum_c s_c |w_c|^2 l_c + Re(u vb) (u v)^(-2) sum_c s_c w_c^2 l_c
             + Re(u vb) L_i L_j / (u v)                                                 (Q1)

(sum s_c w_c^2 l_c is the sum of (V1); that of |w|^2 is paired along the shorter element
like it, :func:`_pair_sums`).  A corner w_c = 0 contributes 0; collinear pairs (the
identical one included) have Q = u^2 L_i L_j exactly and are set so.  Far pairs:
w / wb = (w_m / wb_m) (1 + z) / (1 + conj z), z = a alpha + b beta (a, b as above), and
E[(1 + z) sum_k (-conj z)^k] has only the moments E[conj z^k] (k even: the c0 sums) and
E[alpha conj z^k], E[beta conj z^k] (k odd: the c1 sums with the roles of a, b as in J1
and J1'), so with the sums s0 = sum c0_mj a^m b^j, s1 = sum c1_mj a^m b^j (m even, j
odd), s1' = sum c1_jm a^m b^j (m odd, j even) that give J0, J1, J1',

    Q = L_i L_j (w_m / wb_m) [conj(s0) + a conj(s1') + b conj(s1)],                    (Q2)

whose tail is (1 + q) times that of the double layer's series (the same order n).
Measured (tests/bem/test_bem_lowest_order_lame.py): (Q1) against (Q2) within 5.8e-15, 1.1e-14,
2.4e-14 of L_i L_j at q = 0.225, 0.125, 0.05; (Q1) against a 200-point Gauss rule for
adjacent pairs at 30 ... 150 degrees.

Lame operators' kernels and the matrices (L1), (L2): :mod:`.lowest_order_lame`.
"""

from __future__ import annotations

import math
from math import comb

import numpy as np
from numba import njit

INV_2PI = 1.0 / (2.0 * math.pi)

Q_NEAR = 0.25        # pairs with (L_i + L_j) / (2 |w_m|) >= Q_NEAR: closed form (V1), (K1)
# ... except nearly parallel pairs (|sin| of their angle < SIN_SMOOTH) with q < Q_SMOOTH:
# neighbours on a smooth curve, where K is small by cancellation (module doc)
Q_SMOOTH = 0.55
SIN_SMOOTH = 0.25
SERIES_TOL = 1e-17   # bound of the truncated tail of the far-pair series (relative)
N_SERIES = 72        # largest series order (q < Q_SMOOTH needs n <= 61)


def _series_tables(n: int):
    """cV, c0, c1 (c1 for m even, j odd) and c1r[m, j] = c1[j, m] of the module doc,
    zero where a parity does not apply; index [m, j] up to total degree n."""
    cV = np.zeros((n + 1, n + 1))
    c0 = np.zeros((n + 1, n + 1))
    c1 = np.zeros((n + 1, n + 1))
    for m in range(0, n + 1, 2):
        for j in range(n + 1 - m):
            c = comb(m + j, m)
            if j % 2 == 0:
                c0[m, j] = c / ((m + 1) * (j + 1))
                if m + j >= 2:
                    cV[m, j] = -c / ((m + j) * (m + 1) * (j + 1))
            else:
                c1[m, j] = -c / ((m + 1) * (j + 2))
    c1r = np.ascontiguousarray(c1.T)
    for t in (cV, c0, c1, c1r):
        t.setflags(write=False)
    return cV, c0, c1, c1r


CV, C0, C1, C1R = _series_tables(N_SERIES)


@njit(cache=True, inline="always")
def _on_line(p0, p1, a, n0, n1):
    """Whether the points p0, p1 lie on the line through a with unit normal (n0, n1), to
    1e-15 of their distances from a (the collinearity test of the general assembly;
    |d| > 1e-15 (|x| + |y|) rejects without a square root)."""
    x0 = p0[0] - a[0]
    y0 = p0[1] - a[1]
    d0 = abs(x0 * n0 + y0 * n1)
    if d0 > 1e-15 * (abs(x0) + abs(y0)) or d0 > 1e-15 * math.hypot(x0, y0):
        return False
    x1 = p1[0] - a[0]
    y1 = p1[1] - a[1]
    return abs(x1 * n0 + y1 * n1) <= 1e-15 * math.hypot(x1, y1)


@njit(cache=True, inline="always")
def _k_entries(p0, p1, a, d, J0, J1):
    """The K entries (hat at the start a, hat at the end) of the test element [p0, p1]
    against the trial element starting at a with unit direction d (normal n = -i d),
    from J0, J1 of (K1); zero if the test element lies on the trial element's line."""
    n0, n1 = d.imag, -d.real
    if _on_line(p0, p1, a, n0, n1):
        return 0.0, 0.0
    n = complex(n0, n1)
    return INV_2PI * (n * (0.5 * J0 - J1)).real, INV_2PI * (n * (0.5 * J0 + J1)).real


@njit(cache=True, inline="always")
def _smooth_pair(u, v, wm, r):
    """Nearly parallel (|sin| < SIN_SMOOTH) but not on one line (the midpoint of E_i off
    the line of E_j by more than 1e-10 |w_m|): neighbours on a smooth curve, whose K
    entries are small by cancellation and better by the series (q < Q_SMOOTH)."""
    return (abs((u * v.conjugate()).imag) < SIN_SMOOTH
            and abs((wm * v.conjugate()).imag) > 1e-10 * r)


@njit(cache=True, inline="always")
def _log_ratio(w, wm, r2m):
    """log(w / wm), principal branch, from w * conj(wm) (r2m = |wm|^2)."""
    z = w * wm.conjugate()
    return complex(0.5 * math.log((w.real * w.real + w.imag * w.imag) / r2m),
                   math.atan2(z.imag, z.real))


@njit(cache=True, inline="always")
def _log_quotient(wp, wn, d):
    """log(wp / wn), principal branch, to full relative accuracy also for wp close to wn
    (by log1p of z = d / wn when |z| < 1/2; directly otherwise, where log1p's argument
    2 Re z + |z|^2 would cancel, e.g. for wp close to 0).  ``d`` = wp - wn formed from
    the element's own end points (b_i - a_i, exact for nearby nodes): the difference of
    the rounded wp, wn would carry an error of eps |wp| into a d of the size of a short
    element (measured: V entries of a 1e-9 element against collinear neighbours 4e-8
    off relative, against 2e-16 with d)."""
    r2n = wn.real * wn.real + wn.imag * wn.imag
    z = d * wn.conjugate() / r2n
    z2 = z.real * z.real + z.imag * z.imag
    if z2 < 0.25:
        return complex(0.5 * math.log1p(2.0 * z.real + z2), math.atan2(z.imag, 1.0 + z.real))
    q = wp * wn.conjugate()
    return complex(0.5 * math.log((wp.real * wp.real + wp.imag * wp.imag) / r2n),
                   math.atan2(q.imag, q.real))


@njit(cache=True)
def _pair_sums(ai, bi, aj, bj, A, v, Lj, wm):
    """The corner sums of (V1), (K1), (Q1): sum_c s_c P(w_c) log(w_c / w_m) for P = w^2,
    w, w (w/2 + t v), w (w/2 - s u), |w|^2, each as a sum over the two ends y of E_j of the
    difference of the corners x = b_i, a_i (w = z +- A, z = m_i - y, A = (b_i - a_i)/2):

        P+ l+ - P- l- = (P+ - P-)/2 (l+ + l-) + (P+ + P-)/2 log(w+ / w-),

    with the differences of P in closed form and log(w+ / w-) by log1p when w+ is
    close to w- (:func:`_log_quotient`): no cancellation when E_i is much shorter
    than E_j (graded meshes; the plain corner sum loses L_j / L_i).  A corner at a shared
    vertex (w = 0) contributes 0."""
    r2m = wm.real * wm.real + wm.imag * wm.imag
    sv = 0j
    s0 = 0j
    s1 = 0j
    s1r = 0j
    sq = 0j
    for e in range(2):
        y = bj if e == 0 else aj
        st = 1.0 if e == 0 else -1.0
        tv = (0.5 * Lj * st) * v               # t v at this end
        wp = bi - y
        wn = ai - y
        z = 0.5 * (wp + wn)
        if wp != 0j and wn != 0j:
            lsum = _log_ratio(wp, wm, r2m) + _log_ratio(wn, wm, r2m)
            ldif = _log_quotient(wp, wn, 2.0 * A)
            sv += st * (2.0 * z * A * lsum + (z * z + A * A) * ldif)
            s0 += st * (A * lsum + z * ldif)
            s1 += st * (A * (z + tv) * lsum + (0.5 * (z * z + A * A) + z * tv) * ldif)
            s1r += st * (0.5 * (z * z - A * A) * ldif)
            # |w+|^2 - |w-|^2 = 4 Re(z conj(A)), |w+|^2 + |w-|^2 = 2 (|z|^2 + |A|^2)
            zA = z * A.conjugate()
            sq += st * (2.0 * zA.real * lsum
                        + (z.real * z.real + z.imag * z.imag + A.real * A.real
                           + A.imag * A.imag) * ldif)
        elif wp != 0j:
            lg = _log_ratio(wp, wm, r2m) * st
            sv += wp * wp * lg
            s0 += wp * lg
            s1 += wp * (0.5 * wp + tv) * lg
            s1r += wp * (0.5 * wp - A) * lg
            sq += (wp.real * wp.real + wp.imag * wp.imag) * lg
        elif wn != 0j:
            lg = _log_ratio(wn, wm, r2m) * (-st)
            sv += wn * wn * lg
            s0 += wn * lg
            s1 += wn * (0.5 * wn + tv) * lg
            s1r += wn * (0.5 * wn + A) * lg
            sq += (wn.real * wn.real + wn.imag * wn.imag) * lg
    return sv, s0, s1, s1r, sq


@njit(cache=True)
def _pair_near(ai, bi, aj, bj, Li, Lj, u, v, wm, logR):
    """(I - L_i L_j log R, J0, J1 / L_j, J0', J1' / L_i, Q) of formulas (V1), (K1), (Q1)
    for a pair of distinct elements; J0', J1' those of the swapped pair (test j, trial
    i), Q = Q_ij = Q_ji.  The corner sums are paired along the shorter element
    (:func:`_pair_sums`; its sums of w^2 and |w|^2 are those of the swapped pair)."""
    if Li <= Lj:
        sv, s0, s1, s1r, sq = _pair_sums(ai, bi, aj, bj, 0.5 * (bi - ai), v, Lj, wm)
    else:
        # the swapped pair: corners -w_c, the same logarithms; its sums of w, w (w/2 +
        # s u), w (w/2 - t v) are -s0, s1r and s1 of this pair
        sv, s0, s1r, s1, sq = _pair_sums(aj, bj, ai, bi, 0.5 * (bj - aj), u, Li, -wm)
        s0 = -s0
    r2m = wm.real * wm.real + wm.imag * wm.imag
    uv = u * v
    LL = Li * Lj
    I = LL * (0.5 * math.log(r2m) - logR - 1.5) - (sv / (2.0 * uv)).real
    J0 = -s0 / uv
    J1 = -(s1 + 0.5 * uv * LL) / (uv * v)
    J1r = -(s1r + 0.5 * uv * LL) / (uv * u)
    # (Q1): conj Q = -(u v)^(-1) sum s_c |w_c|^2 l_c + c (u v)^(-2) sum s_c w_c^2 l_c
    #                + c L_i L_j / (u v),  c = Re(u conj(v))
    c = (u * v.conjugate()).real
    iuv = uv.conjugate()              # 1 / (u v), |u v| = 1
    Q = (iuv * (c * (iuv * sv + LL) - sq)).conjugate()
    return I, J0, J1 / Lj, -J0, J1r / Li, Q


def _order_thresholds(n_max: int, tol: float) -> np.ndarray:
    """qmax[n]: the largest q with 2 q^(n+1) / ((n+3)(1-q)) <= tol (the tail bound of
    the module doc), by bisection; increasing in n."""
    qmax = np.zeros(n_max + 1)
    for n in range(1, n_max + 1):
        lo, hi = 0.0, 0.999
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if 2.0 * mid ** (n + 1) / ((n + 3) * (1.0 - mid)) <= tol:
                lo = mid
            else:
                hi = mid
        qmax[n] = lo
    qmax.setflags(write=False)
    return qmax


QMAX = _order_thresholds(N_SERIES, SERIES_TOL)
if not QMAX[N_SERIES] > max(Q_NEAR, Q_SMOOTH):
    raise ValueError(f"N_SERIES = {N_SERIES} is too small for Q_NEAR, Q_SMOOTH")


@njit(cache=True)
def _pair_far(Li, Lj, u, v, wm, logR, ap, bp):
    """The same six values as :func:`_pair_near` by the truncated series (module doc);
    ``ap``, ``bp``: scratch for the powers of a and b."""
    r2m = wm.real * wm.real + wm.imag * wm.imag
    iw = wm.conjugate() / r2m                    # 1 / w_m
    a = (0.5 * Li) * u * iw
    b = (-0.5 * Lj) * v * iw
    q = 0.5 * (Li + Lj) / math.sqrt(r2m)          # |a| + |b|
    n = 1
    while q > QMAX[n] and n < N_SERIES:
        n += 1
    ap[0] = 1.0
    bp[0] = 1.0
    for k in range(1, n + 1):
        ap[k] = ap[k - 1] * a
        bp[k] = bp[k - 1] * b
    sv = 0j
    s0 = 0j
    s1 = 0j
    s1r = 0j
    for m in range(n + 1):
        if m % 2 == 0:
            tv = 0j
            t0 = 0j
            t1 = 0j
            for j in range(0, n + 1 - m, 2):
                tv += CV[m, j] * bp[j]
                t0 += C0[m, j] * bp[j]
            for j in range(1, n + 1 - m, 2):
                t1 += C1[m, j] * bp[j]
            sv += ap[m] * tv
            s0 += ap[m] * t0
            s1 += ap[m] * t1
        else:
            t1 = 0j
            for j in range(0, n + 1 - m, 2):
                t1 += C1R[m, j] * bp[j]
            s1r += ap[m] * t1
    LL = Li * Lj
    I = LL * (0.5 * math.log(r2m) - logR + sv.real)
    J0 = (LL * iw) * s0
    h = (0.5 * LL) * iw
    # (Q2): Q = L_i L_j (w_m / conj w_m) [conj(s0) + a conj(s1r) + b conj(s1)]
    Q = (LL * wm * iw.conjugate()) * (s0.conjugate() + a * s1r.conjugate()
                                      + b * s1.conjugate())
    return I, J0, h * s1, -J0, -(h * s1r), Q
