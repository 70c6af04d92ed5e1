"""Closed-form Galerkin entries of the lowest-order Laplace operators (p = 1).

At p = 1 the single layer V lives on W_hp = P0 (one constant per element) and the double
layer K has test P0 and trial P1 (the GLL hats of V_hp, dofs at the element ends); the
hypersingular W = T^T V T follows from V.  For straight elements these entries have
closed forms, derived here in complex notation (points of R^2 as complex numbers).

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

Lame matrices (:func:`lame_p1`, interleaved components, 2 x 2 block per pair, I' = I - L_i
L_j log R = -2 pi V_Laplace):

    V_ij  = c1 [-I' I + c2 R_ij],  Vt_ij = Et [-I' I + R_ij],
    R_ij  = L_i L_j / 2 I + 1/2 [[Re Q, Im Q], [Im Q, -Re Q]],                         (L1)

and the double layer by its Guenter-derivative representation (Kupradze; Steinbach,
"Numerical Approximation Methods for Elliptic Boundary Value Problems", Springer 2008,
chapter on linear elastostatics, in 3D with the Guenter derivative M; in 2D M u = J du/ds
with J = [[0, 1], [-1, 0]] for our orientation):

    K = K_Laplace I + (V_Laplace I - 2 mu V) (I J) T                                   (L2)
      = K_Laplace I - alpha (V_Laplace J) T - beta Q_b (I J) T,
    alpha = mu / (lambda + 2 mu),  beta = (lambda + mu) / (4 pi (lambda + 2 mu)),
    Q_b = [[Re Q, Im Q], [Im Q, -Re Q]] per pair

(T the P1 derivative matrix per component; the L_i L_j and log R parts of V drop out
against T, whose columns integrate to zero on closed curves: m^T T = 0).  How (L2) was
established: a least-squares fit of K_quadrature - K_Laplace I over the candidates
(V_Laplace J) T, R (I J) T and (I J) R T on an L-shape for three materials gave the
coefficients -alpha, -beta, +beta (residual 8e-16 of max |K|), and R (I J) - (I J) R =
Q_b (I J); the second line follows from the first with V = 2 pi c1 V_Laplace + c1 c2 R
(1 - 4 pi mu c1 = -alpha, 2 mu c1 c2 = 2 beta).  The test checks (L2) on the quadrature
matrices alone at p = 2 (to 1e-13), where no closed form is involved.  :func:`lame_p1` runs the pass of :func:`laplace_p1_vk` with Q and then
one row pass (:func:`_lame_rows`) that writes V, Vt and K; :func:`lame_p1_w` forms W = T^T
Vt T per component pair by :func:`laplace_p1_w` (the blocks Vt[k::2, l::2] are symmetric).
Nothing of the general quadrature path is compiled for p = 1.

:func:`laplace_p1_vk` assembles V and K of a mesh with all degrees 1 in one pass over the
unordered element pairs, on several threads for large meshes with the same bits
(:class:`~hpfebe.bem.laplace.LaplaceBEM` uses it there; the general quadrature path of
:mod:`hpfebe.bem.assembly` remains the reference), and
:func:`laplace_p1_w` the hypersingular operator W = T^T V T from V without forming T
(T at p = 1: -+1/L_e at the two ends of element e).
"""

from __future__ import annotations

import math
from math import comb

import numpy as np
from numba import njit

from .kernels import KP_C1, KP_C1_C2, KP_ET, KP_LAMBDA, KP_LAME_SIZE, KP_MU
from .threads import all_finite, interleaved, n_threads, run_chunks, zeros_aligned

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


@njit(cache=True, nogil=True)
def _element_data(nodes, elements):
    """Start and end points (complex), lengths and unit directions of the elements."""
    ne = elements.shape[0]
    zs = np.empty(ne, np.complex128)
    ze = np.empty(ne, np.complex128)
    L = np.empty(ne)
    dirs = np.empty(ne, np.complex128)
    for e in range(ne):
        zs[e] = complex(nodes[elements[e, 0], 0], nodes[elements[e, 0], 1])
        ze[e] = complex(nodes[elements[e, 1], 0], nodes[elements[e, 1], 1])
        d = ze[e] - zs[e]
        L[e] = math.hypot(d.real, d.imag)
        dirs[e] = d / L[e]
    return zs, ze, L, dirs


