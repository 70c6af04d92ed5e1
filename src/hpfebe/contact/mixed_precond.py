"""A block-diagonal multilevel preconditioner of the mixed penalty system (issue 27).

Each semismooth Newton step of :func:`~.matrix_free.solve_penalty_mixed` solves

    [[A, B^T], [B, -V]],   A = W + C_eps   (free dofs of U),

symmetric and indefinite.  Its Schur complement on U is A + B^T V^{-1} B = S_hat + C_eps,
and on the complement of the rigid modes (fixed here by Gamma_D) W and S_hat are
spectrally equivalent (both define the H^{1/2} energy, S_hat = W + B^T V^{-1} B with
B^T V^{-1} B bounded in H^{1/2}).  So the block-diagonal preconditioner

    P = diag(P_A, P_V),   P_A ~ W + C_eps,   P_V ~ V   (spectrally, constants free of h)

gives the preconditioned system eigenvalues in a few h-independent intervals around
+-1 (the standard theory of regularised saddle-point systems), and GMRES (or MINRES)
iterations bounded in N.  The near-field LU of the whole block matrix with a deflation
by chunks of a fixed size does not: its iterations grew from 60-95 (N = 256) to 202-952
(N = 4096), because neither the near field nor one coarse level sees the scales between.

P_V is the multilevel additive-Schwarz preconditioner of V of
:mod:`hpfebe.bem.hmatrix.precond` (mean-free leaf blocks, Haar functions per cluster,
exact coarse cut; both Lame components).  P_A is its counterpart for the order +1
operator W + C_eps on the continuous p = 1 hat functions, a BPX-type additive Schwarz
splitting (Oswald 1998; Tran & Stephan 1996 for the hypersingular operator):

    P_A^{-1} = sum_{groups g} R_g^T (A_n)_gg^{-1} R_g             (fine: exact blocks)
             + sum_{levels l} Z_l D_l^{-1} Z_l^T                  (one hat per level)
             + Z_c (Z_c^T A Z_c)^{-1} Z_c^T                       (coarse, exact)

with the groups of ``group`` consecutive nodes along the curve (their blocks of the
near-field W plus C_eps: principal sub-matrices, exact entries), Z_l the hat functions
on every 2^l-th node (l = 1, 2, ... while more than ``n_coarse`` hats per component;
:func:`~.matrix_free.coarse_space`: piecewise linear in the element count, restricted to
the free dofs), D_l the 2 x 2 (component) diagonal blocks of Z_l^T A Z_l, and Z_c the
first level with at most ``n_coarse`` hats, its Galerkin matrix exact (W by matvecs
of the H-matrix, once; C_eps sparse, every step).  The W part of D_l is measured once
by probing: the hats of one level are coloured by their index mod ``colors`` and W is
applied to the sum of one colour and component; the cross terms between hats of one
colour (at least ``colors`` supports apart) decay like the inverse square distance
(the hats' derivatives are mean-free dipoles), a few per cent of the diagonal, which
a diagonal scaling tolerates.  C_eps's part is exact (sparse).  Set-up: 2 ``colors``
matvecs of W per level plus 2 ``n_coarse``: O(N log N); application O(N log N).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

N_COARSE = 32     # at most this many hats per component on the exact coarse level
GROUP = 8         # nodes per fine block
COLORS = 4        # probing colours of the level diagonals


def _block_diag_2x2(M: sp.spmatrix) -> np.ndarray:
    """(k, 2, 2): the 2 x 2 diagonal blocks of the (2k x 2k) sparse matrix M."""
    M = M.tocoo()
    k = M.shape[0] // 2
    keep = (M.row // 2) == (M.col // 2)
    out = np.zeros((k, 2, 2))
    np.add.at(out, (M.row[keep] // 2, M.row[keep] % 2, M.col[keep] % 2), M.data[keep])
    return out


class PrimalMultilevel:
    """P_A^{-1} of the module doc for A = W + C_eps on the free dofs ``free`` of the
    interleaved V_hp^2 (p = 1).  ``apply_W``: W on (n, q) columns; ``Wn_ff`` the near-
    field W on the free dofs (sparse); ``hats(chunk)``: the hat functions of every
    ``chunk``-th element start, (n, 2k) sparse, both components interleaved;
    ``node_position``: the position along the curve of every free dof's node.
    :meth:`update` sets C_eps and returns the solve."""

    def __init__(self, apply_W, Wn_ff, free, n, hats, node_position, n_nodes,
                 group: int = GROUP, n_coarse: int = N_COARSE, colors: int = COLORS):
        t0 = time.process_time()
        self.free, self.n, self.nf = free, n, len(free)
        self.group = node_position // group
        A = Wn_ff.tocoo()
        inside = self.group[A.row] == self.group[A.col]
        self.Wg = sp.csc_matrix((A.data[inside], (A.row[inside], A.col[inside])),
                                shape=A.shape)
        self.levels: list[sp.csr_matrix] = []
        self.DW: list[np.ndarray] = []
        chunk = 2
        while True:
            Z = self._restricted(hats(chunk))
            if Z.shape[1] <= 2 * n_coarse or chunk >= n_nodes:
                break
            self.levels.append(Z)
            self.DW.append(self._probe(apply_W, Z, colors))
            chunk *= 2
        self.Zc = Z
        Xc = self._embed(Z.toarray())
        self.ZcWZc = Z.T @ apply_W(Xc)[free]
        self.ZcWZc = 0.5 * (self.ZcWZc + self.ZcWZc.T)
        self.n_levels = len(self.levels)
        self.setup_s = time.process_time() - t0

    def _restricted(self, Zu):
        Z = Zu[self.free].tocsc()
        Z.eliminate_zeros()                 # the stored zeros of a hat's far end
        return Z[:, np.flatnonzero(np.diff(Z.indptr))].tocsr()

    def _embed(self, X):
        out = np.zeros((self.n,) + X.shape[1:])
        out[self.free] = X
        return out

    def _probe(self, apply_W, Z, colors):
        """(k, 2, 2): the W part of D_l by coloured probing (module doc)."""
        k = Z.shape[1] // 2
        color = np.arange(k) % colors
        pick = sp.csr_matrix((np.ones(2 * k), (np.arange(2 * k),
                              2 * color.repeat(2) + np.tile([0, 1], k))),
                             shape=(2 * k, 2 * colors))
        Y = apply_W(self._embed((Z @ pick).toarray()))[self.free]       # (nf, 2 colors)
        ZY = Z.T @ Y                                                     # (2k, 2 colors)
        rows = np.arange(2 * k)
        D = np.empty((k, 2, 2))
        for c in range(2):                  # the component of the probing vector
            D[:, :, c] = ZY[rows, 2 * color.repeat(2) + c].reshape(k, 2)
        return 0.5 * (D + np.transpose(D, (0, 2, 1)))

    def update(self, Cff: sp.spmatrix):
        """The solve of P_A with the penalty Jacobian ``Cff`` (free dofs)."""
        fine = spla.splu(self._fine(Cff), permc_spec="COLAMD")
        blocks = []
        for Z, DW in zip(self.levels, self.DW):
            D = DW + _block_diag_2x2(Z.T @ Cff @ Z)
            blocks.append(np.linalg.inv(D))
        Zall = sp.hstack(self.levels, format="csr") if self.levels else None
        Dinv = sp.block_diag(np.concatenate(blocks), format="csr") if blocks else None
        Gc = self.ZcWZc + (self.Zc.T @ Cff @ self.Zc).toarray()
        coarse = sla.cho_factor(0.5 * (Gc + Gc.T))
        Zc = self.Zc

        def solve(r):
            y = fine.solve(r)
            if Zall is not None:
                y += Zall @ (Dinv @ (Zall.T @ r))
            return y + Zc @ sla.cho_solve(coarse, Zc.T @ r)
        return solve

    def _fine(self, Cff):
        C = Cff.tocoo()
        inside = self.group[C.row] == self.group[C.col]
        Cg = sp.csc_matrix((C.data[inside], (C.row[inside], C.col[inside])),
                           shape=C.shape)
        return (self.Wg + Cg).tocsc()
