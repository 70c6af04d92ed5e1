"""The Newton matrix of a penalty contact problem with sparse bodies on one fixed pattern,
and its sparse LU with the symbolic analysis done once per pattern.

The Newton matrix of Algorithm 4.1 on the free dofs is (Section 4.2.5, (4.36)-(4.37))

    A = K_body + Gn^T W_n Gn + Gt^T (W_t Gt - W_tn Gn),   W = diag(w dp_n), diag(w dt_t),
                                                          diag(w dt_n)

with fixed contact maps Gn, Gt (the Gauss points of the slave segments and their
projections do not move with U).  Its sparsity pattern changes with the active set and
the stick/slip states only through which W vanish, and a plastic body's tangent keeps the
pattern of its stiffness; so the union P of the pattern of K_body and of the contact
terms at *every* point is a superset of every Newton matrix of a load path.
:class:`NewtonMatrix` writes A straight into P (index maps computed once; no scipy
sparse sum, conversion or slicing per Newton step) and :class:`FixedPatternLU` factorises
matrices on P: with PARDISO (MKL through ``pypardiso``, a dependency on x86_64 Linux and
Windows where MKL has wheels; sequential MKL) the ordering and symbolic factorisation of
P once and a numeric factorisation per matrix; without it, SuperLU (``scipy.sparse.linalg.splu``) of each matrix with the
explicit zeros of P dropped (the matrices of the earlier code, to the order of their
sums).  Measured on the stamping systems (8160 dofs, 1.4e5 nonzeros, one thread, loaded
machine): SuperLU 28-31 ms, PARDISO's numeric factorisation 10 ms and solve 1.8 ms
(:data:`PARDISO_IPARM`; analysis 16 ms once); the whole ch4_plasticity__ex1 job 1.4x
less CPU with PARDISO (mkl 2026.2 and pypardiso 0.4.7 from PyPI; results equal to the
Newton tolerance, iteration counts +-1 in a few increments).  Session 19, idle 2-core
machine, one thread: ch4_plasticity__ex1 16.8 s against 27.8 s with SuperLU
(``HPFEBE_PARDISO=0``), the states of both within 7e-8 relative (dev sigma at X).
"""

from __future__ import annotations

import ctypes
import glob
import os
import sys
import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: environment variable: "0" disables PARDISO even when pypardiso is installed
ENV_PARDISO = "HPFEBE_PARDISO"
#: PARDISO's iparm (1-based): MKL's defaults for a real unsymmetric matrix (METIS
#: ordering, pivot perturbation 1e-13, scaling and weighted matching) set explicitly,
#: with iterative refinement off (iparm 8 = 0): with iparm 1 = 0 (all defaults) every
#: solve made two refinement steps, 4.0 ms against 1.8 ms per solve on the stamping
#: systems (8160 dofs), relative residuals 2e-11 either way (the Newton step's residual
#: check of :meth:`hpfebe.contact.loading.LoadSteps._solve_fixed` stays)
PARDISO_IPARM = {1: 1, 2: 2, 8: 0, 10: 13, 11: 1, 13: 1}