@njit(cache=True, nogil=True)
def _vk_rows(zs, ze, L, dirs, nodes, elements, vdofs, wdofs, logR, V, K, Qm, R, direct,
             rows):
    """V (symmetric) and K (W_hp x V_hp) of a mesh with all degrees 1 for the test
    elements i in ``rows``, over the pairs j > i: each gives V_ij = V_ji and the K entries
    of (i, j) (row i) and of (j, i) (row j).  ``direct``: the latter are added to K;
    otherwise stored in R[w_j, 2 i + r] (r = 0, 1 the ends of E_i) for :func:`_gather`, so
    that several threads (disjoint ``rows``) never add to one entry.  If ``Qm`` is not
    empty (W_hp x W_hp, complex), also Q_ij = Q_ji of (Q1), (Q2) (u^2 L_i L_j exactly for
    collinear pairs, the identical pair included)."""
    want_q = Qm.shape[0] > 0
    ne = elements.shape[0]
    ap = np.empty(N_SERIES + 1, np.complex128)
    bp = np.empty(N_SERIES + 1, np.complex128)
    for i in rows:
        ai, bi, Li, u = zs[i], ze[i], L[i], dirs[i]
        wi = wdofs[i]
        # identical pair: I = L^2 (log L - 3/2); K = 0 (collinear)
        V[wi, wi] = -INV_2PI * Li * Li * (math.log(Li) - logR - 1.5)
        if want_q:
            Qm[wi, wi] = (u * u) * (Li * Li)
        for j in range(i + 1, ne):
            aj, bj, Lj, v = zs[j], ze[j], L[j], dirs[j]
            # differences of nearby nodes first (exact, Sterbenz): w_m to relative eps
            wm = 0.5 * ((ai - aj) + (bi - bj))
            h = 0.5 * (Li + Lj)
            r = abs(wm)
            if h >= Q_NEAR * r and (h >= Q_SMOOTH * r or not _smooth_pair(u, v, wm, r)):
                I, J0, J1, J0r, J1r, Q = _pair_near(ai, bi, aj, bj, Li, Lj, u, v, wm, logR)
            else:
                I, J0, J1, J0r, J1r, Q = _pair_far(Li, Lj, u, v, wm, logR, ap, bp)
            wj = wdofs[j]
            V[wi, wj] = -INV_2PI * I
            V[wj, wi] = V[wi, wj]
            if want_q:
                if _on_line(nodes[elements[i, 0]], nodes[elements[i, 1]],
                            nodes[elements[j, 0]], v.imag, -v.real):
                    Q = (u * u) * (Li * Lj)
                Qm[wi, wj] = Q
                Qm[wj, wi] = Q
            # K of (test i, trial j) and of (test j, trial i)
            ka, kb = _k_entries(nodes[elements[i, 0]], nodes[elements[i, 1]],
                                nodes[elements[j, 0]], v, J0, J1)
            if vdofs[j, 0] >= 0:
                K[wi, vdofs[j, 0]] += ka
            if vdofs[j, 1] >= 0:
                K[wi, vdofs[j, 1]] += kb
            ka, kb = _k_entries(nodes[elements[j, 0]], nodes[elements[j, 1]],
                                nodes[elements[i, 0]], u, J0r, J1r)
            if direct:
                if vdofs[i, 0] >= 0:
                    K[wj, vdofs[i, 0]] += ka
                if vdofs[i, 1] >= 0:
                    K[wj, vdofs[i, 1]] += kb
            else:
                R[wj, 2 * i] = ka
                R[wj, 2 * i + 1] = kb


@njit(cache=True, nogil=True)
def _gather(R, vdofs, wdofs, K, rows):
    """K[w_j, dofs of E_i] += R[w_j, 2 i + r] for i < j, j in ``rows`` (the second pass of
    the threaded assembly).  Every K entry of a closed curve has at most two terms (a
    node lies on two elements), so the sum does not depend on their order: the result is
    bitwise that of the direct single-thread pass."""
    for j in rows:
        wj = wdofs[j]
        for i in range(j):
            if vdofs[i, 0] >= 0:
                K[wj, vdofs[i, 0]] += R[wj, 2 * i]
            if vdofs[i, 1] >= 0:
                K[wj, vdofs[i, 1]] += R[wj, 2 * i + 1]


