"""The cell-block kernels of the plastic BE work piece (:mod:`hpfebe.bodies.plastic_be`):
products of a dense operator with the block diagonal of the 3 x 3 strain-stress blocks
D of the cells, and the reduced Jacobian I - M_pp D_p of its implicit inner solve, read
straight from M (no column copies), each entry a 3-term sum in one fixed order (bit for
bit the numbers of the batched matmul they replace; tests/bodies/test_plastic_be.py)."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["_plastic_blocks", "_times_blocks"]


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
def _row_times_block(M, r, c, D, col):
    """(M[r, 3c:3c+3] D[c])[col]: the 3-term sum of :func:`_times_blocks_kernel`, in its
    order."""
    acc = 0.0
    for k in range(3):
        acc += M[r, 3 * c + k] * D[c, k, col]
    return acc


@numba.njit(cache=True)
def _plastic_blocks_kernel(M, pl, D, rows):
    """(MD, J) of the plastic cells ``pl``: MD = (M[:, p] blockdiag(D[pl]))[rows] (p the
    strain rows 3 pl + a) and J = I - M[p, p] blockdiag(D[pl]), read straight from M and
    D (no column copies of M); every entry is the 3-term sum of
    :func:`_times_blocks_kernel` in its order, J is 1 - sum on its diagonal and 0 - sum
    elsewhere - the numbers of ``MD = _times_blocks(M[:, p], D[pl])``,
    ``np.eye(n) - MD[p]`` bit for bit."""
    n = pl.size
    MD = np.empty((rows.size, 3 * n))
    for t in range(rows.size):
        r = rows[t]
        for j in range(n):
            for col in range(3):
                MD[t, 3 * j + col] = _row_times_block(M, r, pl[j], D, col)
    J = np.empty((3 * n, 3 * n))
    for a in range(n):
        for i in range(3):
            r = 3 * pl[a] + i
            for j in range(n):
                for col in range(3):
                    J[3 * a + i, 3 * j + col] = ((1.0 if a == j and i == col else 0.0)
                                                 - _row_times_block(M, r, pl[j], D, col))
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
