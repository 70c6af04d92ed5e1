"""The cell-block kernels of the plastic BE work piece (:mod:`hpfebe.bodies.plastic_be`):
products of a dense operator with the block diagonal of the 3 x 3 strain-stress blocks
D of the cells, and the reduced Jacobian I - M_pp D_p of its implicit inner solve, read
straight from M (no column copies), each entry a 3-term sum in one fixed order (bit for
bit the numbers of the batched matmul they replace; tests/bodies/test_plastic_be.py)."""

from __future__ import annotations

import numba
import numpy as np

from ..constitutive.j2 import radial_return_point

__all__ = ["_cell_return_kernel", "_plastic_blocks", "_times_blocks"]


def _times_blocks(A: np.ndarray, D: np.ndarray) -> np.ndarray:
    """A @ blockdiag(D) for A (m, 3 n) and n blocks D (n, 3, 3), without forming the
    block diagonal matrix."""
    A = np.ascontiguousarray(A, dtype=float)  # a column selection M[:, p] may be strided
    return _times_blocks_kernel(A, np.ascontiguousarray(D, dtype=float))


@numba.njit(cache=True)
def _times_blocks_kernel(A, D):
    """The 1 x 3 by 3 x 3 products of :func:`_times_blocks`, each a 3-term dot product
    summed left to right (the order of np.matmul's small-matrix loop: the same numbers
    bit for bit on CPUs where that loop uses no fused multiply-add, within the 3-term
    rounding bound elsewhere), ~6x faster than the batched matmul."""
    m, n = A.shape[0], D.shape[0]
    out = np.empty((m, 3 * n))
    for r in range(m):
        for j in range(n):
            for col in range(3):
                acc = 0.0
                for k in range(3):
                    acc += A[r, 3 * j + k] * D[j, k, col]
                out[r, 3 * j + col] = acc
    return out


@numba.njit(cache=True, inline="always")
def _row_times_blocks(row, pl, Dp, out, diag, sign):
    """out[3 j + col] = sign (row[3 pl_j:3 pl_j + 3] Dp[j])[col] for every plastic cell j,
    each the 3-term sum of :func:`_times_blocks_kernel` in its order (the three row
    entries loaded once for the three columns, no branch in the loop: it vectorises);
    ``diag`` >= 0: then out[diag] += 1 (J = I - ...: 1 - sum, the elementwise form's
    number; -sum elsewhere, 0 - sum up to the sign of a zero)."""
    for j in range(pl.size):
        c = 3 * pl[j]
        m0, m1, m2 = row[c], row[c + 1], row[c + 2]
        for col in range(3):
            acc = 0.0
            acc += m0 * Dp[j, 0, col]
            acc += m1 * Dp[j, 1, col]
            acc += m2 * Dp[j, 2, col]
            out[3 * j + col] = sign * acc
    if diag >= 0:
        out[diag] += 1.0                # 1 + (-acc) is 1 - acc exactly


@numba.njit(cache=True)
def _plastic_blocks_kernel(M, pl, D, rows):
    """(MD, J) of the plastic cells ``pl``: MD = (M[:, p] blockdiag(D[pl]))[rows] (p the
    strain rows 3 pl + a) and J = I - M[p, p] blockdiag(D[pl]), read straight from M and
    D (no column copies of M); every entry is the 3-term sum of
    :func:`_times_blocks_kernel` in its order, J is 1 - sum on its diagonal and 0 - sum
    elsewhere - the numbers of ``MD = _times_blocks(M[:, p], D[pl])``,
    ``np.eye(n) - MD[p]`` bit for bit."""
    n = pl.size
    Dp = np.empty((n, 3, 3))            # the plastic blocks contiguous, read n^2 times
    for j in range(n):
        Dp[j] = D[pl[j]]
    MD = np.empty((rows.size, 3 * n))
    for t in range(rows.size):
        _row_times_blocks(M[rows[t]], pl, Dp, MD[t], -1, 1.0)
    J = np.empty((3 * n, 3 * n))
    for a in range(n):
        for i in range(3):
            _row_times_blocks(M[3 * pl[a] + i], pl, Dp, J[3 * a + i], 3 * a + i, -1.0)
    return MD, J