def _lookup(P: sp.csr_matrix, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Positions in P.data of the entries (rows, cols) (-1 where a row or col is -1)."""
    L = sp.csr_matrix((np.arange(1, P.nnz + 1, dtype=float), P.indices, P.indptr),
                      shape=P.shape)
    ok = (rows >= 0) & (cols >= 0)
    out = np.full(rows.shape, -1, dtype=np.int64)
    if ok.any():
        out[ok] = np.asarray(L[rows[ok], cols[ok]]).ravel().astype(np.int64) - 1
    if np.any(out[ok] < 0):
        raise ValueError("entry outside the fixed pattern")
    return out


def _rows_padded(G: sp.csr_matrix, local: np.ndarray):
    """(columns (n, k) in the free numbering, -1 for fixed dofs and padding; values
    (n, k)) of the rows of G."""
    G = sp.csr_matrix(G)
    counts = np.diff(G.indptr)
    k = max(int(counts.max(initial=0)), 1)
    cols = np.full((G.shape[0], k), -1, dtype=np.int64)
    vals = np.zeros((G.shape[0], k))
    r = np.repeat(np.arange(G.shape[0]), counts)
    j = np.arange(G.nnz) - G.indptr[r]
    cols[r, j] = local[G.indices]
    vals[r, j] = G.data
    vals[cols < 0] = 0.0
    return cols, vals


class NewtonMatrix:
    """A = K_body + C on the free dofs ``free`` in the fixed pattern (module doc) of the
    body tangent ``K_body`` (its pattern: plastic bodies keep the pattern of their
    stiffness) and of the contact maps ``Gn``, ``Gt`` at all points."""

    def __init__(self, K_body, Gn, Gt, free: np.ndarray):
        n = K_body.shape[0]
        self.free = free
        local = np.full(n, -1, dtype=np.int64)
        local[free] = np.arange(free.size)
        self.local = local
        ones = lambda M: sp.csr_matrix((np.ones(M.nnz), M.indices, M.indptr),  # noqa: E731
                                       shape=M.shape)
        K1, N1, T1 = ones(sp.csr_matrix(K_body)), ones(sp.csr_matrix(Gn)), ones(
            sp.csr_matrix(Gt))
        S = (K1 + N1.T @ N1 + T1.T @ T1 + T1.T @ N1 + N1.T @ T1).tocsr()
        P = S[free][:, free].tocsr()
        P.sort_indices()
        self.P = sp.csr_matrix((np.zeros(P.nnz), P.indices, P.indptr), shape=P.shape)
        self._kmap = None
        gn, vn = _rows_padded(Gn, local)
        gt, vt = _rows_padded(Gt, local)
        self._vn, self._vt = vn, vt
        pair = lambda a, b: _lookup(self.P, np.repeat(a, b.shape[1], axis=1),  # noqa: E731
                                    np.tile(b, (1, a.shape[1]))).reshape(
            a.shape[0], a.shape[1], b.shape[1])
        # entries on a fixed dof or padding (value 0) go to the dump slot P.nnz
        self._pos_nn, self._pos_tt, self._pos_tn = (np.where(q < 0, self.P.nnz, q) for q in
                                                    (pair(gn, gn), pair(gt, gt),
                                                     pair(gt, gn)))

    def _body_map(self, K: sp.csr_matrix):
        """(entries of K.data on free rows and columns, their positions in P), cached
        for K's pattern."""
        km = self._kmap
        if km is not None and km[0].shape == K.indptr.shape and km[1].shape == \
                K.indices.shape and np.array_equal(km[0], K.indptr) and \
                np.array_equal(km[1], K.indices):
            return km[2], km[3]
        r = np.repeat(np.arange(K.shape[0]), np.diff(K.indptr))
        lr, lc = self.local[r], self.local[K.indices]
        sel = np.flatnonzero((lr >= 0) & (lc >= 0))
        pos = _lookup(self.P, lr[sel], lc[sel])
        # a canonical K (no duplicate entries) meets every position of P once: then
        # its entries are stored, not summed (bincount's 0 + x is x: the same numbers)
        ordered = np.sort(pos)
        if np.all(ordered[1:] != ordered[:-1]):
            pos = (pos,)
        self._kmap = (K.indptr.copy(), K.indices.copy(), sel, pos)
        return sel, pos

    def assemble(self, K_body, wn: np.ndarray, wt: np.ndarray, wtn: np.ndarray):
        """A on the free dofs (CSR on the fixed pattern; explicit zeros kept) for the
        body tangent ``K_body`` and the weighted law derivatives w dp_n, w dt_t, w dt_n
        per point."""
        K = K_body if sp.isspmatrix_csr(K_body) or isinstance(K_body, sp.csr_array) \
            else sp.csr_matrix(K_body)
        sel, pos = self._body_map(K)
        m = self.P.nnz + 1                      # the last slot takes fixed dofs' entries
        if isinstance(pos, tuple):              # every position once (:meth:`_body_map`)
            data = np.zeros(m)
            data[pos[0]] = K.data[sel]
        else:
            data = np.bincount(pos, K.data[sel], minlength=m)
        vn, vt = self._vn, self._vt
        for p, a, b, w in ((self._pos_nn, vn, vn, wn), (self._pos_tt, vt, vt, wt),
                           (self._pos_tn, vt, vn, -wtn)):
            act = np.flatnonzero(w)
            if act.size:
                vals = w[act, None, None] * a[act, :, None] * b[act, None, :]
                data += np.bincount(p[act].ravel(), vals.ravel(), minlength=m)
        return sp.csr_matrix((data[:-1], self.P.indices, self.P.indptr),
                             shape=self.P.shape)


def _pardiso_solver():
    """A pypardiso solver with sequential MKL, or None (not installed, or disabled by
    HPFEBE_PARDISO=0)."""
    if os.environ.get(ENV_PARDISO, "1") == "0":
        return None
    if "PYPARDISO_MKL_RT" not in os.environ:
        # pypardiso's own search globs all of sys.prefix recursively (measured 1.5 s per
        # solver); the mkl wheel puts the library in sys.prefix/lib
        found = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*"))
                       + glob.glob(os.path.join(sys.prefix, "Library", "bin", "mkl_rt*")),
                       key=len)
        if found:
            os.environ["PYPARDISO_MKL_RT"] = found[0]
    try:
        from pypardiso import PyPardisoSolver
        s = PyPardisoSolver(mtype=11)             # real unsymmetric
    except (ImportError, OSError):
        return None
    try:                                          # one thread, deterministic
        s.libmkl.MKL_Set_Threading_Layer(ctypes.c_int(1))   # MKL_THREADING_SEQUENTIAL
    except AttributeError:
        pass
    for i, v in PARDISO_IPARM.items():            # (1-based, as in MKL's manual)
        s.iparm[i - 1] = v
    return s


