"""Kernel functions of the boundary integral operators, and their numba dispatch.

Every kernel k(r) = A log|r| + k_reg(r) (r = x - y) is given by its constant log
coefficient A (``logc``, d*d values) and a numba function for the regular part,

    kernel(rx, ry, npts, n_x, n_y, kp, out):  out[q, :] = k_reg(rx[q], ry[q])  (q < npts)

(row-major d x d values, normals n_x, n_y of the test and trial elements, parameters kp),
homogeneous of degree 0 or -1 in r plus constants (what the singular integration of
:mod:`hpfebe.bem.integration` relies on).  The assemblers are compiled once and receive
the kernel as an integer id, dispatched by :func:`kernel_batch`: numba's on-disk cache
cannot hold functions specialised on function-typed arguments across processes, while an
integer id costs one predictable branch per batch of quadrature points.  A new kernel
gets an id here and a branch in ``kernel_batch``.
"""

from __future__ import annotations

import math

from numba import njit

INV_2PI = 1.0 / (2.0 * math.pi)

LAPLACE_SL, LAPLACE_DL, LAME_SL, LAME_DL, LAME_HS = 0, 1, 2, 3, 4

# Layout of the kernel parameter array kp (module-level integers: numba reads them as
# compile-time constants).  Laplace (laplace.py): kp = [log(R) / (2 pi)].
KP_LAPLACE_LOG_R = 0
# Lame (lame.kernel_params), Et = E'/(4 pi), R the kernel length scale:
#   [c1 log R, c1 c2, lambda, mu, c1, c2, Et log R, Et]
KP_C1_LOG_R = 0     # c1 log R: regular part of the single layer G
KP_C1_C2 = 1        # c1 c2: the r r^T / |r|^2 coefficient of G
KP_LAMBDA = 2       # Lame constant lambda (lambda* in plane stress)
KP_MU = 3           # Lame constant mu
KP_C1 = 4           # c1 = (lambda + 3 mu) / (4 pi mu (lambda + 2 mu)): log coefficient of G
KP_C2 = 5           # c2 = (lambda + mu) / (lambda + 3 mu)
KP_ET_LOG_R = 6     # Et log R: regular part of the hypersingular kernel Vt
KP_ET = 7           # Et = E' / (4 pi): factor (and log coefficient) of Vt
KP_LAME_SIZE = 8


@njit(cache=True)
def laplace_single_layer(rx, ry, npts, nx, ny, kp, out):
    """G(x,y) = -1/(2 pi) log(|r|/R): regular part log(R)/(2 pi) = kp[KP_LAPLACE_LOG_R];
    the log part -1/(2 pi) log|r| is ``logc``."""
    for q in range(npts):
        out[q, 0] = kp[KP_LAPLACE_LOG_R]


@njit(cache=True)
def laplace_double_layer(rx, ry, npts, nx, ny, kp, out):
    """d_{n_y} G(x, y) = (x - y) . n_y / (2 pi |x - y|^2)."""
    for q in range(npts):
        out[q, 0] = INV_2PI * (rx[q] * ny[0] + ry[q] * ny[1]) / (rx[q] * rx[q] + ry[q] * ry[q])


# ------------------------------------------------------------------ 2D Lame (lame.py)
# kp layout: the KP_* indices above
@njit(cache=True, inline="always")
def _log_rr(rx, ry, a0, a1, out):
    """a0 I + a1 r r^T / |r|^2 into out[0:4]."""
    f = a1 / (rx * rx + ry * ry)
    out[0] = a0 + f * rx * rx
    out[1] = f * rx * ry
    out[2] = out[1]
    out[3] = a0 + f * ry * ry