MIN_PAIRS_PER_THREAD = 32768  # below this many element pairs per thread: one thread


def _n_threads(work: float) -> int:
    return n_threads(work, MIN_PAIRS_PER_THREAD)


def _threaded(fn, args, n: int, nt: int) -> None:
    """fn(*args, rows) over chunks of the rows 0..n-1 (interleaved: short and long rows of
    the triangle alternate, 4 chunks per thread) on ``nt`` threads (:mod:`.threads`;
    ``fn`` releases the GIL)."""
    run_chunks(lambda c: fn(*args, c), np.array_split(interleaved(n), 4 * nt), nt)


def applies(mesh) -> bool:
    """Whether the closed forms apply: every element of degree 1."""
    return bool(np.all(mesh.degrees == 1))


def _check_p1(W_space, V_space, scale: float, who: str) -> float:
    mesh = W_space.mesh
    if V_space.mesh is not mesh:
        raise ValueError("W_space and V_space must live on the same mesh")
    if not applies(mesh):
        raise ValueError(f"{who} needs all element degrees 1, got degrees "
                         f"{sorted(set(mesh.degrees.tolist()))}")
    scale = float(scale)
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be positive, got {scale!r}")
    return scale


def _p1_pass(W_space, V_space, scale: float, with_q: bool):
    """(V, K, Q) of the Laplace closed forms in one pass (Q: None unless ``with_q``)."""
    mesh = W_space.mesh
    ne = mesh.n_elements
    V = zeros_aligned((W_space.ndof, W_space.ndof))
    K = zeros_aligned((W_space.ndof, V_space.ndof))
    Q = zeros_aligned((W_space.ndof, W_space.ndof) if with_q else (0, 0), np.complex128)
    vdofs = np.ascontiguousarray(V_space.elem_dofs[:, :2])
    wdofs = np.ascontiguousarray(W_space.elem_dofs[:, 0])
    geo = _element_data(mesh.nodes, mesh.elements)
    args = (*geo, mesh.nodes, mesh.elements, vdofs, wdofs, math.log(scale), V, K, Q)
    nt = _n_threads(0.5 * ne * ne)
    if nt > 1:
        # rows of test elements on nt threads; the K entries of the pairs (j, i), j > i,
        # go through R (rows of several threads would add to one entry), then a second
        # threaded pass over the rows j adds them
        R = np.empty((W_space.ndof, 2 * ne))
        _threaded(_vk_rows, args + (R, False), ne, nt)
        _threaded(_gather, (R, vdofs, wdofs, K), ne, nt)
    else:
        _vk_rows(*args, np.empty((0, 0)), True, np.arange(ne))
    if not (all_finite(V) and all_finite(K) and all_finite(Q)):
        raise FloatingPointError("closed-form assembly produced non-finite entries "
                                 "(intersecting or degenerate elements?)")
    return V, K, (Q if with_q else None)


def laplace_p1_vk(W_space, V_space, scale: float):
    """(V, K) of the Laplace operators (module doc of :mod:`hpfebe.bem.laplace`) on a mesh
    with all degrees 1: V on W_space (P0) x W_space, K on W_space x V_space (P1), kernel
    scale R = ``scale``, by the closed forms (V1), (K1) and the far-pair series.  Serial,
    or on numba.get_num_threads() threads for large meshes (the same bits)."""
    scale = _check_p1(W_space, V_space, scale, "laplace_p1_vk")
    V, K, _ = _p1_pass(W_space, V_space, scale, False)
    return V, K


