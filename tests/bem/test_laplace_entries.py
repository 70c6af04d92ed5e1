"""Entry-by-entry check of the local Laplace Galerkin blocks V, K, W of
:func:`hpfebe.bem.laplace.local_blocks` against an independent high-precision reference.

Cases (every one a closed, counter-clockwise polygon that contains the pair):

* coincident straight elements (i == j), lengths 1 and 1/50;
* adjacent elements sharing one vertex, interior angle 10, 90, 180 and 350 degrees at the
  shared vertex, lengths (1, 1) and (1/50, 1) - both orders (i, j) and (j, i), so that the
  test element is once the short and once the long one;
* near-but-disjoint pairs of unit elements at distance 1e-3: collinear with a gap,
  perpendicular with a gap (an L corner with a tiny cut) and parallel (a thin rectangle);

for p = 1..8 on both elements and a few mixed degrees (p_i != p_j).  Element lengths are
1 and 1/50 and the kernel scale is R = 4, so that log(|x - y| / R) is O(1).  Every entry
must satisfy  |a - b| <= 1e-12 |b| + 1e-14 max|block|  (a computed, b reference).  The
only blocks without a meaningful "largest entry" are the K blocks of collinear pairs,
which vanish identically ((x - y) . n_y = 0); for those the floor is 1e-14 min(|I|, |J|),
K having the dimension of a length.

Reference (independent of hpfebe's quadrature; numpy and mpmath only)
------------------------------------------------------------------------
Parametrise x = a_I + s (b_I - a_I), y = a_J + sigma (b_J - a_J), s, sigma in [0, 1].
In the frame of J, x - a_J = L_J (u e_J + v n_J) with z = u + i v an affine function of
s whose coefficients are exact rationals of the (binary) node coordinates, and
|x - y| = L_J |sigma - z|,  (x - y) . n_J = L_J v.  The inner integrals over sigma have
closed forms,

    C_n(z) = int_0^1 sigma^n / (sigma - z) dsigma,  C_0 = log(1 - z) - log(-z),
             C_n = 1/n + z C_{n-1}  (evaluated with extra bits for |z| > 1),
    A_n(z) = int_0^1 sigma^n log|sigma - z| dsigma = Re(log(1 - z) - C_{n+1}(z)) / (n+1),
    B_n(z) = int_0^1 sigma^n v / |sigma - z|^2 dsigma = Im C_n(z),

and only the outer integral over s is numerical: tanh-sinh (double-exponential) rules,
refined level by level until two successive levels agree to ~1e-27, on sub-intervals
split at (and graded geometrically toward) the points of I nearest to the endpoints of
J, the only places where the outer integrand is singular or nearly singular.  This
gives the monomial moments (m <= 7, n <= 8)

    V^mono[m, n] = int_I int_J G s^m sigma^n,   K^mono[m, n] = int_I int_J dG/dn_y s^m sigma^n

at ~45 digits, once per ordered pair; the blocks of every degree follow by exact
changes of basis (shifted Legendre coefficients, Gauss-Lobatto Lagrange coefficients
from GLL points refined by Newton's method in mpmath).  The reference itself is checked
against closed forms (int_0^1 int_0^1 log|s - t| = -3/2, a collinear pair with a gap),
the double-layer identity int_Gamma dG/dn_y ds_y = -1/2 on a closed triangle, and a plain
two-dimensional mpmath quadrature.
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction

import mpmath
import numpy as np
import pytest

from hpfebe.bem.laplace import local_blocks
from hpfebe.geometry import BoundaryMesh

SCALE_R = 4.0            # kernel scale R of G = -1/(2 pi) log(|x - y| / R)
P_MAX = 8                # degrees p = 1..P_MAX
RTOL = 1e-12             # relative tolerance per entry
FLOOR = 1e-14            # absolute floor, relative to the largest entry of the block
DELTA = 1e-3             # distance of the near pairs (elements of length 1)
SHORT = 1.0 / 50.0       # the short element of the length-ratio cases

NA = P_MAX               # log moments A_n, n < NA (V and W need sigma^n, n <= 7)
NB = P_MAX + 1           # Cauchy moments B_n, n < NB (K: Lagrange of degree <= 8)
NM = P_MAX               # test monomials s^m, m < NM

# private multiprecision context: ~48 digits, the outer sums in 170-bit fixed point
MP = mpmath.MPContext()
MP.prec = 160
FIX = 170
TS_TMAX = 4.3            # tanh-sinh truncation: weights < 1e-48 beyond
TS_TOL_BITS = 90         # two successive levels agree to 2^-90 ~ 1e-27 (error ~ its square)
TS_KMAX = 9

# generic rotation and shift of the non-collinear geometries (nothing axis aligned)
PHI = 0.4
SHIFT = np.array([0.3, -0.2])


# ----------------------------------------------------------------------------- geometry
def _place(vertices, rotate=True):
    v = np.asarray(vertices, dtype=float)
    if rotate:
        c, s = math.cos(PHI), math.sin(PHI)
        v = v @ np.array([[c, s], [-s, c]]) + SHIFT
    return v


def _adjacent_vertices(theta_deg, l1, l2):
    """Polygon P0 -> v -> P2 -> ... with element 0 = P0->v (length l1), element 1 =
    v->P2 (length l2) and interior angle theta at the shared vertex v = 0."""
    t = math.radians(theta_deg)
    p2 = (l2, 0.0)
    if theta_deg == 180:
        return [(-l1, 0.0), (0.0, 0.0), p2, ((l2 - l1) / 2, 0.5)]
    p0 = (l1 * math.cos(t), l1 * math.sin(t))
    if theta_deg < 180:
        return [p0, (0.0, 0.0), p2]
    # reflex angle: go around the outside of the thin exterior wedge
    return [p0, (0.0, 0.0), p2, (l2, 1.0), (-1.0, 1.0), (-1.0, -1.0), (p0[0], -1.0)]


def _make_geometries():
    geoms = {}
    # coincident: an axis-aligned unit element and a rotated element of length 1/50
    geoms["coinc-L1"] = dict(nodes=_place([(0, 0), (1, 0), (0.3, 0.8)], rotate=False),
                             pairs=[(0, 0)])
    geoms["coinc-L1/50"] = dict(nodes=_place([(0, 0), (SHORT, 0), (0.01, 0.3)]),
                                pairs=[(0, 0)])
    for theta in (10, 90, 180, 350):
        for tag, (l1, l2) in (("r1", (1.0, 1.0)), ("r50", (SHORT, 1.0))):
            verts = _adjacent_vertices(theta, l1, l2)
            geoms[f"adj{theta:03d}-{tag}"] = dict(
                nodes=_place(verts, rotate=theta != 180), pairs=[(0, 1), (1, 0)],
                theta=theta)
    geoms["near-collinear"] = dict(
        nodes=_place([(0, 0), (1, 0), (1 + DELTA, 0), (2 + DELTA, 0), (2 + DELTA, 0.5),
                      (0, 0.5)], rotate=False), pairs=[(0, 2), (2, 0)])
    geoms["near-perpendicular"] = dict(
        nodes=_place([(0, 0), (1, 0), (1, DELTA), (1, 1 + DELTA), (0, 1 + DELTA)]),
        pairs=[(0, 2), (2, 0)])
    geoms["near-parallel"] = dict(
        nodes=_place([(0, 0), (1, 0), (1, DELTA), (0, DELTA)]), pairs=[(0, 2), (2, 0)])
    for g in geoms.values():
        n = len(g["nodes"])
        g["segments"] = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    return geoms


GEOMS = _make_geometries()
PAIRS = [(name, i, j) for name, g in GEOMS.items() for (i, j) in g["pairs"]]


def _mesh(name, i, j, pi, pj):
    g = GEOMS[name]
    p = [1] * len(g["segments"])
    p[i], p[j] = pi, pj
    return BoundaryMesh.from_segments(g["nodes"], g["segments"], p=p)


# ----------------------------------------------------------------------------- reference
def _fixed(x):
    """mpf -> integer x * 2^FIX (truncated)."""
    if not x:
        return 0
    sign, man, exp, _ = x._mpf_
    e = exp + FIX
    v = man << e if e >= 0 else man >> (-e)
    return -v if sign else v


def _unfix(k, bits):
    return MP.ldexp(MP.mpf(k), -bits)


@functools.lru_cache(maxsize=None)
def _ts_level(k):
    """New tanh-sinh nodes of level k (step 2^-k) as (side, e, w): the node lies at the
    fraction e in (0, 1/2] of the interval from its end ``side`` (-1 left, +1 right,
    0 middle), w the weight of the rule on [-1, 1] without the step h."""
    h = MP.ldexp(1, -k)
    out = []
    j, step = (0, 1) if k == 0 else (1, 2)
    while j * h <= TS_TMAX:
        t = j * h
        q = MP.pi / 2 * MP.sinh(t)
        e = 1 / (1 + MP.exp(2 * q))
        w = MP.pi / 2 * MP.cosh(t) / MP.cosh(q) ** 2
        out += [(0, e, w)] if j == 0 else [(-1, e, w), (1, e, w)]
        j += step
    return out


def _inner(u, v):
    """A_n (n < NA) and B_n (n < NB) at z = u + i v, as fixed-point integers."""
    nc = max(NA + 1, NB)
    az = max(abs(u), abs(v))
    extra = int(MP.log(az, 2) * nc) + 16 if az > 1 else 0
    with MP.extraprec(extra):
        z = MP.mpc(u, v)
        l1 = MP.log(1 - z)
        C = [l1 - MP.log(-z)]
        for n in range(1, nc):
            C.append(MP.mpf(1) / n + z * C[-1])
        A = [_fixed((l1.real - C[n + 1].real) / (n + 1)) for n in range(NA)]
        B = [0] * NB if v == 0 else [_fixed(C[n].imag) for n in range(NB)]
    return A + B


def _breakpoints(aI, dI, aJ, bJ):
    """Split points of [0, 1] (exact Fractions): for each endpoint Y of J the nearest
    point c of I and geometric grading c +- r 4^k, r the distance of Y from c in units
    of |I|, so that every sub-interval is at least as far from the singularity at Y as
    it is long (relative to 4)."""
    LI2 = dI[0] ** 2 + dI[1] ** 2
    pts = {Fraction(0), Fraction(1)}
    for Y in (aJ, bJ):
        w = (Y[0] - aI[0], Y[1] - aI[1])
        sY = (w[0] * dI[0] + w[1] * dI[1]) / LI2
        dY = abs(w[0] * dI[1] - w[1] * dI[0]) / LI2
        c = min(Fraction(1), max(Fraction(0), sY))
        r = math.hypot(float(sY - c), float(dY))
        if r == 0:
            assert c in (0, 1), "J touches the interior of I"
            continue
        pts.add(c)
        for sgn in (-1, 1):
            k = 0
            while True:
                x = float(c) + sgn * r * 4.0 ** k
                if not 0 < x < 1:
                    break
                pts.add(Fraction(x))
                k += 1
    return sorted(pts)


@functools.lru_cache(maxsize=None)
def reference_moments(name, i, j):
    """Raw moments MA[m][n] = int_0^1 s^m A_n(z(s)) ds, MB[m][n] = int_0^1 s^m B_n ds
    (mpf), |I|, |J| and the summed tanh-sinh error estimate, for test element i and
    trial element j of the geometry ``name``."""
    g = GEOMS[name]
    nodes = [(Fraction(float(x)), Fraction(float(y))) for x, y in g["nodes"]]
    aI, bI = nodes[g["segments"][i][0]], nodes[g["segments"][i][1]]
    aJ, bJ = nodes[g["segments"][j][0]], nodes[g["segments"][j][1]]
    dI = (bI[0] - aI[0], bI[1] - aI[1])
    dJ = (bJ[0] - aJ[0], bJ[1] - aJ[1])
    LJ2 = dJ[0] ** 2 + dJ[1] ** 2
    w0 = (aI[0] - aJ[0], aI[1] - aJ[1])
    # z(s) = (c0 + c1 s) + i (d0 + d1 s), exact rationals
    c0 = (w0[0] * dJ[0] + w0[1] * dJ[1]) / LJ2
    c1 = (dI[0] * dJ[0] + dI[1] * dJ[1]) / LJ2
    d0 = (w0[0] * dJ[1] - w0[1] * dJ[0]) / LJ2
    d1 = (dI[0] * dJ[1] - dI[1] * dJ[0]) / LJ2
    mp = lambda q: MP.mpf(q.numerator) / q.denominator  # noqa: E731
    ncomp = NA + NB
    MA = [[MP.zero] * NA for _ in range(NM)]
    MB = [[MP.zero] * NB for _ in range(NM)]
    err = MP.zero
    brk = _breakpoints(aI, dI, aJ, bJ)
    for a, b in zip(brk[:-1], brk[1:]):
        L = b - a
        ua, va, ub, vb = mp(c0 + c1 * a), mp(d0 + d1 * a), mp(c0 + c1 * b), mp(d0 + d1 * b)
        c1L, d1L, Lm, am, bm = mp(c1 * L), mp(d1 * L), mp(L), mp(a), mp(b)
        T = [0] * (NM * ncomp)
        prev = None
        for k in range(TS_KMAX + 1):
            for side, e, w in _ts_level(k):
                if side <= 0:       # from the left end (z measured from z(a): no loss)
                    s, u, v = am + Lm * e, ua + c1L * e, va + d1L * e
                else:
                    s, u, v = bm - Lm * e, ub - c1L * e, vb - d1L * e
                f = _inner(u, v)
                sm = MP.one
                for m in range(NM):
                    wm = _fixed(w * sm)
                    row = m * ncomp
                    for c in range(ncomp):
                        if f[c]:
                            T[row + c] += wm * f[c]
                    sm *= s
            if k >= 3:
                if prev is not None:
                    diff = max(abs(x - 2 * y) for x, y in zip(T, prev))
                    scale = max(abs(x) for x in T)
                    if diff <= scale >> TS_TOL_BITS:
                        break
                prev = list(T)
        else:
            raise RuntimeError(f"tanh-sinh did not converge on [{a}, {b}] ({name}, {i}, {j})")
        fac = Lm / 2
        err += _unfix(diff, 2 * FIX + k) * fac
        for m in range(NM):
            for n in range(NA):
                MA[m][n] += _unfix(T[m * ncomp + n], 2 * FIX + k) * fac
            for n in range(NB):
                MB[m][n] += _unfix(T[m * ncomp + NA + n], 2 * FIX + k) * fac
    LI = MP.sqrt(mp(dI[0] ** 2 + dI[1] ** 2))
    LJ = MP.sqrt(mp(LJ2))
    return MA, MB, LI, LJ, err


@functools.lru_cache(maxsize=None)
def _shifted_legendre():
    """S[m][k]: coefficient of s^m in P_k(2 s - 1), k < P_MAX (exact integers)."""
    return [[MP.mpf((-1) ** (k + m) * math.comb(k, m) * math.comb(k + m, m))
             for k in range(P_MAX)] for m in range(P_MAX)]


@functools.lru_cache(maxsize=None)
def gll_points(p):
    """Gauss-Lobatto points of degree p on [-1, 1]: -1, 1 and the roots of P_p'
    (Newton's method in mpmath from numpy's double-precision roots)."""
    inner = []
    if p >= 2:
        guess = np.polynomial.legendre.Legendre.basis(p).deriv().roots()
        for t0 in np.sort(guess.real):
            t = MP.mpf(float(t0))
            for _ in range(100):
                P = [MP.one, t]
                for n in range(1, p):
                    P.append(((2 * n + 1) * t * P[n] - n * P[n - 1]) / (n + 1))
                d1 = p * (t * P[p] - P[p - 1]) / (t * t - 1)
                d2 = (2 * t * d1 - p * (p + 1) * P[p]) / (1 - t * t)
                dt = d1 / d2
                t -= dt
                if abs(dt) < MP.ldexp(1, -MP.prec + 4):
                    break
            inner.append(t)
    return [-MP.one] + inner + [MP.one]


@functools.lru_cache(maxsize=None)
def _lagrange(p):
    """Lg[m][l]: coefficient of s^m in the GLL Lagrange polynomial L_l(2 s - 1)."""
    sn = [(t + 1) / 2 for t in gll_points(p)]
    Lg = [[MP.zero] * (p + 1) for _ in range(p + 1)]
    for l in range(p + 1):
        c = [MP.one]
        for m in range(p + 1):
            if m == l:
                continue
            den = sn[l] - sn[m]
            c = [((c[q - 1] if q > 0 else 0) - sn[m] * (c[q] if q < len(c) else 0)) / den
                 for q in range(len(c) + 1)]
        for m in range(p + 1):
            Lg[m][l] = c[m]
    return Lg


def _dlagrange(p):
    """Coefficient of s^m (m < p) in d/ds L_l(2 s - 1)."""
    Lg = _lagrange(p)
    return [[(m + 1) * Lg[m + 1][l] for l in range(p + 1)] for m in range(p)]


def _congruence(A, M, B):
    """A^T M B for nested lists (mpf)."""
    MB_ = [[MP.fsum(M[m][n] * B[n][l] for n in range(len(B))) for l in range(len(B[0]))]
           for m in range(len(A))]
    return [[MP.fsum(A[m][k] * MB_[m][l] for m in range(len(A))) for l in range(len(B[0]))]
            for k in range(len(A[0]))]


@functools.lru_cache(maxsize=None)
def reference_blocks(name, i, j, pi, pj):
    """Reference V (p_i x p_j), K (p_i x (p_j+1)), W ((p_i+1) x (p_j+1)) as floats."""
    MA, MB, LI, LJ, _ = reference_moments(name, i, j)
    logLJ = MP.log(LJ / SCALE_R)
    c = -LI * LJ / (2 * MP.pi)
    Vm = [[c * (logLJ / ((m + 1) * (n + 1)) + MA[m][n]) for n in range(NA)]
          for m in range(NM)]
    Km = [[LI / (2 * MP.pi) * MB[m][n] for n in range(NB)] for m in range(NM)]
    S = _shifted_legendre()
    Si = [row[:pi] for row in S[:pi]]
    Sj = [row[:pj] for row in S[:pj]]
    V = _congruence(Si, [row[:pj] for row in Vm[:pi]], Sj)
    K = _congruence(Si, [row[:pj + 1] for row in Km[:pi]], _lagrange(pj))
    W = _congruence(_dlagrange(pi), [row[:pj] for row in Vm[:pi]], _dlagrange(pj))
    W = [[x / (LI * LJ) for x in row] for row in W]
    as_np = lambda X: np.array([[float(x) for x in row] for row in X])  # noqa: E731
    return {"V": as_np(V), "K": as_np(K), "W": as_np(W)}, float(LI), float(LJ)


# ----------------------------------------------------------------------------- comparison
def _compare(label, got, ref, zero_floor):
    got = np.asarray(got, dtype=float)
    assert got.shape == ref.shape, f"{label}: shape {got.shape}, expected {ref.shape}"
    scale = np.abs(ref).max()
    floor = FLOOR * scale if scale > 0 else zero_floor
    err = np.abs(got - ref)
    bound = RTOL * np.abs(ref) + floor
    bad = np.argwhere(~(err <= bound))
    if bad.size == 0:
        return []
    lines = []
    for k, l in bad:
        rel = err[k, l] / abs(ref[k, l]) if ref[k, l] != 0 else np.inf
        lines.append(f"{label}[{k},{l}]: got {got[k, l]:.17e}, reference {ref[k, l]:.17e}, "
                     f"abs err {err[k, l]:.3e}, rel err {rel:.3e}, bound {bound[k, l]:.3e}")
    return lines


def _check_pair(name, i, j, pi, pj):
    mesh = _mesh(name, i, j, pi, pj)
    got = local_blocks(mesh, i, j, scale=SCALE_R)
    ref, LI, LJ = reference_blocks(name, i, j, pi, pj)
    failures = []
    for blk in ("V", "K", "W"):
        failures += _compare(f"{blk}", got[blk], ref[blk], FLOOR * min(LI, LJ))
    assert not failures, (f"{name} (i={i}, j={j}, p_i={pi}, p_j={pj}): "
                          f"{len(failures)} entries off\n" + "\n".join(failures))


# ----------------------------------------------------------------------------- tests
SAME_DEGREE = [pytest.param(name, i, j, p, p, id=f"{name}-{i}{j}-p{p}")
               for name, i, j in PAIRS for p in range(1, P_MAX + 1)]
MIXED_DEGREE = [pytest.param(name, i, j, pi, pj, id=f"{name}-{i}{j}-p{pi}x{pj}")
                for name, i, j in PAIRS if i != j
                for pi, pj in ((1, 8), (8, 1), (3, 6), (7, 2))]


@pytest.mark.parametrize("name, i, j, pi, pj", SAME_DEGREE)
def test_blocks_same_degree(name, i, j, pi, pj):
    _check_pair(name, i, j, pi, pj)


@pytest.mark.parametrize("name, i, j, pi, pj", MIXED_DEGREE)
def test_blocks_mixed_degree(name, i, j, pi, pj):
    _check_pair(name, i, j, pi, pj)


# ----------------------------------------------- near-touching elements (issue 10)
# The slit polygon of issue 10: its sides x = 1 and x = 1 + d (elements 3 and 5, length
# 0.8) face each other at distance d, joined by the element 4 of length d.  Parallel
# facing pairs are integrated by integration.parallel_block, the tiny element against
# its neighbours by the adjacent rule; both at 1e-12 as everywhere else.
SLIT_D = (1e-6, 1e-8)


def _slit_geometry(d):
    nodes = _place([(0, 0), (2, 0), (2, 1), (1 + d, 1), (1 + d, 0.2), (1, 0.2), (1, 1),
                    (0, 1)], rotate=False)
    n = len(nodes)
    return dict(nodes=nodes, pairs=[(3, 5), (5, 3), (3, 4), (4, 5)],
                segments=np.column_stack([np.arange(n), (np.arange(n) + 1) % n]))


for _d in SLIT_D:
    GEOMS[f"slit-{_d:g}"] = _slit_geometry(_d)    # after PAIRS: own, shorter test list

SLIT_CASES = [pytest.param(f"slit-{d:g}", i, j, pi, pj, id=f"slit{d:g}-{i}{j}-p{pi}x{pj}")
              for d in SLIT_D for (i, j) in _slit_geometry(d)["pairs"]
              for pi, pj in ((1, 1), (2, 2), (5, 5), (8, 8), (2, 7))]


@pytest.mark.parametrize("name, i, j, pi, pj", SLIT_CASES)
def test_near_touching_blocks(name, i, j, pi, pj):
    _check_pair(name, i, j, pi, pj)


# ------------------------------------------------------------- checks of the test itself
def test_geometries_are_the_intended_ones():
    """CCW closed polygons; interior angle at the shared vertex; lengths; gaps."""
    for name, g in GEOMS.items():
        v = g["nodes"]
        area2 = np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
        assert area2 > 0, name
        mesh = BoundaryMesh.from_segments(v, g["segments"])
        if "theta" in g:
            a, vtx, b = v[0], v[1], v[2]
            d0, d2 = a - vtx, b - vtx
            ang = math.degrees(math.atan2(d2[0] * d0[1] - d2[1] * d0[0], d2 @ d0)) % 360
            assert abs(ang - g["theta"]) < 1e-9, (name, ang)
            L = sorted(mesh.lengths[:2])
            assert np.allclose(L, [SHORT if name.endswith("r50") else 1.0, 1.0]), name
        if name.startswith("near"):
            i, j = g["pairs"][0]
            assert np.allclose(mesh.lengths[[i, j]], 1.0)
            # distance between the two elements: sample densely (both are straight)
            t = np.linspace(0, 1, 2001)[:, None]
            x = mesh.a[i] + t * (mesh.b[i] - mesh.a[i])
            y = mesh.a[j] + t * (mesh.b[j] - mesh.a[j])
            dist = np.min(np.linalg.norm(x[:, None] - y[None], axis=2))
            assert abs(dist - DELTA) < 1e-9, (name, dist)


def test_reference_gll_points_and_lagrange_basis():
    for p in range(1, P_MAX + 1):
        t = gll_points(p)
        ref = np.sort(np.polynomial.legendre.Legendre.basis(p).deriv().roots().real) \
            if p > 1 else np.array([])
        assert np.allclose([float(x) for x in t[1:-1]], ref, atol=1e-13)
        Lg = _lagrange(p)
        for q, tq in enumerate(t):
            s = (tq + 1) / 2
            for l in range(p + 1):
                val = MP.fsum(Lg[m][l] * s ** m for m in range(p + 1))
                assert abs(val - (1 if q == l else 0)) < MP.mpf(10) ** -35


def test_reference_closed_forms():
    """int_0^1 int_0^1 log|s - t| ds dt = -3/2 (coincident unit element), and the
    collinear pair with a gap: int int log(y - x) = H(b-c) - H(b-d) + H(a-d) - H(a-c),
    H(t) = t^2 log(t) / 2 - 3 t^2 / 4, x in [c, d], y in [a, b]."""
    MA, MB, LI, LJ, err = reference_moments("coinc-L1", 0, 0)
    assert abs(LI - 1) == 0 and abs(MA[0][0] + MP.mpf(3) / 2) < MP.mpf(10) ** -35
    assert all(x == 0 for row in MB for x in row)       # (x - y) . n_y = 0
    # int_0^1 int_0^1 s t log|s - t| = 2 int_0^1 s (s^2 log(s) / 2 - 3 s^2 / 4) = -7/16
    assert abs(MA[1][1] + MP.mpf(7) / 16) < MP.mpf(10) ** -35
    g = GEOMS["near-collinear"]
    x = [Fraction(float(q)) for q in g["nodes"][:, 0]]
    c, d, a, b = x[0], x[1], x[2], x[3]
    def H(q):
        t = MP.mpf(q.numerator) / q.denominator
        return t ** 2 * MP.log(t) / 2 - 3 * t ** 2 / 4

    exact = H(b - c) - H(b - d) + H(a - d) - H(a - c)
    MA, MB, LI, LJ, err = reference_moments("near-collinear", 0, 2)
    val = LI * LJ * (MP.log(LJ) + MA[0][0])
    assert abs(val - exact) < MP.mpf(10) ** -35 * abs(exact), (val, exact)


def test_reference_double_layer_identity():
    """int_Gamma dG/dn_y(x, y) ds_y = -1/2 for x on a side of a closed polygon: the
    moments of all pairs (i, j), j = 0..2, of a triangle sum to -|I|/2 / (m + 1).
    The thin 10-degree triangle with the element of length 1/50 (test element: the long
    side at the 10-degree corner)."""
    name, i = "adj010-r50", 1
    tot = [MP.zero] * NM
    for j in range(3):
        MA, MB, LI, LJ, err = reference_moments(name, i, j)
        for m in range(NM):
            tot[m] += LI / (2 * MP.pi) * MB[m][0]
    for m in range(NM):
        assert abs(tot[m] + LI / 2 / (m + 1)) < MP.mpf(10) ** -30, (m, tot[m])


def test_reference_against_plain_2d_quadrature():
    """Plain iterated tanh-sinh (mpmath.quad of mpmath.quad, split where the integrand
    is nearly singular) at 20 digits of a V moment of a 90-degree corner with the short
    test element and of a K moment of the perpendicular gap."""
    cases = (("adj090-r50", 0, 1, "V", [0, 1], [0, SHORT, 1]),
             ("near-perpendicular", 2, 0, "K", [0, 1e-2, 1], [0, 0.99, 1]))
    for name, i, j, op, s_split, t_split in cases:
        g = GEOMS[name]
        (ax, ay), (bx, by) = g["nodes"][g["segments"][i]]
        (cx, cy), (dx, dy) = g["nodes"][g["segments"][j]]
        with mpmath.workdps(20):
            ax, ay, bx, by, cx, cy, dx, dy = map(mpmath.mpf, (ax, ay, bx, by, cx, cy, dx, dy))
            LI, LJ = mpmath.hypot(bx - ax, by - ay), mpmath.hypot(dx - cx, dy - cy)
            nx, ny = (dy - cy) / LJ, -(dx - cx) / LJ

            def f(s, t):
                rx = ax + s * (bx - ax) - cx - t * (dx - cx)
                ry = ay + s * (by - ay) - cy - t * (dy - cy)
                if op == "V":   # G s^2 t
                    return -mpmath.log(mpmath.hypot(rx, ry) / SCALE_R) * s ** 2 * t
                return (rx * nx + ry * ny) / (rx * rx + ry * ry) * s * t ** 3   # dG/dn s t^3

            val = LI * LJ / (2 * mpmath.pi) * mpmath.quad(
                lambda s: mpmath.quad(lambda t: f(s, t), t_split), s_split)
        MA, MB, LIr, LJr, err = reference_moments(name, i, j)
        if op == "V":
            ref = -LIr * LJr / (2 * MP.pi) * (MP.log(LJr / SCALE_R) / 6 + MA[2][1])
        else:
            ref = LIr / (2 * MP.pi) * MB[1][3]
        assert abs(ref - val) < 1e-15 * abs(ref), (name, op, ref, val)


@pytest.mark.parametrize("name, i, j", [pytest.param(*c, id=f"{c[0]}-{c[1]}{c[2]}")
                                        for c in PAIRS])
def test_reference_quadrature_converged(name, i, j):
    """The tanh-sinh error estimate of the moments is far below what the 1e-12 check
    needs (the monomial -> Legendre/Lagrange change of basis amplifies by < 1e10)."""
    MA, MB, LI, LJ, err = reference_moments(name, i, j)
    big = max(abs(x) for row in MA + MB for x in row)
    assert err < MP.mpf(10) ** -26 * big
