"""A multilevel additive-Schwarz preconditioner for the compressed single layer V on the
cluster tree (issue 27).

V is of order -1: on the piecewise polynomials W_hp its condition number grows like
1 / h, and the block-Jacobi preconditioner (:class:`~.solvers.BlockJacobi`, the exact
inverses of the leaf blocks) leaves it growing like N: it sees the means of the density
over the leaves only through the leaf blocks, which underestimate their energy by the
whole far field (measured: lambda_max of the block-Jacobi-preconditioned V grows with N,
lambda_min does not).  Here the means are taken out of the leaf blocks and put back
level by level, as in the Haar-basis multilevel methods for negative-order operators
(Oswald 1998; Tran & Stephan 1996), with the direct additive-Schwarz splitting of W_hp
(per component c = 1..d)

    W_hp = sum_{leaves t} W_hp,0(t)                     (mean-free leaf blocks, exact)
         + sum_{c below the cut} span{h_c e_c}          (one Haar function per cluster)
         + span{chi_s e_c : s in the cut}               (coarse space, solved exactly)

W_hp,0(t) the functions on leaf t with zero mean of every component, solved exactly:
Q (Q^T V_tt Q)^{-1} Q^T = V_tt^{-1} - Z_t (w_t^T Z_t)^{-1} Z_t^T, Z_t = V_tt^{-1} w_t,
w_t the mean functionals (the element lengths at the P_0 coefficients), with the
Cholesky factors of :class:`~.solvers.BlockJacobi`;

    h_c = chi_{c1} / |c1| - chi_{c2} / |c2|,   c1, c2 the children of c,

chi_s the indicator of the elements of cluster s (its constant Legendre coefficient
P_0 = 1), |s| their total length.  The cut is the deepest level of the tree with at
most ``N_COARSE`` clusters (and the leaves above it): the Haar functions of the levels
above the cut and the constant span its indicators, so they are solved together by one
dense Cholesky factor.  The Haar functions are mean-free, hence their V-energies decay
with the cluster size and the levels are nearly V-orthogonal: the preconditioned
condition number grows like log N (measured, Laplace p = 1: 10.3 at N = 1024, 31.8 at
N = 65536, + 3.6 per doubling; block Jacobi 129 and 8004, like N).  Its application

    C^{-1} r = sum_t Q_t (Q_t^T V_tt Q_t)^{-1} Q_t^T r + sum_c h_c (h_c^T V h_c)^{-1} h_c^T r
               + X (X^T V X)^{-1} X^T r

costs O(N) (prefix sums over the tree positions); the energies h_c^T V h_c (d x d
per cluster) come from the stored blocks: every block (t, s) contributes its constant-
constant sum 1_t^T A_ts 1_s to the lowest common ancestor of t and s, and the sums over
sub-trees give 1_c^T V 1_c for every c, from which the Haar energies follow.  X^T V X
is d * (clusters in the cut) matvecs of V.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from numba import njit

from .cluster import ClusterTree
from .solvers import BlockJacobi

N_COARSE = 32          # at most this many clusters in the coarse cut (d x that unknowns)
COARSE_CHUNK = 16      # columns per matvec when forming X^T V X


@njit(cache=True)
def _block_constant_sums(t_s, start, off, rng, data_off, data, d, near, rank, uoff, voff,
                         U, V, out):
    """out[b, a, c] = 1_{t,a}^T A_ts 1_{s,c} for every stored block b = (t, s): the sum
    of its entries between the constant (P_0) functions of components a and c.  ``near``:
    dense row-major blocks (data, data_off); else low rank U V^T (rank, uoff, voff)."""
    for b in range(t_s.shape[0]):
        t, s = t_s[b, 0], t_s[b, 1]
        r0, c0 = rng[b, 0], rng[b, 2]
        ncol = rng[b, 3] - rng[b, 2]
        for a in range(d):
            for c in range(d):
                out[b, a, c] = 0.0
        if near:
            for pt in range(start[t, 0], start[t, 1]):
                for ps in range(start[s, 0], start[s, 1]):
                    for a in range(d):
                        i = off[pt] + a - r0
                        for c in range(d):
                            j = off[ps] + c - c0
                            out[b, a, c] += data[data_off[b] + i * ncol + j]
        else:
            k = rank[b]
            ua = np.zeros((d, k))
            vc = np.zeros((d, k))
            for pt in range(start[t, 0], start[t, 1]):
                for a in range(d):
                    i = off[pt] + a - r0
                    for l in range(k):
                        ua[a, l] += U[uoff[b] + i * k + l]
            for ps in range(start[s, 0], start[s, 1]):
                for c in range(d):
                    j = off[ps] + c - c0
                    for l in range(k):
                        vc[c, l] += V[voff[b] + j * k + l]
            for a in range(d):
                for c in range(d):
                    acc = 0.0
                    for l in range(k):
                        acc += ua[a, l] * vc[c, l]
                    out[b, a, c] = acc


@njit(cache=True)
def _lca(t_s, parent, depth):
    """The lowest common ancestor of every cluster pair (t, s)."""
    out = np.empty(t_s.shape[0], np.int64)
    for b in range(t_s.shape[0]):
        t, s = t_s[b, 0], t_s[b, 1]
        while depth[t] > depth[s]:
            t = parent[t]
        while depth[s] > depth[t]:
            s = parent[s]
        while t != s:
            t, s = parent[t], parent[s]
        out[b] = t
    return out


def _parent_depth(tree: ClusterTree):
    n = tree.n_clusters
    parent = np.full(n, -1, np.int64)
    depth = np.zeros(n, np.int64)
    for c in range(n):                  # children have larger indices (a loop over clusters)
        for ch in tree.children[c]:
            if ch >= 0:
                parent[ch] = c
                depth[ch] = depth[c] + 1
    return parent, depth


class _ClusterMeans:
    """X^T r and X y for the indicator functions chi_s e_c of a set of clusters (their
    P_0 coefficients), by prefix sums over the tree positions: vectorised, O(N + #s)."""

    def __init__(self, p0: np.ndarray, npos: int):
        self.p0, self.npos = p0, npos         # p0[pos, c]: the P_0 dof of component c

    def sums(self, R: np.ndarray, lo: np.ndarray, hi: np.ndarray, weights=None
             ) -> np.ndarray:
        """(len(lo), d, q): the sums of R over the P_0 dofs of positions [lo, hi)
        (times ``weights[pos]`` if given)."""
        cs = np.zeros((self.npos + 1,) + self.p0.shape[1:] + R.shape[1:])
        Rp = R[self.p0] if weights is None else R[self.p0] * weights[:, None, None]
        np.cumsum(Rp, axis=0, out=cs[1:])
        return cs[hi] - cs[lo]

    def spread(self, Y: np.ndarray, lo: np.ndarray, hi: np.ndarray, out: np.ndarray):
        """out[P_0 dofs of positions [lo_i, hi_i)] += Y[i] (Y: (len(lo), d, q))."""
        diff = np.zeros((self.npos + 1,) + Y.shape[1:])
        np.add.at(diff, lo, Y)
        np.add.at(diff, hi, -Y)
        out[self.p0] += np.cumsum(diff, axis=0)[:-1]


class Multilevel:
    """The multilevel additive-Schwarz preconditioner of the module doc for the SPD
    H-matrix ``H`` of V (broken W_hp numbering, d components, tree ``tree``, ``layout``
    its :class:`~.matrix.Layout`, ``lengths`` the element lengths in tree order).
    ``solve`` applies C^{-1} to a vector or to the columns of a matrix."""

    def __init__(self, H, tree: ClusterTree, layout, lengths: np.ndarray, d: int,
                 n_coarse: int = N_COARSE):
        self.jacobi = BlockJacobi(H)           # the leaf blocks (the set-up of solvers.py)
        self.n, self.d = H.shape[0], d
        npos = len(layout.off) - 1
        p0 = (layout.off[:-1, None] + np.arange(d)[None, :]).astype(np.int64)
        self.means = _ClusterMeans(p0, npos)
        self.lengths = np.asarray(lengths, float)
        # mean-free leaf blocks: Q (Q^T V_tt Q)^{-1} Q^T = V_tt^{-1} - Z_t G_t^{-1} Z_t^T,
        # Z_t = V_tt^{-1} w_t, G_t = w_t^T Z_t, w_t the mean functionals (L_e at P_0)
        jb = self.jacobi
        self.leaf_lo = np.searchsorted(layout.off, jb.r0s).astype(np.int64)
        self.leaf_hi = np.searchsorted(layout.off, jb.r1s).astype(np.int64)
        by_row = np.argsort(jb.r0s)             # the leaf blocks in dof order
        self.row_leaf = np.repeat(by_row, (jb.r1s - jb.r0s)[by_row])
        Wm = np.zeros((self.n, d))
        Wm[p0, np.arange(d)[None, :]] = self.lengths[:, None]
        self.Z = self.jacobi.solve(Wm)
        Gt = self.means.sums(self.Z, self.leaf_lo, self.leaf_hi, self.lengths)
        self.Gt_inv = np.linalg.inv(0.5 * (Gt + np.transpose(Gt, (0, 2, 1))))
        parent, depth = _parent_depth(tree)
        leaf = tree.children[:, 0] < 0
        lcum = np.concatenate([[0.0], np.cumsum(lengths)])
        size = lcum[tree.stop] - lcum[tree.start]            # |c|
        # cut: the deepest level with at most n_coarse clusters, and the leaves above
        nlev = int(depth.max()) + 1
        counts = np.array([np.sum((depth == l) | (leaf & (depth < l))) for l in range(nlev)])
        L0 = int(np.flatnonzero(counts <= n_coarse).max())
        cut = np.flatnonzero((depth == L0) | (leaf & (depth < L0)))
        haar = np.flatnonzero(~leaf & (depth >= L0))
        self.levels = nlev
        # 1_c^T V 1_c (d x d) for every cluster from the blocks' constant sums
        S = np.zeros((tree.n_clusters, d, d))
        se = np.column_stack([tree.start, tree.stop]).astype(np.int64)
        for near, pairs in ((True, H.near_clusters), (False, H.far_clusters)):
            pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
            if len(pairs) == 0:
                continue
            a = np.empty((len(pairs), d, d))
            if near:
                _block_constant_sums(pairs, se, layout.off, H.near_rng, H.near_off,
                                     H.near_data, d, True, H.near_off, H.near_off,
                                     H.near_off, H.near_data, H.near_data, a)
            else:
                _block_constant_sums(pairs, se, layout.off, H.far_rng, H.near_off,
                                     H.near_data, d, False, H.far_rank, H.far_uoff,
                                     H.far_voff, H.far_U, H.far_V, a)
            if H.symmetric:             # the mirror block (s, t) of an off-diagonal one
                off_diag = pairs[:, 0] != pairs[:, 1]
                a = a + off_diag[:, None, None] * np.transpose(a, (0, 2, 1))
            np.add.at(S, _lca(pairs, parent, depth), a)
        for c in range(tree.n_clusters - 1, 0, -1):          # sub-tree sums, bottom up
            S[parent[c]] += S[c]
        c1, c2 = tree.children[haar, 0], tree.children[haar, 1]
        m1, m2 = size[c1][:, None, None], size[c2][:, None, None]
        G = S[c1] / m1 ** 2 + S[c2] / m2 ** 2 - (S[haar] - S[c1] - S[c2]) / (m1 * m2)
        G = 0.5 * (G + np.transpose(G, (0, 2, 1)))
        ev = np.linalg.eigvalsh(G) if len(G) else np.ones((0, d))
        if len(G) and not np.all(ev > 0.0):
            raise np.linalg.LinAlgError(
                "multilevel preconditioner: a Haar function has energy h^T V h <= 0 "
                f"(min {ev.min():.3e}); V is not SPD on W_hp")
        self.Ginv = np.linalg.inv(G)
        self.h_lo = (tree.start[c1], tree.start[c2])
        self.h_hi = (tree.stop[c1], tree.stop[c2])
        self.h_w = (1.0 / size[c1], -1.0 / size[c2])
        # the coarse space: X^T V X by matvecs of the indicators of the cut
        self.c_lo, self.c_hi = tree.start[cut], tree.stop[cut]
        nc = len(cut) * d
        X_T_VX = np.empty((nc, nc))
        for j0 in range(0, nc, COARSE_CHUNK):
            cols = np.arange(j0, min(nc, j0 + COARSE_CHUNK))
            E = np.zeros((len(cut), d, len(cols)))
            E.reshape(nc, -1)[cols, np.arange(len(cols))] = 1.0
            Xc = np.zeros((self.n, len(cols)))
            self.means.spread(E, self.c_lo, self.c_hi, Xc)
            X_T_VX[:, j0:j0 + len(cols)] = self.means.sums(
                H.matvec(Xc), self.c_lo, self.c_hi).reshape(nc, -1)
        self.coarse = sla.cho_factor(0.5 * (X_T_VX + X_T_VX.T))
        self.n_haar, self.n_cut = len(haar), len(cut)

    def solve(self, x: np.ndarray) -> np.ndarray:
        """C^{-1} x on a vector or on the columns of a matrix."""
        x = np.asarray(x, dtype=float)
        one = x.ndim == 1
        R = x.reshape(self.n, -1)
        m = self.means
        Z = self.jacobi.solve(R)
        g = m.sums(Z, self.leaf_lo, self.leaf_hi, self.lengths)     # w_t^T V_tt^{-1} r
        y = np.einsum("tab,tbq->taq", self.Gt_inv, g)
        Z -= np.einsum("ib,ibq->iq", self.Z, y[self.row_leaf])
        if len(self.Ginv):
            g = sum(w[:, None, None] * m.sums(R, lo, hi)
                    for w, lo, hi in zip(self.h_w, self.h_lo, self.h_hi))
            y = np.einsum("hab,hbq->haq", self.Ginv, g)
            for w, lo, hi in zip(self.h_w, self.h_lo, self.h_hi):
                m.spread(w[:, None, None] * y, lo, hi, Z)
        g = m.sums(R, self.c_lo, self.c_hi)
        y = sla.cho_solve(self.coarse, g.reshape(-1, R.shape[1])).reshape(g.shape)
        m.spread(y, self.c_lo, self.c_hi, Z)
        return Z[:, 0] if one else Z