@njit(cache=True)
def _w_from_v(V, vdofs, L, W):
    """W = T^T V T at p = 1, T[e, dof] = -+1/L_e for the hats at the ends a_e, b_e of
    element e (the arc-length derivatives): the contributions of all element pairs, then
    the upper triangle mirrored (W exactly symmetric, as :func:`assembly.sandwich`)."""
    ne = V.shape[0]
    for e in range(ne):
        ae, be = vdofs[e, 0], vdofs[e, 1]
        for f in range(ne):
            af, bf = vdofs[f, 0], vdofs[f, 1]
            val = V[e, f] / (L[e] * L[f])
            if ae >= 0:
                if af >= 0:
                    W[ae, af] += val
                if bf >= 0:
                    W[ae, bf] -= val
            if be >= 0:
                if af >= 0:
                    W[be, af] -= val
                if bf >= 0:
                    W[be, bf] += val
    n = W.shape[0]
    for k in range(n):
        for l in range(k):
            W[k, l] = W[l, k]


def laplace_p1_w(V: np.ndarray, W_space, V_space) -> np.ndarray:
    """The hypersingular operator W = T^T V T (V_hp x V_hp) of a mesh with all degrees
    1 from its single layer V (W_space x W_space), without forming T (the same matrix as
    ``sandwich(V_space.derivative_matrix(W_space), V)`` to round-off)."""
    mesh = W_space.mesh
    if not applies(mesh):
        raise ValueError("laplace_p1_w needs all element degrees 1, got degrees "
                         f"{sorted(set(mesh.degrees.tolist()))}")
    V = np.ascontiguousarray(V, dtype=float)
    if V.shape != (W_space.ndof, W_space.ndof):
        raise ValueError(f"V must have shape {(W_space.ndof, W_space.ndof)}, got {V.shape}")
    W = zeros_aligned((V_space.ndof, V_space.ndof))
    _w_from_v(V, np.ascontiguousarray(V_space.elem_dofs[:, :2]), mesh.lengths, W)
    return W


@njit(cache=True, nogil=True)
def _lame_rows(Vl, Q, Kl, Ld, va, vb, cst, V, Vt, K, rows):
    """Rows 2 e, 2 e + 1 (e in ``rows``, W_hp dofs) of the Lame V, Vt (L1) and K (L2)
    from the Laplace V_Laplace = ``Vl``, K_Laplace = ``Kl`` and Q, with ``Ld`` the element
    lengths, ``va``, ``vb`` the V_hp dofs of the start and end of each W_hp dof's element
    (T[f, va[f]] = -1/L_f, T[f, vb[f]] = 1/L_f) and ``cst`` = (2 pi c1, c1 c2, 2 pi Et,
    Et, alpha, beta).  K must be zero on entry (rows of several threads are disjoint)."""
    fv, gv, ft, gt, alpha, beta = cst[0], cst[1], cst[2], cst[3], cst[4], cst[5]
    hv = 0.5 * gv
    ht = 0.5 * gt
    n = Vl.shape[0]
    nv = Kl.shape[1]
    for e in rows:
        r0 = 2 * e
        r1 = r0 + 1
        for f in range(n):
            vl = Vl[e, f]
            qr = Q[e, f].real
            qi = Q[e, f].imag
            ll = 0.5 * (Ld[e] * Ld[f])
            c0 = 2 * f
            d = fv * vl + gv * ll
            V[r0, c0] = d + hv * qr
            V[r1, c0 + 1] = d - hv * qr
            V[r0, c0 + 1] = hv * qi
            V[r1, c0] = hv * qi
            d = ft * vl + gt * ll
            Vt[r0, c0] = d + ht * qr
            Vt[r1, c0 + 1] = d - ht * qr
            Vt[r0, c0 + 1] = ht * qi
            Vt[r1, c0] = ht * qi
            # C_ef / L_f, C = -alpha V_Laplace J - beta Q_b J (module doc, (L2))
            il = 1.0 / Ld[f]
            k00 = (beta * qi) * il
            k01 = (-alpha * vl - beta * qr) * il
            k10 = (alpha * vl - beta * qr) * il
            a = va[f]
            if a >= 0:
                K[r0, 2 * a] -= k00
                K[r0, 2 * a + 1] -= k01
                K[r1, 2 * a] -= k10
                K[r1, 2 * a + 1] += k00
            b = vb[f]
            if b >= 0:
                K[r0, 2 * b] += k00
                K[r0, 2 * b + 1] += k01
                K[r1, 2 * b] += k10
                K[r1, 2 * b + 1] -= k00
        for k in range(nv):
            K[r0, 2 * k] += Kl[e, k]
            K[r1, 2 * k + 1] += Kl[e, k]


