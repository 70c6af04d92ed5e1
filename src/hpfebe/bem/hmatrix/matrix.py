"""The H-matrix of one Galerkin operator: storage, assembly, matvec, error control.

Near-field blocks (dense, row-major) and far-field blocks (U V^T) live in flat arrays,
addressed by the dof ranges [r0, r1) x [c0, c1) of the broken numbering of
:mod:`.entries`; the matvec and its transpose are numba loops over the blocks.

Error control.  Each far block is built by ACA+ to eps_aca = tol / 10 and recompressed to
eps_rec = 0.3 tol relative to its own Frobenius norm, or to an absolute floor, its share
tol/4 ||A_near||_F sqrt(m n / (M N)) of the operator's tolerance (so that a block that is
round-off of the whole operator, e.g. the Laplace double layer between two panels on one
line, costs no rank); near blocks are exact.  Hence ||A - H||_F <~ tol ||A||_F for the
whole operator.  What was achieved is reported twice: the estimate from the blocks
(:attr:`HMatrix.error_bound`, the root of the summed squared ACA and truncation
estimates over the Frobenius norm) and a measurement, :meth:`HMatrix.sampled_error`:
exact rows of the operator (the same quadrature, row by row) against the rows of H.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from .aca import aca_all
from .cluster import ClusterTree, block_tree
from .entries import fill_dense, fill_row, work_arrays

ACA_FRACTION = 0.1       # eps_aca = ACA_FRACTION * tol
RECOMPRESS_FRACTION = 0.3  # eps_rec
FLOOR_FRACTION = 0.25     # the absolute floor: its share of FLOOR_FRACTION tol ||A_near||


@dataclass(frozen=True)
class Layout:
    """Dofs of one side of the matrix in the broken numbering: ``off[pos]`` the first
    dof of the element at tree position pos (off[-1] the size), ``pos[r]`` and ``loc[r]``
    the tree position and local index of dof r."""

    off: np.ndarray
    pos: np.ndarray
    loc: np.ndarray

    @classmethod
    def of(cls, degrees_in_tree_order: np.ndarray, kind: int, deriv: bool, d: int):
        sizes = _sizes(degrees_in_tree_order, kind, deriv, d)
        off = np.zeros(len(sizes) + 1, np.int64)
        np.cumsum(sizes, out=off[1:])
        pos = np.repeat(np.arange(len(sizes), dtype=np.int64), sizes)
        loc = np.arange(off[-1], dtype=np.int64) - off[pos]
        return cls(off, pos, loc)

    @property
    def size(self) -> int:
        return int(self.off[-1])


def _sizes(p, kind, deriv, d):
    """Local functions (times d) per element: p_e + 1 (GLL, or W's GLL output), p_e."""
    p = np.asarray(p, np.int64)
    return ((p + 1) * d if (deriv or kind == 1) else p * d).astype(np.int64)


@njit(cache=True)
def _fill_near(kern, geom, rules, toff, roff, blocks, noff, data, work):
    for b in range(blocks.shape[0]):
        r0, r1, c0, c1 = blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3]
        m = toff[r1] - toff[r0]
        n = roff[c1] - roff[c0]
        out = data[noff[b]:noff[b] + m * n].reshape(m, n)
        fill_dense(kern, geom, rules, toff, roff, r0, r1, c0, c1, out, work)


@njit(cache=True, nogil=True)
def _matvec(nrng, noff, ndata, frng, frank, fuoff, fvoff, U, V, x, y, trans, sym):
    """y += H x (``trans``: y += H^T x); x, y 2D (columns).  ``sym``: only the blocks
    on and above the diagonal are stored, each off-diagonal one acting twice (A_ts and
    A_ts^T = A_st) in one pass over its data."""
    ncol = x.shape[1]
    for b in range(nrng.shape[0]):
        r0, r1, c0, c1 = nrng[b, 0], nrng[b, 1], nrng[b, 2], nrng[b, 3]
        n = c1 - c0
        base = noff[b]
        both = sym and r0 != c0
        tr = trans and not sym
        for a in range(r1 - r0):
            for c in range(n):
                v = ndata[base + a * n + c]
                if both:
                    for q in range(ncol):
                        y[r0 + a, q] += v * x[c0 + c, q]
                        y[c0 + c, q] += v * x[r0 + a, q]
                elif tr:
                    for q in range(ncol):
                        y[c0 + c, q] += v * x[r0 + a, q]
                else:
                    for q in range(ncol):
                        y[r0 + a, q] += v * x[c0 + c, q]
    for b in range(frng.shape[0]):
        r0, r1, c0, c1 = frng[b, 0], frng[b, 1], frng[b, 2], frng[b, 3]
        k = frank[b]
        ub = fuoff[b]
        vb = fvoff[b]
        tr = trans and not sym
        vx = np.zeros((k, ncol))        # V^T x_s (or U^T x_t when tr)
        ux = np.zeros((k, ncol))        # U^T x_t, for the mirror of a symmetric H
        if tr:          # H^T x = V (U^T x)
            for a in range(r1 - r0):
                for l in range(k):
                    u = U[ub + a * k + l]
                    for q in range(ncol):
                        vx[l, q] += u * x[r0 + a, q]
            for c in range(c1 - c0):
                for l in range(k):
                    v = V[vb + c * k + l]
                    for q in range(ncol):
                        y[c0 + c, q] += v * vx[l, q]
            continue
        for c in range(c1 - c0):
            for l in range(k):
                v = V[vb + c * k + l]
                for q in range(ncol):
                    vx[l, q] += v * x[c0 + c, q]
        for a in range(r1 - r0):        # y_t += U (V^T x_s); and U^T x_t if sym
            for l in range(k):
                u = U[ub + a * k + l]
                for q in range(ncol):
                    y[r0 + a, q] += u * vx[l, q]
                    if sym:
                        ux[l, q] += u * x[r0 + a, q]
        if sym:                         # y_s += V (U^T x_t)
            for c in range(c1 - c0):
                for l in range(k):
                    v = V[vb + c * k + l]
                    for q in range(ncol):
                        y[c0 + c, q] += v * ux[l, q]


