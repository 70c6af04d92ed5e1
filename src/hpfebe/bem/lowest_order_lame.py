"""Closed-form Galerkin matrices of the lowest-order Lame operators (p = 1).

The Lame kernels (:mod:`hpfebe.bem.lame`: G = c1 {-log(r/R) I + c2 r r^T/r^2}, the
hypersingular kernel Vt = Et {-log(r/R) I + r r^T/r^2}) need, besides the Laplace I, the
integral Q = int int w / conj(w) of each pair ((Q1), (Q2) of :mod:`.lowest_order_pairs`),
computed in the pass of :func:`hpfebe.bem.lowest_order.laplace_p1_vk`.

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
matrices alone at p = 2 (to 1e-13), where no closed form is involved.  :func:`lame_p1`
runs the pass of :func:`.lowest_order.laplace_p1_vk` with Q and then one row pass
(:func:`_lame_rows`) that writes V, Vt and K; :func:`lame_p1_w` forms W = T^T Vt T per
component pair by :func:`.lowest_order.laplace_p1_w` (the blocks Vt[k::2, l::2] are
symmetric).
Nothing of the general quadrature path is compiled for p = 1.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .kernels import KP_C1, KP_C1_C2, KP_ET, KP_LAMBDA, KP_LAME_SIZE, KP_MU
from .lowest_order import _check_p1, _n_threads, _p1_pass, _threaded, laplace_p1_w
from .threads import zeros_aligned


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
