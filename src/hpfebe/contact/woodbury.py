"""Newton systems of linear bodies in contact by one factorisation per body and the
Sherman-Morrison-Woodbury formula (:class:`WoodburySolver`), with the factorisation of
a body's stiffness by PARDISO (Cholesky with partial solves on the contact dofs,
:class:`PardisoBody`) or by SuperLU (:class:`SuperLUBody`).

Measured on the largest body of the adaptive FE/FE scene (65792 dofs, 132 contact dofs,
one thread): SuperLU ordering 0.06 s, factorisation 0.37 s, solve 11.5 ms; PARDISO
Cholesky 0.18 s, full solve 4.4 ms, the contact part (K^{-1} b)_c of a solve 2.2 ms,
(K^{-1})_cc by 132 partial solves 0.10 s; the two agree to 3e-12 relative."""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..solvers import SingularStep
from .newton_matrix import _pardiso_solver

#: the backends of :class:`WoodburySolver` (None: PARDISO where pypardiso is installed)
BODY_BACKENDS = ("pardiso", "superlu")


class SuperLUBody:
    """Sparse LU of one body's stiffness Kb (symmetric positive definite on its free
    dofs), the contact dofs ``c`` ordered last: minimum degree on Kb for the others, so
    that the trailing block of the factors is the Schur complement
    S = K_cc - K_ci K_ii^{-1} K_ic and (K^{-1})_cc = S^{-1} needs no solves."""

    backend = "superlu"

    def __init__(self, Kb: sp.csc_matrix, c: np.ndarray):
        n = Kb.shape[0]
        self.c, self.lu, self.from_factors = c, None, True
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", spla.MatrixRankWarning)
            try:
                # the minimum degree order of Kb (an incomplete LU that drops every
                # entry returns it at the cost of the ordering)
                seq = np.argsort(spla.spilu(Kb, drop_tol=1e300, fill_factor=1,
                                            permc_spec="MMD_AT_PLUS_A",
                                            diag_pivot_thresh=0.0,
                                            options=dict(SymmetricMode=True)).perm_c)
                is_c = np.zeros(n, dtype=bool)
                is_c[c] = True
                self.p = np.concatenate([seq[~is_c[seq]], c])
                Kp = Kb[self.p][:, self.p].tocsc()
                Kp.sort_indices()
                self.lu = spla.splu(Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                    options=dict(SymmetricMode=True))
            except RuntimeError:           # singular: reported at the first solve
                self.kinv_cc = np.zeros((c.size, c.size))
                return
        self.kinv_cc = self._kinv_trailing(self.lu, n, c.size)

    def _kinv_trailing(self, lu, n: int, m: int) -> np.ndarray:
        """(Kp^{-1}) on the last m unknowns: the inverse of the Schur complement, the
        trailing block L_tt U_tt of the factors when SuperLU kept those unknowns last
        (its elimination-tree postorder may move them; then m solves)."""
        t = n - m
        self.from_factors = bool(np.all(lu.perm_c[t:] >= t) and np.all(lu.perm_r[t:] >= t))
        if m == 0:
            return np.zeros((0, 0))
        if self.from_factors:
            L = lu.L[:, t:].tocsr()[t:].toarray()
            U = lu.U[:, t:].tocsr()[t:].toarray()
            T = L @ U                       # LU[perm_r[j], perm_c[k]] = Kp[j, k]
            S = T[np.ix_(lu.perm_r[t:] - t, lu.perm_c[t:] - t)]
            return sla.inv(S)
        E = np.zeros((n, m))
        E[t + np.arange(m), np.arange(m)] = 1.0
        return lu.solve(E)[t:]

    def kinv_columns(self, j: np.ndarray) -> np.ndarray:
        """(K^{-1})_cc[:, j] (from the factors)."""
        return self.kinv_cc[:, j]

    def solve(self, b: np.ndarray) -> np.ndarray:
        """K^{-1} b."""
        if self.lu is None:
            raise SingularStep("singular body stiffness (a body not held by Dirichlet "
                               "conditions?): use linear_solver='lu'")
        x = np.empty_like(b)
        x[self.p] = self.lu.solve(np.ascontiguousarray(b[self.p]))
        return x

    def solve_c(self, b: np.ndarray) -> np.ndarray:
        """(K^{-1} b)_c (a full solve)."""
        return self.solve(b)[self.c]