def _plastic_blocks(M: np.ndarray, pl: np.ndarray, D: np.ndarray, rows=None):
    """(MD, J) of :func:`_plastic_blocks_kernel`: the rows ``rows`` (default all) of the
    columns of M D on the plastic cells ``pl`` and the reduced Jacobian I - M_pp D_p of
    :meth:`ElastoPlasticBE.implicit_response` (its Newton step needs the elastic rows of
    MD only)."""
    rows = np.arange(M.shape[0]) if rows is None else rows
    return _plastic_blocks_kernel(np.ascontiguousarray(M, dtype=float),
                                  np.ascontiguousarray(pl, dtype=np.int64),
                                  np.ascontiguousarray(D, dtype=float),
                                  np.ascontiguousarray(rows, dtype=np.int64))


@numba.njit(cache=True)
def _cell_return_kernel(E3, ep, alpha, beta, mu, kappa, lam, H, theta, sigma_Y):
    """The radial return of every cell (:func:`hpfebe.constitutive.j2.radial_return_point`,
    the numbers of :func:`~hpfebe.constitutive.j2.return_map` to round-off) at the cell
    strains E3 (nc, 3) = (eps11, eps22, 2 eps12) (plane strain) from the committed
    (ep, alpha, beta), fused with what the inner Newton needs of it: the initial stress
    tau = (C : eps_p)_(11, 22, 12) (:func:`hpfebe.fem.newton_potential.initial_stress`)
    and the blocks D = d tau / d e of (C - C_alg) in closed form,
    2 mu (1 - theta_1) P_dev + 2 mu theta_bar n x n (the kappa terms of C and C_alg
    cancel; zero on elastic cells) - one pass instead of about 40 numpy temporaries of
    (nc, 3, 3[, 3, 3]) per evaluation.  Returns (tau, D, plastic, sigma, eps_p, alpha,
    beta, dgamma, f_trial, normal, eta_norm), tensors (nc, 3, 3)."""
    nc = E3.shape[0]
    tau, D = np.empty((nc, 3)), np.zeros((nc, 3, 3))
    plastic = np.zeros(nc, dtype=np.bool_)
    sig, ep_new, beta_new, nrm = (np.empty((nc, 9)), np.empty((nc, 9)),
                                  np.empty((nc, 9)), np.empty((nc, 9)))
    al_new, dgam, ftr, safe = np.empty(nc), np.empty(nc), np.empty(nc), np.empty(nc)
    eps = np.zeros(9)
    ep9, beta9 = ep.reshape(nc, 9), beta.reshape(nc, 9)
    tb0 = 1.0 / (1.0 + H / (3.0 * mu))
    for c in range(nc):
        eps[0], eps[4] = E3[c, 0], E3[c, 1]
        eps[1] = eps[3] = 0.5 * E3[c, 2]
        al_new[c], dgam[c], ftr[c], safe[c] = radial_return_point(
            eps, ep9[c], alpha[c], beta9[c], mu, kappa, H, theta, sigma_Y, sig[c],
            ep_new[c], beta_new[c], nrm[c])
        e = ep_new[c]
        tr = e[0] + e[4] + e[8]
        tau[c, 0] = lam * tr + 2 * mu * e[0]
        tau[c, 1] = lam * tr + 2 * mu * e[4]
        tau[c, 2] = 2 * mu * e[1]
        if ftr[c] > 0.0:
            plastic[c] = True
            th1 = 1.0 - 2.0 * mu * dgam[c] / safe[c]
            c1, c2 = 2.0 * mu * (1.0 - th1), 2.0 * mu * (tb0 - (1.0 - th1))
            n = (nrm[c, 0], nrm[c, 4], nrm[c, 1])
            for a in range(3):
                for b in range(3):
                    D[c, a, b] = c2 * n[a] * n[b]
            D[c, 0, 0] += c1 * (2.0 / 3.0)
            D[c, 1, 1] += c1 * (2.0 / 3.0)
            D[c, 0, 1] -= c1 / 3.0
            D[c, 1, 0] -= c1 / 3.0
            D[c, 2, 2] += 0.5 * c1
    return (tau, D, plastic, sig.reshape(nc, 3, 3), ep_new.reshape(nc, 3, 3), al_new,
            beta_new.reshape(nc, 3, 3), dgam, ftr, nrm.reshape(nc, 3, 3), safe)