def lame_p1(W_space, V_space, kp, scale: float):
    """(V, K, Vt) of the Lame operators (module doc of :mod:`hpfebe.bem.lame`:
    G = c1 {-log(r/R) I + c2 r r^T/r^2}, Vt = Et {-log(r/R) I + r r^T/r^2}) on a mesh with
    all degrees 1, interleaved components, from one pass of the Laplace closed forms
    with Q (module doc, "Lame"): V and Vt by (L1), K by the Guenter representation (L2)
    from the Laplace K, V and Q and the P1 derivative matrix T.  ``kp``: the kernel
    parameters of :func:`hpfebe.bem.lame.kernel_params` (lambda, mu, c1, c2, Et; lambda*
    in plane stress) for the scale R = ``scale``."""
    scale = _check_p1(W_space, V_space, scale, "lame_p1")
    kp = np.asarray(kp, dtype=float)
    if kp.shape != (KP_LAME_SIZE,) or not np.all(np.isfinite(kp)):
        raise ValueError(f"kp must be the {KP_LAME_SIZE} finite Lame kernel parameters "
                         f"(lame.kernel_params), got {kp!r}")
    lam, mu = kp[KP_LAMBDA], kp[KP_MU]
    if not (mu > 0 and lam + mu > 0):
        raise ValueError(f"kp: the Lame constants need mu > 0 and lambda + mu > 0, got "
                         f"lambda = {lam!r}, mu = {mu!r}")
    mesh = W_space.mesh
    Vl, Kl, Q = _p1_pass(W_space, V_space, scale, True)
    n, nv = W_space.ndof, V_space.ndof
    wd = W_space.elem_dofs[:, 0]
    Ld = np.empty(n)
    Ld[wd] = mesh.lengths
    va = np.full(n, -1, np.int64)
    vb = np.full(n, -1, np.int64)
    va[wd] = V_space.elem_dofs[:, 0]
    vb[wd] = V_space.elem_dofs[:, 1]
    lp2 = lam + 2.0 * mu
    cst = np.array([2.0 * math.pi * kp[KP_C1], kp[KP_C1_C2], 2.0 * math.pi * kp[KP_ET],
                    kp[KP_ET], mu / lp2, (lam + mu) / (4.0 * math.pi * lp2)])
    V = zeros_aligned((2 * n, 2 * n))
    Vt = zeros_aligned((2 * n, 2 * n))
    K = zeros_aligned((2 * n, 2 * nv))
    args = (Vl, Q, Kl, Ld, va, vb, cst, V, Vt, K)
    nt = _n_threads(n * n)
    if nt > 1:
        _threaded(_lame_rows, args, n, nt)
    else:
        _lame_rows(*args, np.arange(n))
    return V, K, Vt


def lame_p1_w(Vt: np.ndarray, W_space, V_space) -> np.ndarray:
    """The Lame hypersingular operator W = T^T Vt T (interleaved, V_hp^2 x V_hp^2) of a
    mesh with all degrees 1 from Vt (W_hp^2 x W_hp^2, 2 x 2 blocks symmetric and
    Vt_ef = Vt_fe): per component pair the scalar :func:`laplace_p1_w` of the symmetric
    block Vt[k::2, l::2] (Vt_01 = Vt_10)."""
    n, nv = W_space.ndof, V_space.ndof
    Vt = np.asarray(Vt, dtype=float)
    if Vt.shape != (2 * n, 2 * n):
        raise ValueError(f"Vt must have shape {(2 * n, 2 * n)}, got {Vt.shape}")
    W = zeros_aligned((2 * nv, 2 * nv))
    for k, l in ((0, 0), (1, 1), (0, 1)):
        W[k::2, l::2] = laplace_p1_w(Vt[k::2, l::2], W_space, V_space)
    W[1::2, 0::2] = W[0::2, 1::2]
    return W