class PardisoBody:
    """PARDISO's Cholesky factorisation of one body's stiffness Kb (matrix type 2, its
    upper triangle), with the contact dofs ``c`` marked in ``perm`` for the partial
    solves of MKL's iparm 31: (K^{-1} b)_c of a full b (mode 3, half a solve) and
    columns of (K^{-1})_cc from unit vectors on c (mode 1, the contact rows only: 0.4 ms
    per column against 4.4 ms for a solve), computed when a step first needs them
    (:meth:`kinv_columns`: the dofs of points that never touch cost nothing).
    ``solver``: a fresh solver of :func:`~hpfebe.contact.newton_matrix._pardiso_solver`."""

    backend = "pardiso"
    from_factors = False
    #: columns of (K^{-1})_cc per partial solve: at most this many entries of n x k (8 MB;
    #: 0.23 s for the 65792-dof body against 0.39 s with 8e6, larger blocks miss the cache)
    BLOCK_ENTRIES = 1_000_000

    def __init__(self, Kb: sp.spmatrix, c: np.ndarray, solver):
        n = Kb.shape[0]
        self.c, self.n = c, n
        s = self.pardiso = solver
        s.set_matrix_type(2)                # real symmetric positive definite
        s.perm = np.zeros(n, dtype=np.int32)
        s.perm[c] = 1
        self.A = sp.triu(Kb, format="csr")
        self.A.sort_indices()
        self.singular = False
        try:
            self._call(12, 1, np.zeros((n, 1)))   # (analysis with iparm 31 != 0)
        except Exception:  # noqa: BLE001 (PyPardisoError: not positive definite)
            self.singular = True

    def kinv_columns(self, j: np.ndarray) -> np.ndarray:
        """(K^{-1})_cc[:, j] (``j`` positions in c), by partial solves."""
        self._check()
        n, c = self.n, self.c
        out = np.empty((c.size, j.size))
        k = max(1, self.BLOCK_ENTRIES // max(n, 1))
        for lo in range(0, j.size, k):
            cols = np.arange(lo, min(lo + k, j.size))
            E = np.zeros((n, cols.size), order="F")
            E[c[j[cols]], np.arange(cols.size)] = 1.0
            out[:, cols] = self._call(33, 1, E)[c]
        return out

    def __del__(self):
        s = getattr(self, "pardiso", None)
        if s is not None:
            try:
                s.free_memory(everything=True)      # PARDISO's factors (phase -1)
            except Exception:   # noqa: BLE001 (interpreter shutdown: nothing to free)
                pass

    def _call(self, phase: int, mode: int, b: np.ndarray) -> np.ndarray:
        s = self.pardiso
        s.set_phase(phase)
        s.set_iparm(31, mode)
        return s._call_pardiso(self.A, np.asfortranarray(b.reshape(self.n, -1)))

    def _check(self):
        if self.singular:
            raise SingularStep("singular body stiffness (a body not held by Dirichlet "
                               "conditions?): use linear_solver='lu'")

    def solve(self, b: np.ndarray) -> np.ndarray:
        """K^{-1} b."""
        self._check()
        return self._call(33, 0, b).reshape(b.shape)

    def solve_c(self, b: np.ndarray) -> np.ndarray:
        """(K^{-1} b)_c."""
        self._check()
        return self._call(33, 3, b).reshape(b.shape)[self.c]


def body_factor(Kb: sp.spmatrix, c: np.ndarray, backend: str | None = None):
    """The factorisation of one body's stiffness with contact dofs ``c``: PARDISO
    (:class:`PardisoBody`) if ``backend`` is "pardiso", or None and pypardiso is
    installed; else SuperLU (:class:`SuperLUBody`)."""
    if backend not in (None,) + BODY_BACKENDS:
        raise ValueError(f"backend must be one of {BODY_BACKENDS} or None, got {backend!r}")
    solver = None if backend == "superlu" else _pardiso_solver()
    if solver is not None:
        return PardisoBody(Kb, c, solver)
    if backend == "pardiso":
        raise RuntimeError("backend='pardiso' needs pypardiso (not installed, or "
                           "HPFEBE_PARDISO=0)")
    return SuperLUBody(sp.csc_matrix(Kb), c)


class WoodburySolver:
    """Newton systems (K + C) d = r of linear bodies on the free dofs, C = B^T M B the
    linearised contact terms of Section 4.2.5 (B = [G_n; G_t] on the points where the
    law has a derivative, M = [[W_n, 0], [-W_tn, W_t]]), by

        (K + B^T M B)^{-1} = K^{-1} - K^{-1} B^T (I + M B K^{-1} B^T)^{-1} M B K^{-1}

    (Sherman-Morrison-Woodbury, push-through form: M may be singular, e.g. W_t = 0 on
    slipping points).  K = blockdiag(K^s, K^m) is factorised once per body
    (:func:`body_factor`) with (K^{-1})_cc on its contact dofs c (all dofs a contact
    point touches), so that B K^{-1} B^T = B_c (K^{-1})_cc B_c^T needs no solves.  A
    Newton step is d = K^{-1} (r - B^T s), s = (I + M H)^{-1} M B (K^{-1} r) with
    H = B K^{-1} B^T: the contact part (K^{-1} r)_c and one solve per body; the same
    Newton steps as a sparse LU of K + C, up to round-off.  ``K`` the body tangent on all
    dofs, ``free`` the free dofs, ``offset`` the first master dof, ``Gn``, ``Gt`` the
    maps U -> dg_n, dg_t at all contact points, ``backend`` that of :func:`body_factor`."""

    #: the dense (K^{-1})_cc has this many rows at most (8e3: 0.5 GB)
    MAX_CONTACT_DOFS = 8000

    def __init__(self, K, free: np.ndarray, offset: int, Gn, Gt, backend: str | None = None):
        self.K = K
        Kf = sp.csr_matrix(K)[free][:, free].tocsc()
        self.Kf = Kf
        self.n = free.size
        self.Gn, self.Gt = (sp.csr_matrix(G)[:, free] for G in (Gn, Gt))
        # the contact dofs: all dofs touched by a contact point (free numbering)
        self.rows = np.unique(np.concatenate([self.Gn.indices, self.Gt.indices]))
        if self.rows.size > self.MAX_CONTACT_DOFS:
            raise ValueError(f"{self.rows.size} contact dofs: too many for the dense "
                             f"(K^-1)_cc (at most {self.MAX_CONTACT_DOFS}); use "
                             "linear_solver='lu'")
        self.row_pos = np.full(self.n, -1, dtype=np.int64)
        self.row_pos[self.rows] = np.arange(self.rows.size)
        # [Gn; Gt] on the contact dofs (columns: positions in rows): B of a step is a
        # row selection, B (K^-1)_cc B^T costs nnz(B) (contact dofs + 2 m) flops
        self.npts = self.Gn.shape[0]
        self.G_c = sp.vstack([self.Gn, self.Gt]).tocsc()[:, self.rows].tocsr()
        # the body blocks of K on the free dofs (no coupling between the bodies in K)
        split = int(np.searchsorted(free, offset))
        if 0 < split < self.n and (Kf[:split][:, split:].count_nonzero() or
                                   Kf[split:][:, :split].count_nonzero()):
            raise ValueError("K couples the bodies: no factorisation body by body")
        # (K^{-1})_cc, its columns filled when first needed (:meth:`_need`; zero between
        # the bodies)
        self.kinv_cc = np.zeros((self.rows.size, self.rows.size))
        self.known = np.zeros(self.rows.size, dtype=bool)
        self.body_of = np.zeros(self.rows.size, dtype=np.int64)
        self.blocks = []                 # per body: (slice, contact positions, factor)
        for lo, hi in ((0, split), (split, self.n)):
            if hi > lo:
                c = self.rows[(self.rows >= lo) & (self.rows < hi)] - lo
                f = body_factor(Kf[lo:hi][:, lo:hi], c, backend)
                pos = self.row_pos[c + lo]
                self.body_of[pos] = len(self.blocks)
                self.blocks.append((slice(lo, hi), pos, f))

    def _need(self, a: np.ndarray) -> None:
        """The columns ``a`` (positions in ``rows``) of (K^{-1})_cc computed."""
        new = a[~self.known[a]]
        if new.size == 0:
            return
        for b, (_, pos, f) in enumerate(self.blocks):
            j = new[self.body_of[new] == b]
            if j.size:
                local = np.searchsorted(pos, j)      # pos is increasing (rows sorted)
                self.kinv_cc[np.ix_(pos, j)] = f.kinv_columns(local)
        self.known[new] = True

    @property
    def from_factors(self) -> list:
        """Per body: (K^{-1})_cc from the trailing block of SuperLU's factors (else by
        solves)."""
        return [f.from_factors for _, _, f in self.blocks]

    def _kinv(self, R: np.ndarray) -> np.ndarray:
        """K^{-1} R (R: (n,) or (n, k)), body by body."""
        out = np.empty_like(R)
        for sl, _, f in self.blocks:
            out[sl] = f.solve(np.ascontiguousarray(R[sl]))
        return out

    def _kinv_c(self, r: np.ndarray) -> np.ndarray:
        """(K^{-1} r) on the contact dofs (in the order of ``rows``)."""
        out = np.empty(self.rows.size)
        for sl, pos, f in self.blocks:
            out[pos] = f.solve_c(np.ascontiguousarray(r[sl]))
        return out

    def _columns(self, dofs: np.ndarray) -> np.ndarray:
        """(K^{-1})[dofs, dofs] (``dofs`` among the contact dofs)."""
        pos = self.row_pos[dofs]
        self._need(np.unique(pos))
        return self.kinv_cc[np.ix_(pos, pos)]

    def solve(self, wn: np.ndarray, wt: np.ndarray, wtn: np.ndarray,
              r: np.ndarray) -> np.ndarray:
        """d with (K + Gn^T W_n Gn + Gt^T (W_t Gt - W_tn Gn)) d = r on the free dofs,
        W = diag(wn), diag(wt), diag(wtn) (the law derivatives times the weights)."""
        act = np.flatnonzero((wn != 0) | (wt != 0) | (wtn != 0))
        if act.size == 0:
            return self._kinv(r)
        m = act.size
        # B = [Gn; Gt] on the active points, on the contact dofs (sparse)
        B = self.G_c[np.concatenate([act, act + self.npts])]
        # B (K^-1)_cc B^T on the contact dofs the active points touch (a)
        a = np.unique(B.indices)
        self._need(a)
        Ba = B[:, a]
        H = Ba @ (Ba @ self.kinv_cc[np.ix_(a, a)].T).T
        # M H and M B y with M = [[W_n, 0], [-W_tn, W_t]] (diagonal blocks): row scalings
        an, at, atn = wn[act], wt[act], wtn[act]
        MH = np.concatenate([an[:, None] * H[:m], -atn[:, None] * H[:m] + at[:, None] * H[m:]])
        By = B @ self._kinv_c(r)
        MBy = np.concatenate([an * By[:m], -atn * By[:m] + at * By[m:]])
        MH[np.arange(2 * m), np.arange(2 * m)] += 1.0
        try:
            # (numpy's solve: no condition estimate, the residual check of the step
            # judges the result; a third to a half of scipy's overhead)
            s = np.linalg.solve(MH, MBy)
        except (np.linalg.LinAlgError, ValueError):
            raise SingularStep("singular Newton matrix (contact update of the "
                               "Woodbury formula)") from None
        Bs = np.zeros(self.n)
        Bs[self.rows] = B.T @ s
        return self._kinv(r - Bs)

    def matvec(self, wn, wt, wtn, d: np.ndarray) -> np.ndarray:
        """(K + C) d on the free dofs (the residual check of a solve)."""
        gn, gt = self.Gn @ d, self.Gt @ d
        return self.Kf @ d + self.Gn.T @ (wn * gn) + self.Gt.T @ (wt * gt - wtn * gn)
