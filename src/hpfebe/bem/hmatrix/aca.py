"""Adaptive cross approximation of one admissible block, with recompression.

ACA with partial pivoting (Bebendorf 2000; Bebendorf, "Hierarchical Matrices", Springer
2008, Alg. 3.9) builds A_ts ~ S_k = sum_{l<k} u_l v_l^T from k rows and k columns of the
block: row i_k of the residual A - S_k, its largest entry j_k, column j_k of the
residual scaled by 1/(R_k)_{i_k j_k}; the next row is the largest entry of that column.
The Frobenius norm of S_k is updated exactly,

    ||S_{k+1}||^2 = ||S_k||^2 + 2 sum_{l<k} (u_k . u_l)(v_k . v_l) + |u_k|^2 |v_k|^2,

and the iteration stops when |u_k| |v_k| <= eps ||S_{k+1}||_F (the usual estimate of the
relative error ||A - S_k||_F / ||A||_F).  The ACA+ safeguard against a premature stop
(Grasedyck 2005): before accepting, the residual of a reference row and of a reference
column that no pivot has touched is computed, one of each local index class (local
function and component: with the Lame systems the pivots may stay among one component's
rows); if one is above the average of the stopping test, it becomes the next pivot and
the iteration goes on.

Recompression: U = Q_u R_u, V = Q_v R_v (QR), R_u R_v^T = X s Y^T (SVD), truncated to the
smallest rank r with sqrt(sum_{l>=r} s_l^2) <= eps_rec ||S||_F; the truncated tail is the
exact error of the recompression against the ACA approximant.  Both estimates are
returned (the per-block error control that :class:`~.matrix.HMatrix` reports).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .entries import fill_col, fill_row



@njit(cache=True)
def _residual_row(kern, geom, rules, toff, roff, tpos, tloc, c0, c1, U, V, k, i, row, work):
    """row = (A - sum_l u_l v_l^T)[i, :] (U, V: rank-major, U[l] = u_l)."""
    fill_row(kern, geom, rules, toff, roff, tpos[i], tloc[i], c0, c1, row, work)
    for l in range(k):
        u = U[l, i]
        for b in range(row.shape[0]):
            row[b] -= u * V[l, b]


@njit(cache=True)
def _residual_col(kern, geom, rules, toff, roff, rpos, rloc, r0, r1, U, V, k, j, col, work):
    fill_col(kern, geom, rules, toff, roff, r0, r1, rpos[j], rloc[j], col, work)
    for l in range(k):
        v = V[l, j]
        for a in range(col.shape[0]):
            col[a] -= v * U[l, a]


@njit(cache=True)
def _grow(X, k):
    Y = np.zeros((2 * X.shape[0], X.shape[1]))
    Y[:k] = X[:k]
    return Y


@njit(cache=True)
def _argmax_free(x, used):
    best = -1.0
    arg = -1
    for a in range(x.shape[0]):
        if not used[a] and abs(x[a]) > best:
            best = abs(x[a])
            arg = a
    return arg


@njit(cache=True)
def _first_free(used, start):
    n = used.shape[0]
    for s in range(n):
        a = (start + s) % n
        if not used[a]:
            return a
    return -1


@njit(cache=True)
def _first_free_class(used, loc, cls, start):
    """The first untouched index from ``start`` on (cyclically) with loc == cls, or -1."""
    n = used.shape[0]
    for s in range(n):
        a = (start + s) % n
        if not used[a] and loc[a] == cls:
            return a
    return -1


@njit(cache=True)
def aca_block(kern, geom, rules, toff, roff, tpos, tloc, rpos, rloc, r0, r1, c0, c1,
              eps, floor, kmax, work):
    """ACA+ of the block tree positions r0..r1-1 (test) x c0..c1-1 (trial).

    ``tpos``/``tloc`` (``rpos``/``rloc``): tree position and local index of each row
    (column) of the block, relative to the block.  ``floor``: an absolute Frobenius
    error the block may have anyway (its share of the operator's tolerance).  Returns
    (U (m, k), V (n, k), k, err2, norm2, converged): A ~ U V^T, err2 the squared
    estimate |u_k|^2 |v_k|^2 of the last update, norm2 = ||U V^T||_F^2."""
    m = tpos.shape[0]
    n = rpos.shape[0]
    U = np.zeros((min(kmax, 16), m))       # rank-major, grown by doubling
    V = np.zeros((min(kmax, 16), n))
    used_r = np.zeros(m, np.bool_)
    used_c = np.zeros(n, np.bool_)
    row = np.empty(n)
    col = np.empty(m)
    norm2 = 0.0
    err2 = np.inf
    k = 0
    i = 0
    nref = 0
    ncls_r = 0
    for a in range(m):
        ncls_r = max(ncls_r, tloc[a] + 1)
    ncls_c = 0
    for b in range(n):
        ncls_c = max(ncls_c, rloc[b] + 1)
    zero_rows = 0
    while k < kmax:
        _residual_row(kern, geom, rules, toff, roff, tpos, tloc, c0, c1, U, V, k, i, row,
                      work)
        used_r[i] = True
        j = _argmax_free(row, used_c)
        if j < 0:       # every column a pivot (residual 0) or sampled and vanishing
            err2 = 0.0
            break
        piv = row[j]
        tiny = floor * 1e-3 / math.sqrt(m * n)
        if abs(piv) <= tiny or piv == 0.0:
            # a (numerically) zero residual row: the next pivot row is the largest entry
            # of an untouched reference column (ACA+); a block is taken as approximated
            # only when several sampled rows and columns vanish
            zero_rows += 1
            jc = _first_free(used_c, (zero_rows * 104729) % n)
            nxt = -1
            if jc >= 0:
                _residual_col(kern, geom, rules, toff, roff, rpos, rloc, r0, r1, U, V, k,
                              jc, col, work)
                nxt = _argmax_free(col, used_r)
                if nxt >= 0 and abs(col[nxt]) <= tiny:
                    used_c[jc] = True          # a vanishing column: sampled, skip it
                    nxt = -1
            if nxt < 0:
                nxt = _first_free(used_r, i + 1 + (m // 7))
            if nxt < 0 or zero_rows > 8:
                err2 = 0.0
                break
            i = nxt
            continue
        zero_rows = 0
        _residual_col(kern, geom, rules, toff, roff, rpos, rloc, r0, r1, U, V, k, j, col,
                      work)
        used_c[j] = True
        cross = 0.0
        uu = 0.0
        vv = 0.0
        for a in range(m):
            uu += col[a] * col[a]
        for b in range(n):
            vv += (row[b] / piv) ** 2
        for l in range(k):
            su = 0.0
            sv = 0.0
            for a in range(m):
                su += U[l, a] * col[a]
            for b in range(n):
                sv += V[l, b] * row[b]
            cross += su * sv / piv
        if k == U.shape[0]:
            U = _grow(U, k)
            V = _grow(V, k)
        for a in range(m):
            U[k, a] = col[a]
        for b in range(n):
            V[k, b] = row[b] / piv
        k += 1
        norm2 = max(norm2 + 2.0 * cross + uu * vv, 0.0)
        err2 = uu * vv
        if err2 <= max(eps * eps * norm2, floor * floor):
            # ACA+ check before accepting the stop: the residual of an untouched
            # reference row and column of every local index class (local function and
            # component: for the Lame systems the pivots may stay in one component's
            # rows while the other's residual is large); the worst becomes the pivot
            nref += 1
            avg = max(eps * eps * norm2, floor * floor)
            worst = avg
            nxt = -1
            for cls in range(ncls_r):
                ir = _first_free_class(used_r, tloc, cls, (nref * 7919) % m)
                if ir < 0:
                    continue
                _residual_row(kern, geom, rules, toff, roff, tpos, tloc, c0, c1, U, V, k, ir,
                              row, work)
                s = 0.0
                for b in range(n):
                    s += row[b] * row[b]
                if s * m > worst:
                    worst = s * m
                    nxt = ir
            for cls in range(ncls_c):
                jc = _first_free_class(used_c, rloc, cls, (nref * 104729) % n)
                if jc < 0:
                    continue
                _residual_col(kern, geom, rules, toff, roff, rpos, rloc, r0, r1, U, V, k,
                              jc, col, work)
                s = 0.0
                for a in range(m):
                    s += col[a] * col[a]
                if s * n > worst:
                    worst = s * n
                    nxt = _argmax_free(col, used_r)
            if nxt < 0:
                break
            i = nxt
            continue
        i = _argmax_free(col, used_r)
        if i < 0:
            err2 = 0.0
            break
    converged = err2 <= max(eps * eps * norm2, floor * floor) or k == min(m, n)
    return U[:k].T.copy(), V[:k].T.copy(), k, err2, norm2, converged


@njit(cache=True)
def recompress(U, V, eps, floor):
    """Truncated SVD of U V^T (QR of both factors, SVD of R_u R_v^T) to the smallest rank
    whose tail sqrt(sum s_l^2, l >= r) is <= max(eps ||U V^T||_F, floor).  Returns
    (U', V', tail2)."""
    k = U.shape[1]
    if k == 0:
        return U, V, 0.0
    Qu, Ru = np.linalg.qr(np.ascontiguousarray(U))
    Qv, Rv = np.linalg.qr(np.ascontiguousarray(V))
    X, s, Yt = np.linalg.svd(Ru @ Rv.T)
    total = 0.0
    for l in range(s.shape[0]):
        total += s[l] * s[l]
    allowed = max(eps * eps * total, floor * floor)
    r = s.shape[0]
    tail = 0.0
    while r > 0 and tail + s[r - 1] * s[r - 1] <= allowed:
        tail += s[r - 1] * s[r - 1]
        r -= 1
    Xr = np.ascontiguousarray(X[:, :r]) * s[:r]
    Yr = np.ascontiguousarray(Yt[:r].T)
    Un = np.ascontiguousarray(Qu) @ Xr
    Vn = np.ascontiguousarray(Qv) @ Yr
    return Un, Vn, tail


@njit(cache=True)
def aca_all(kern, geom, rules, toff, roff, tpos, tloc, rpos, rloc, blocks, eps_aca, eps_rec,
            floors, max_rank, work):
    """:func:`aca_block` and :func:`recompress` for every block (rows of ``blocks``: tree
    positions p0, p1, q0, q1): one call for all (a Python loop paid ~0.2 ms of argument
    unboxing per block).  Returns (U, V flat: each block's U (m, r) and V (n, r)
    row-major, one after the other; ranks; err2 (ACA estimate + truncation tail);
    norm2; converged)."""
    nb = blocks.shape[0]
    ranks = np.zeros(nb, np.int64)
    err2 = np.zeros(nb)
    norm2 = np.zeros(nb)
    ok = np.zeros(nb, np.bool_)
    Uf = np.empty(1 << 16)
    Vf = np.empty(1 << 16)
    nu = 0
    nv = 0
    for b in range(nb):
        p0, p1, q0, q1 = blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3]
        r0, r1, c0, c1 = toff[p0], toff[p1], roff[q0], roff[q1]
        m = r1 - r0
        n = c1 - c0
        U, V, k, e2, n2, conv = aca_block(kern, geom, rules, toff, roff, tpos[r0:r1],
                                          tloc[r0:r1], rpos[c0:c1], rloc[c0:c1], p0, p1,
                                          q0, q1, eps_aca, 0.5 * floors[b],
                                          min(m, n, max_rank), work)
        U, V, tail2 = recompress(U, V, eps_rec, 0.5 * floors[b])
        r = U.shape[1]
        while nu + m * r > Uf.shape[0]:
            G = np.empty(2 * Uf.shape[0])
            G[:nu] = Uf[:nu]
            Uf = G
        while nv + n * r > Vf.shape[0]:
            G = np.empty(2 * Vf.shape[0])
            G[:nv] = Vf[:nv]
            Vf = G
        Uf[nu:nu + m * r] = U.ravel()
        Vf[nv:nv + n * r] = V.ravel()
        nu += m * r
        nv += n * r
        ranks[b] = r
        err2[b] = e2 + tail2 if np.isfinite(e2) else n2
        norm2[b] = n2
        ok[b] = conv
    return Uf[:nu].copy(), Vf[:nv].copy(), ranks, err2, norm2, ok