@njit(cache=True)
def _exact_rows(kern, geom, rules, toff, roff, tpos, tloc, rows, nc, work):
    out = np.empty((rows.shape[0], roff[-1]))
    for q in range(rows.shape[0]):
        r = rows[q]
        fill_row(kern, geom, rules, toff, roff, tpos[r], tloc[r], 0, nc, out[q], work)
    return out


class HMatrix:
    """H-matrix of the Galerkin matrix of ``kern`` between the ``test`` and ``trial``
    :class:`Layout` of the elements of ``tree`` (broken numbering).  Built on
    construction; ``matvec`` / ``rmatvec`` act on vectors or column blocks."""

    def __init__(self, kern, geom, rules, tree: ClusterTree, test: Layout, trial: Layout,
                 tol: float, eta: float, max_rank: int, pmax: int, far_rules=None,
                 symmetric: bool = False):
        self.kern, self.geom, self.rules = kern, geom, rules
        self.far_rules = rules if far_rules is None else far_rules
        self.test, self.trial, self.tol, self.pmax = test, trial, tol, pmax
        self.symmetric = bool(symmetric)
        self.shape = (test.size, trial.size)
        d = kern[4]
        t0 = time.process_time()
        near, far = block_tree(tree, eta)
        if self.symmetric:      # the blocks on and above the diagonal
            near = near[tree.start[near[:, 0]] <= tree.start[near[:, 1]]]
            far = far[tree.start[far[:, 0]] < tree.start[far[:, 1]]]
        self.near_clusters, self.far_clusters = near, far     # (t, s) cluster pairs
        nb = np.column_stack([tree.start[near[:, 0]], tree.stop[near[:, 0]],
                              tree.start[near[:, 1]], tree.stop[near[:, 1]]])
        self.near_rng = _dof_ranges(nb, test.off, trial.off)
        sizes = ((self.near_rng[:, 1] - self.near_rng[:, 0])
                 * (self.near_rng[:, 3] - self.near_rng[:, 2]))
        self.near_off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.near_data = np.empty(int(self.near_off[-1]))
        _fill_near(kern, geom, rules, test.off, trial.off, np.ascontiguousarray(nb),
                   self.near_off, self.near_data, work_arrays(rules, pmax, d))
        self.diag_blocks = np.flatnonzero(near[:, 0] == near[:, 1])
        sq = np.add.reduceat(self.near_data ** 2, self.near_off[:-1]) if len(nb) else [0.0]
        twice = self.symmetric & (self.near_rng[:, 0] != self.near_rng[:, 2])
        near_norm = math.sqrt(float(np.sum(np.where(twice, 2.0, 1.0) * sq)))
        self.time_near = time.process_time() - t0
        self._build_far(tree, far, near_norm, max_rank, d)
        self.time_far = time.process_time() - t0 - self.time_near
        self.near_norm = near_norm

    def _build_far(self, tree, far, near_norm, max_rank, d):
        test, trial = self.test, self.trial
        M, N = self.shape
        blocks = np.ascontiguousarray(np.column_stack(
            [tree.start[far[:, 0]], tree.stop[far[:, 0]], tree.start[far[:, 1]],
             tree.stop[far[:, 1]]]).astype(np.int64).reshape(-1, 4))
        m = test.off[blocks[:, 1]] - test.off[blocks[:, 0]]
        n = trial.off[blocks[:, 3]] - trial.off[blocks[:, 2]]
        floors = FLOOR_FRACTION * self.tol * near_norm * np.sqrt(m * n / (M * N))
        U, V, ranks, err2, norm2, ok = aca_all(
            self.kern, self.geom, self.far_rules, test.off, trial.off, test.pos, test.loc,
            trial.pos, trial.loc, blocks, ACA_FRACTION * self.tol,
            RECOMPRESS_FRACTION * self.tol, floors, max_rank,
            work_arrays(self.far_rules, self.pmax, d))
        w = 2.0 if self.symmetric else 1.0     # A_ts and A_st
        self.unconverged = int((~ok).sum())
        self.far_err2, self.far_norm2 = w * float(err2.sum()), w * float(norm2.sum())
        self.far_rng = _dof_ranges(blocks, test.off, trial.off)
        self.far_rank = ranks
        self.far_uoff = np.concatenate([[0], np.cumsum(m * ranks)]).astype(np.int64)
        self.far_voff = np.concatenate([[0], np.cumsum(n * ranks)]).astype(np.int64)
        self.far_U, self.far_V = U, V

    # ------------------------------------------------------------------ action
    def _apply(self, x, trans: bool):
        x = np.asarray(x, dtype=float)
        one = x.ndim == 1
        X = np.ascontiguousarray(x.reshape(x.shape[0], -1))
        Y = np.zeros((self.shape[1] if trans else self.shape[0], X.shape[1]))
        _matvec(self.near_rng, self.near_off, self.near_data, self.far_rng, self.far_rank,
                self.far_uoff, self.far_voff, self.far_U, self.far_V, X, Y, trans,
                self.symmetric)
        return Y[:, 0] if one else Y

    def matvec(self, x):
        """H x (broken numbering)."""
        return self._apply(x, False)

    def rmatvec(self, x):
        """H^T x (broken numbering)."""
        return self._apply(x, True)

    # ------------------------------------------------------------------ figures
    @property
    def nbytes(self) -> int:
        """Bytes of the stored blocks (data and their index arrays)."""
        arrays = (self.near_data, self.near_rng, self.near_off, self.far_U, self.far_V,
                  self.far_rng, self.far_rank, self.far_uoff, self.far_voff)
        return int(sum(a.nbytes for a in arrays))

    @property
    def dense_nbytes(self) -> int:
        return 8 * self.shape[0] * self.shape[1]

    @property
    def error_bound(self) -> float:
        """Estimated ||A - H||_F / ||A||_F from the blocks' ACA and truncation estimates."""
        total = self.near_norm ** 2 + self.far_norm2
        return math.sqrt(self.far_err2 / total) if total > 0 else 0.0

    def sampled_error(self, n_rows: int = 8, seed: int = 0) -> float:
        """Measured ||A - H||_F / ||A||_F from ``n_rows`` random rows: exact rows r (the
        dense assembly's quadrature, row by row) against the rows of H (H^T e_r); the
        unbiased estimate (M / n_rows) sum_r ||(A - H)_r||^2 of ||A - H||_F^2 over
        ||H||_F^2 (near blocks and the far blocks' ||U V^T||_F^2)."""
        rng = np.random.default_rng(seed)
        rows = np.sort(rng.choice(self.shape[0], size=min(n_rows, self.shape[0]),
                                  replace=False)).astype(np.int64)
        nc = len(self.trial.off) - 1
        exact = _exact_rows(self.kern, self.geom, self.rules, self.test.off, self.trial.off,
                            self.test.pos, self.test.loc, rows, nc,
                            work_arrays(self.rules, self.pmax, self.kern[4]))
        E = np.zeros((self.shape[0], len(rows)))
        E[rows, np.arange(len(rows))] = 1.0
        approx = self.rmatvec(E).T
        err2 = self.shape[0] / len(rows) * float(np.sum((exact - approx) ** 2))
        total = self.near_norm ** 2 + self.far_norm2
        return math.sqrt(err2 / total) if total > 0 else 0.0

    def info(self) -> dict:
        """Storage, ranks, timings and error figures."""
        return {"shape": self.shape, "bytes": self.nbytes, "dense_bytes": self.dense_nbytes,
                "ratio": self.nbytes / self.dense_nbytes, "n_near": len(self.near_rng),
                "n_far": len(self.far_rng),
                "max_rank": int(self.far_rank.max()) if len(self.far_rank) else 0,
                "mean_rank": float(self.far_rank.mean()) if len(self.far_rank) else 0.0,
                "unconverged_blocks": int(self.unconverged),
                "error_bound": self.error_bound, "cpu_near_s": self.time_near,
                "cpu_far_s": self.time_far}

    def diagonal_block(self, b: int) -> tuple[int, int, np.ndarray]:
        """(r0, r1, dense block) of the near block number ``b``."""
        r0, r1, c0, c1 = self.near_rng[b]
        blk = self.near_data[self.near_off[b]:self.near_off[b + 1]]
        return int(r0), int(r1), blk.reshape(r1 - r0, c1 - c0)


def _dof_ranges(pos_ranges, toff, roff):
    pr = np.asarray(pos_ranges, np.int64).reshape(-1, 4)
    return np.ascontiguousarray(np.column_stack([toff[pr[:, 0]], toff[pr[:, 1]],
                                                 roff[pr[:, 2]], roff[pr[:, 3]]]))