@njit(cache=True, inline="always")
def _traction_of_G(rx, ry, ny0, ny1, lam, mu, c1, c2, out):
    """K_ik(x, y) = [sigma_y(G(x, .) e_i) n_y]_k at r = x - y into out[0:4] (degree -1;
    on a straight element only its odd Cauchy part survives: principal value)."""
    r2 = rx * rx + ry * ry
    for i in range(2):
        ri = rx if i == 0 else ry
        e0 = 1.0 if i == 0 else 0.0
        e1 = 1.0 - e0
        # D_jl = d v_j / d y_l for v = G(x, .) e_i, with d/dy = -d/dr and
        # dG_ji/dr_l = c1 (-d_ij r_l + c2 (d_il r_j + d_jl r_i) - 2 c2 r_i r_j r_l/|r|^2)/|r|^2
        g = 2.0 * c2 * ri / r2
        d00 = -c1 * (-e0 * rx + c2 * (e0 * rx + ri) - g * rx * rx) / r2
        d01 = -c1 * (-e0 * ry + c2 * e1 * rx - g * rx * ry) / r2
        d10 = -c1 * (-e1 * rx + c2 * e0 * ry - g * ry * rx) / r2
        d11 = -c1 * (-e1 * ry + c2 * (e1 * ry + ri) - g * ry * ry) / r2
        div = d00 + d11
        s00 = lam * div + 2.0 * mu * d00
        s11 = lam * div + 2.0 * mu * d11
        s01 = mu * (d01 + d10)
        out[i * 2 + 0] = s00 * ny0 + s01 * ny1
        out[i * 2 + 1] = s01 * ny0 + s11 * ny1


@njit(cache=True)
def lame_single_layer(rx, ry, npts, nx, ny, kp, out):
    """Regular part of G: c1 log R I + c1 c2 r r^T / |r|^2 (degree 0); the log part
    -c1 log|r| I is ``logc``."""
    for q in range(npts):
        _log_rr(rx[q], ry[q], kp[KP_C1_LOG_R], kp[KP_C1_C2], out[q])


@njit(cache=True)
def lame_double_layer(rx, ry, npts, nx, ny, kp, out):
    """Traction of G with respect to y, (1.4): K_ik = [sigma_y(G e_i) n_y]_k."""
    for q in range(npts):
        _traction_of_G(rx[q], ry[q], ny[0], ny[1], kp[KP_LAMBDA], kp[KP_MU], kp[KP_C1],
                       kp[KP_C2], out[q])


@njit(cache=True)
def lame_hypersingular(rx, ry, npts, nx, ny, kp, out):
    """Regular part of Vt: E'/(4 pi) (log R I + r r^T/|r|^2); log part -E'/(4 pi) log|r| I."""
    for q in range(npts):
        _log_rr(rx[q], ry[q], kp[KP_ET_LOG_R], kp[KP_ET], out[q])


@njit(cache=True)
def kernel_point(kid, rx, ry, nx0, nx1, ny0, ny1, kp, out):
    """The regular part of kernel ``kid`` at one point r = (rx, ry) into out[0, :], the
    same arithmetic as :func:`kernel_batch` (bitwise the same values).  For the
    point-by-point singular rules: scalar arguments, where a one-point ``kernel_batch``
    call (array arguments, one more call level) cost ~150 ns per point - 80 % of an
    adjacent pair at p = 1 (issue 14)."""
    if kid == LAPLACE_SL:
        out[0, 0] = kp[KP_LAPLACE_LOG_R]
    elif kid == LAPLACE_DL:
        out[0, 0] = INV_2PI * (rx * ny0 + ry * ny1) / (rx * rx + ry * ry)
    elif kid == LAME_SL:
        _log_rr(rx, ry, kp[KP_C1_LOG_R], kp[KP_C1_C2], out[0])
    elif kid == LAME_DL:
        _traction_of_G(rx, ry, ny0, ny1, kp[KP_LAMBDA], kp[KP_MU], kp[KP_C1], kp[KP_C2],
                       out[0])
    elif kid == LAME_HS:
        _log_rr(rx, ry, kp[KP_ET_LOG_R], kp[KP_ET], out[0])
    else:
        raise ValueError("unknown kernel id")


@njit(cache=True)
def kernel_batch(kid, rx, ry, npts, nx, ny, kp, out):
    """Evaluate the regular part of kernel ``kid`` at a batch of points."""
    if kid == LAPLACE_SL:
        laplace_single_layer(rx, ry, npts, nx, ny, kp, out)
    elif kid == LAPLACE_DL:
        laplace_double_layer(rx, ry, npts, nx, ny, kp, out)
    elif kid == LAME_SL:
        lame_single_layer(rx, ry, npts, nx, ny, kp, out)
    elif kid == LAME_DL:
        lame_double_layer(rx, ry, npts, nx, ny, kp, out)
    elif kid == LAME_HS:
        lame_hypersingular(rx, ry, npts, nx, ny, kp, out)
    else:
        raise ValueError("unknown kernel id")