class _PardisoLU:
    """The numeric factorisation of one matrix by a :class:`FixedPatternLU` (valid until
    the next one)."""

    def __init__(self, owner, A):
        self.owner, self.A, self.stamp = owner, A, owner.stamp

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.stamp != self.owner.stamp:
            raise RuntimeError("a later matrix was factorised since")
        return self.owner.pardiso_solve(self.A, b)


class FixedPatternLU:
    """Sparse LU of matrices on one pattern (:class:`NewtonMatrix`): PARDISO's analysis
    once and a numeric factorisation per matrix, or SuperLU per matrix (module doc;
    ``splu_options`` the keywords of splu)."""

    def __init__(self, splu_options: dict):
        self.splu_options = splu_options
        self.pardiso = _pardiso_solver()
        self.analysed = None                # nnz of the analysed pattern
        self.stamp = 0

    def __del__(self):
        s = getattr(self, "pardiso", None)
        if s is not None and self.analysed is not None:
            try:
                s.free_memory(everything=True)      # PARDISO's factors (phase -1)
            except Exception:   # noqa: BLE001 (interpreter shutdown: nothing to free)
                pass

    @property
    def backend(self) -> str:
        return "pardiso" if self.pardiso is not None else "superlu"

    def _call(self, phase: int, A: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
        s = self.pardiso
        s.set_phase(phase)
        return s._call_pardiso(A, b)

    def factor(self, A: sp.csr_matrix):
        """An object with ``solve(b)`` for A (CSR on the fixed pattern)."""
        if self.pardiso is None:
            B = A.tocsc()
            B.eliminate_zeros()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", spla.MatrixRankWarning)
                return spla.splu(B, **self.splu_options)
        s = self.pardiso
        s._check_A(A)                       # CSR: iparm 12 = 0, sorted indices
        zero = np.zeros((A.shape[0], 1))
        if self.analysed is None:           # one pattern per FixedPatternLU
            self._call(11, A, zero)         # ordering and symbolic factorisation
            self.analysed = A.nnz
        elif A.nnz != self.analysed:
            raise ValueError("the matrix is not on the analysed pattern")
        self._call(22, A, zero)             # numeric factorisation
        self.stamp += 1
        return _PardisoLU(self, A)

    def pardiso_solve(self, A, b: np.ndarray) -> np.ndarray:
        rhs = np.asfortranarray(np.asarray(b, dtype=float).reshape(A.shape[0], -1))
        return self._call(33, A, rhs).reshape(np.shape(b))
