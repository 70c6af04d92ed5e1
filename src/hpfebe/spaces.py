"""hp boundary element spaces on a :class:`~hpfebe.geometry.BoundaryMesh`.

Reference element: ``t`` in [-1, 1], mapped affinely onto ``I = [a_I, b_I]``
(``x = a_I + (t+1)/2 (b_I - a_I)``, ``ds = |I|/2 dt``).

* ``V_hp`` (:class:`ContinuousSpace`): continuous piecewise polynomials of degree p_I.
  Local basis: the Lagrange polynomials l_0..l_p at the p+1 Gauss-Lobatto points of
  [-1, 1]; l_0 and l_p are the vertex functions (shared with the neighbours), l_1..l_{p-1}
  are interior.  ``zero_on=("D",)`` drops every function that does not vanish on the
  elements with those labels: the space H~^(1/2) of the complementary part.
* ``W_hp`` (:class:`DiscontinuousSpace`): piecewise polynomials of degree p_I - 1, no
  continuity.  Local basis: Legendre polynomials P_0..P_{p_I-1}.

Global numbering of V_hp: vertex functions first (in node order), then the interior
functions element by element.  ``elem_dofs[e, j]`` is the global index of local function
j on element e, -1 for padding or for a function removed by ``zero_on``.  Vector fields
(V_hp^2, W_hp^2) interleave the components: dof 2 d + c.

Basis values at points: :meth:`_Space.trace_matrix` (sparse, scalar or interleaved
vector).  Nested meshes: :func:`prolongate` writes a function of a coarse mesh exactly in
the space of a refinement (parent maps of :meth:`BoundaryMesh.refine`, or geometry).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from numba import njit
from numpy.polynomial import legendre as npleg

from .geometry import BoundaryMesh
from .quadrature import gauss_legendre, gauss_lobatto

__all__ = ["ContinuousSpace", "DiscontinuousSpace", "prolongate", "containing_elements",
           "lagrange_values", "legendre_values", "gll_tables", "eval_basis", "n_local",
           "P_MAX", "LEGENDRE", "LAGRANGE_GLL"]

P_MAX = 24  # largest supported polynomial degree

LEGENDRE, LAGRANGE_GLL = 0, 1  # basis kinds understood by the numba kernels


@lru_cache(maxsize=None)
def gll_tables(pmax: int = P_MAX):
    """Gauss-Lobatto nodes ``x[p, :p+1]`` and barycentric weights ``b[p, :p+1]``."""
    x = np.zeros((pmax + 1, pmax + 1))
    b = np.zeros((pmax + 1, pmax + 1))
    for p in range(1, pmax + 1):
        xp, _ = gauss_lobatto(p + 1)
        diff = xp[:, None] - xp[None, :]
        np.fill_diagonal(diff, 1.0)
        bp = 1.0 / np.prod(diff, axis=1)
        x[p, :p + 1] = xp
        b[p, :p + 1] = bp / np.abs(bp).max()
    x.setflags(write=False)
    b.setflags(write=False)
    return x, b


@njit(cache=True, inline="always")
def n_local(kind, p):
    """Number of local basis functions of a basis kind on an element of degree p."""
    return p if kind == 0 else p + 1


@njit(cache=True, inline="always")
def eval_basis(kind, p, t, gll_x, gll_b, out):
    """Values of the local basis at the reference point t: Legendre P_0..P_{p-1}
    (kind 0) or the Gauss-Lobatto Lagrange polynomials of degree p (kind 1)."""
    if kind == 0:
        out[0] = 1.0
        if p > 1:
            out[1] = t
        for k in range(2, p):
            out[k] = ((2 * k - 1) * t * out[k - 1] - (k - 1) * out[k - 2]) / k
        return
    hit = -1
    for j in range(p + 1):
        if t == gll_x[p, j]:
            hit = j
    if hit >= 0:
        for j in range(p + 1):
            out[j] = 0.0
        out[hit] = 1.0
        return
    s = 0.0
    for j in range(p + 1):
        out[j] = gll_b[p, j] / (t - gll_x[p, j])
        s += out[j]
    for j in range(p + 1):
        out[j] /= s


def _degree(p, minimum: int = 1) -> int:
    """``p`` as an int >= ``minimum``; ValueError for booleans and non-integers (never
    truncated: 2.7 is not 2, True is not 1)."""
    if (isinstance(p, (bool, np.bool_))
            or not isinstance(p, (int, float, np.integer, np.floating))
            or not np.isfinite(p) or p != int(p) or p < minimum):
        raise ValueError(f"degree p must be an integer >= {minimum}, got {p!r}")
    return int(p)


def lagrange_values(p: int, t: np.ndarray, derivative: bool = False) -> np.ndarray:
    """GLL Lagrange basis of degree p at points t, shape (len(t), p+1) (numpy)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    coef = _lagrange_legendre_coef(_degree(p), bool(derivative))
    return npleg.legvander(t, coef.shape[0] - 1) @ coef


@lru_cache(maxsize=None)
def _lagrange_legendre_coef(p: int, derivative: bool) -> np.ndarray:
    """Legendre coefficients of the GLL Lagrange polynomials l_j (column j) of degree p,
    or of their derivatives."""
    xp, _ = gauss_lobatto(p + 1)
    # coefficients of each l_j in the Legendre basis by exact interpolation at the nodes
    vand = npleg.legvander(xp, p)
    coef = np.linalg.solve(vand, np.eye(p + 1))  # column j: Legendre coeffs of l_j
    if derivative:
        coef = npleg.legder(coef, axis=0)
    coef.setflags(write=False)
    return coef


def legendre_values(p: int, t: np.ndarray, derivative: bool = False) -> np.ndarray:
    """Legendre P_0..P_{p-1} at points t, shape (len(t), p) (numpy)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    p = _degree(p)
    coef = np.eye(p)
    if derivative:
        der = np.zeros((p, p))
        d = npleg.legder(coef, axis=0)      # (max(p - 1, 1), p): a constant's is [0]
        der[:p - 1] = d[:p - 1]
        return npleg.legvander(t, p - 1) @ der
    return npleg.legvander(t, p - 1)


class _Space:
    kind: int
    mesh: BoundaryMesh
    elem_dofs: np.ndarray
    ndof: int

    def local_degree(self) -> np.ndarray:
        """Polynomial degree of the functions on each element."""
        raise NotImplementedError

    def _values(self, p: int, t, derivative=False):
        raise NotImplementedError

    def trace_matrix(self, elem, t, components: int = 1,
                     derivative: bool = False) -> sp.csr_matrix:
        """Sparse matrix of the basis values (or arc-length derivatives d/ds) at the points
        of reference coordinates ``t[i]`` (in [-1, 1]) on the elements ``elem[i]``.

        ``components=1``: shape (n, ndof), entry [i, dof].  ``components=2``: the
        interleaved vector version (row 2 i + c, column 2 dof + c), shape (2n, 2 ndof),
        so that ``trace_matrix(elem, t, 2) @ U`` are the interleaved values of U in
        V_hp^2 (or W_hp^2)."""
        if components not in (1, 2):
            raise ValueError(f"components must be 1 or 2, got {components!r}")
        elem = np.atleast_1d(np.asarray(elem))
        if elem.ndim != 1 or (elem.size and not np.issubdtype(elem.dtype, np.integer)):
            raise ValueError("elem must be a 1D array of element indices")
        ne = self.mesh.n_elements
        if elem.size and (elem.min() < 0 or elem.max() >= ne):
            raise ValueError(f"elem must lie in 0..{ne - 1}")
        t = np.broadcast_to(np.asarray(t, dtype=float), elem.shape)
        if t.size and np.max(np.abs(t)) > 1.0 + 1e-12:
            raise ValueError("t must lie in [-1, 1]")
        n = len(elem)
        rows, cols, vals = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)], [np.zeros(0)]
        degrees = self.mesh.degrees[elem]
        for p in np.unique(degrees):
            sel = np.flatnonzero(degrees == p)
            phi = self._values(int(p), t[sel], derivative)          # (k, nloc)
            if derivative:
                phi = phi * (2.0 / self.mesh.lengths[elem[sel]])[:, None]
            dofs = self.elem_dofs[elem[sel], :phi.shape[1]]
            keep = dofs >= 0
            rows.append(np.broadcast_to(sel[:, None], dofs.shape)[keep])
            cols.append(dofs[keep])
            vals.append(phi[keep])
        r, c, v = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
        if components == 2:
            r = np.concatenate([2 * r, 2 * r + 1])
            c = np.concatenate([2 * c, 2 * c + 1])
            v = np.concatenate([v, v])
        return sp.csr_matrix((v, (r, c)), shape=(components * n, components * self.ndof))

    def evaluate(self, coeffs, elem, t, derivative: bool = False) -> np.ndarray:
        """Values (or arc-length derivatives d/ds) of the discrete function with
        coefficients ``coeffs`` at reference points ``t`` of elements ``elem``."""
        coeffs = np.asarray(coeffs)
        if coeffs.shape[0] != self.ndof:
            raise ValueError(f"coeffs must have {self.ndof} entries, got {coeffs.shape[0]}")
        elem = np.atleast_1d(np.asarray(elem))
        t = np.broadcast_to(np.asarray(t, dtype=float), elem.shape)
        out = np.zeros(elem.shape + coeffs.shape[1:])
        cpad = np.concatenate([coeffs, np.zeros((1,) + coeffs.shape[1:])])
        L = self.mesh.lengths
        for p in np.unique(self.mesh.degrees[elem]):
            sel = self.mesh.degrees[elem] == p
            vals = self._values(int(p), t[sel], derivative)  # (npts, nloc)
            dofs = self.elem_dofs[elem[sel], :vals.shape[1]]
            c = cpad[np.where(dofs < 0, -1, dofs)]
            v = np.einsum("qj,qj...->q...", vals, c)
            if derivative:
                v = v * (2.0 / L[elem[sel]]).reshape((-1,) + (1,) * (v.ndim - 1))
            out[sel] = v
        return out


    def evaluate_at(self, coeffs, points, tol: float = 5e-11) -> np.ndarray:
        """Values of the discrete function at physical ``points`` (n, 2) lying on the
        boundary (:meth:`BoundaryMesh.locate`); NaN rows for points not on it."""
        coeffs = np.asarray(coeffs)
        elem, t = self.mesh.locate(points, tol)
        out = np.full((len(elem),) + coeffs.shape[1:], np.nan)
        on = elem >= 0
        if np.any(on):
            out[on] = self.evaluate(coeffs, elem[on], t[on])
        return out


class DiscontinuousSpace(_Space):
    """W_hp: Legendre P_0..P_{p_I-1} on each element (degree p_I - 1)."""

    kind = LEGENDRE

    def __init__(self, mesh: BoundaryMesh):
        self.mesh = mesh
        nloc = mesh.degrees
        self.offsets = np.concatenate([[0], np.cumsum(nloc)])
        self.ndof = int(self.offsets[-1])
        pmax = int(nloc.max())
        j = np.arange(pmax)
        dofs = self.offsets[:-1, None] + j[None, :]
        self.elem_dofs = np.where(j[None, :] < nloc[:, None], dofs, -1).astype(np.int64)

    def local_degree(self):
        return self.mesh.degrees - 1

    def _values(self, p, t, derivative=False):
        return legendre_values(p, t, derivative)

    def project(self, f) -> np.ndarray:
        """L2 projection of f(x) (x of shape (n, 2)) onto W_hp, element by element."""
        mesh = self.mesh
        coeffs = np.zeros(self.ndof)
        for p in np.unique(mesh.degrees):
            els = np.flatnonzero(mesh.degrees == p)
            xq, wq = gauss_legendre(int(p) + 8)
            pts = mesh.points(els[:, None], xq[None, :])
            fv = np.asarray(f(pts.reshape(-1, 2)), dtype=float).reshape(len(els), len(xq))
            P = legendre_values(int(p), xq)  # (nq, p)
            k = np.arange(int(p))
            c = (fv * wq) @ P * ((2 * k + 1) / 2.0)
            coeffs[self.elem_dofs[els, :p]] = c
        return coeffs


class ContinuousSpace(_Space):
    """V_hp: continuous, GLL-nodal Lagrange basis of degree p_I on each element."""

    kind = LAGRANGE_GLL

    def __init__(self, mesh: BoundaryMesh, zero_on: tuple[str, ...] | None = None):
        self.mesh = mesh
        self.zero_on = tuple(zero_on or ())
        ne = mesh.n_elements
        p = mesh.degrees
        pmax = int(p.max())
        used = np.unique(mesh.elements)
        vertex_id = -np.ones(len(mesh.nodes), dtype=np.int64)
        vertex_id[used] = np.arange(len(used))
        n_int = p - 1
        int_off = len(used) + np.concatenate([[0], np.cumsum(n_int)])
        j = np.arange(pmax + 1)
        dofs = int_off[:-1, None] + j[None, :] - 1
        dofs = np.where((j[None, :] >= 1) & (j[None, :] < p[:, None]), dofs, -1)
        dofs[:, 0] = vertex_id[mesh.elements[:, 0]]
        dofs[np.arange(ne), p] = vertex_id[mesh.elements[:, 1]]
        ndof = int(int_off[-1])
        if self.zero_on:
            fixed = np.zeros(ndof, dtype=bool)
            on = mesh.where(*self.zero_on)
            fixed[dofs[on][dofs[on] >= 0]] = True
            renum = -np.ones(ndof + 1, dtype=np.int64)
            renum[:-1][~fixed] = np.arange(int((~fixed).sum()))
            dofs = renum[dofs]  # -1 maps to renum[-1] == -1
            ndof = int((~fixed).sum())
        self.elem_dofs = np.ascontiguousarray(dofs, dtype=np.int64)
        self.ndof = ndof

    def local_degree(self):
        return self.mesh.degrees

    def _values(self, p, t, derivative=False):
        return lagrange_values(p, t, derivative)

    def dofs_on(self, *labels: str) -> np.ndarray:
        """Global dofs whose basis functions do not vanish on elements with ``labels``
        (closure: vertex functions at the ends of those parts included)."""
        on = self.mesh.where(*labels)
        d = self.elem_dofs[on]
        return np.unique(d[d >= 0])

    def free_dofs(self, *labels: str, components: int = 1) -> np.ndarray:
        """Sorted dofs whose basis functions vanish on the (closed) elements carrying
        ``labels`` (default the Dirichlet label "D"); for ``components=2`` the interleaved
        vector dofs 2 d + c."""
        if components not in (1, 2):
            raise ValueError(f"components must be 1 or 2, got {components!r}")
        labels = labels or ("D",)
        free = np.setdiff1d(np.arange(self.ndof), self.dofs_on(*labels))
        if components == 2:
            free = np.column_stack([2 * free, 2 * free + 1]).ravel()
        return free

    def interpolate(self, f) -> np.ndarray:
        """Nodal interpolant of f(x) at the Gauss-Lobatto points of each element."""
        mesh = self.mesh
        coeffs = np.zeros(self.ndof)
        for p in np.unique(mesh.degrees):
            els = np.flatnonzero(mesh.degrees == p)
            xp, _ = gauss_lobatto(int(p) + 1)
            pts = mesh.points(els[:, None], xp[None, :]).reshape(-1, 2)
            fv = np.asarray(f(pts), dtype=float).reshape(len(els), int(p) + 1)
            d = self.elem_dofs[els, :int(p) + 1]
            coeffs[d[d >= 0]] = fv[d >= 0]
        return coeffs

    def derivative_matrix(self, W: DiscontinuousSpace) -> sp.csr_matrix:
        """Sparse T (W.ndof x self.ndof): W_hp coefficients of the arc-length derivative
        dU/ds of U in V_hp.  Exact, since d/ds maps degree p_I to p_I - 1.  Used for the
        hypersingular operator <W U, U'> = <V dU/ds, dU'/ds>."""
        return self._local_to_W(W, derivative=True)

    def mass_matrix(self, W: DiscontinuousSpace) -> sp.csr_matrix:
        """Sparse M (W.ndof x self.ndof), M[k, j] = int_Gamma Phi_k U_j ds."""
        return self._local_to_W(W, derivative=False)

    def _local_to_W(self, W: DiscontinuousSpace, derivative: bool) -> sp.csr_matrix:
        if W.mesh is not self.mesh:
            raise ValueError("W must live on the same mesh as this space")
        mesh = self.mesh
        pmax = int(mesh.degrees.max())
        # the CSR arrays directly (a row per W_hp dof, its element's V_hp dofs sorted):
        # the entries of a COO construction without its conversion (~60 us of 90 for a
        # 16-element mesh, issue 14)
        indptr, indices, data, repeated = _local_to_W_csr(
            self.elem_dofs, W.elem_dofs, mesh.degrees, mesh.lengths,
            _local_W_table(pmax, derivative), derivative, W.ndof)
        if repeated:
            # a V_hp dof twice on one element: summed, as a COO construction does
            r = np.repeat(np.arange(W.ndof), np.diff(indptr))
            return sp.csr_matrix((data, (r, indices)), shape=(W.ndof, self.ndof))
        return sp.csr_matrix((data, indices, indptr), shape=(W.ndof, self.ndof))


@njit(cache=True)
def _local_to_W_csr(dofs_v, dofs_w, degrees, L, loc, derivative, ndof_w):
    """CSR (indptr, indices, data, repeated) of the matrix with rows dofs_w[e, j]
    (j < p_e) and, per row, the entries scale_e loc[p_e, j, k] at the columns
    dofs_v[e, k] >= 0 (k <= p_e) in increasing order; scale_e = 2 / L_e (derivative) or
    L_e / 2.  ``repeated``: some element has a column twice (then not summed here)."""
    ne = degrees.shape[0]
    indptr = np.zeros(ndof_w + 1, np.int64)
    for e in range(ne):
        cnt = 0
        for k in range(degrees[e] + 1):
            if dofs_v[e, k] >= 0:
                cnt += 1
        for j in range(degrees[e]):
            indptr[dofs_w[e, j] + 1] = cnt
    for r in range(ndof_w):
        indptr[r + 1] += indptr[r]
    nnz = indptr[ndof_w]
    indices = np.empty(nnz, np.int64)
    data = np.empty(nnz)
    cs = np.empty(dofs_v.shape[1], np.int64)
    ks = np.empty(dofs_v.shape[1], np.int64)
    repeated = False
    for e in range(ne):
        p = degrees[e]
        scale = 2.0 / L[e] if derivative else L[e] / 2.0
        m = 0
        for k in range(p + 1):          # stable insertion sort of the element's columns
            c = dofs_v[e, k]
            if c < 0:
                continue
            pos = m
            while pos > 0 and cs[pos - 1] > c:
                cs[pos] = cs[pos - 1]
                ks[pos] = ks[pos - 1]
                pos -= 1
            if pos > 0 and cs[pos - 1] == c:
                repeated = True
            cs[pos] = c
            ks[pos] = k
            m += 1
        for j in range(p):
            s0 = indptr[dofs_w[e, j]]
            for t in range(m):
                indices[s0 + t] = cs[t]
                data[s0 + t] = scale * loc[p, j, ks[t]]
    return indptr, indices, data, repeated


@lru_cache(maxsize=None)
def _local_W_table(pmax: int, derivative: bool) -> np.ndarray:
    """tab[p, :p, :p + 1] = :func:`_local_W_block` (p, derivative) for p <= pmax."""
    tab = np.zeros((pmax + 1, pmax, pmax + 1))
    for p in range(1, pmax + 1):
        tab[p, :p, :p + 1] = _local_W_block(p, derivative)
    tab.setflags(write=False)
    return tab


@lru_cache(maxsize=None)
def _local_W_block(p: int, derivative: bool) -> np.ndarray:
    """(p, p + 1): the W_hp (Legendre) coefficients of the GLL Lagrange functions l_j of
    degree p (int P_k l_j dt), or of their derivatives dl_j/dt; times |I|/2 (2/|I|) per
    element these are the local blocks of mass_matrix (derivative_matrix)."""
    xq, wq = gauss_legendre(p + 1)
    Pk = legendre_values(p, xq)                     # (nq, p)
    lj = lagrange_values(p, xq, derivative)         # (nq, p+1)
    if derivative:
        # Legendre coefficients of dl_j/dt
        loc = (Pk * wq[:, None]).T @ lj * ((2 * np.arange(p) + 1) / 2.0)[:, None]
    else:
        loc = (Pk * wq[:, None]).T @ lj            # int P_k l_j dt
    loc.setflags(write=False)
    return loc


def containing_elements(coarse: BoundaryMesh, fine: BoundaryMesh, tol: float = 5e-11):
    """For each element of ``fine``, the element of ``coarse`` containing it: from the
    ``parent`` maps when ``coarse`` is an ancestor of ``fine`` (:meth:`BoundaryMesh.refine`),
    otherwise by locating the element midpoints.  ValueError if some fine element does not
    lie inside one coarse element (meshes not nested)."""
    idx = fine.ancestor_map(coarse)
    if idx is not None:
        return idx
    mid = 0.5 * (fine.a + fine.b)
    idx, _ = coarse.locate(mid, tol)
    if np.any(idx < 0):
        k = int(np.flatnonzero(idx < 0)[0])
        raise ValueError(f"meshes are not nested: fine element {k} is not on the coarse "
                         "mesh")
    # both ends on the same coarse element (within the element, not beyond its ends)
    for x in (fine.a, fine.b):
        a, ab = coarse.a[idx], coarse.b[idx] - coarse.a[idx]
        s = np.sum((x - a) * ab, 1) / np.sum(ab ** 2, 1)
        off = np.linalg.norm(a + s[:, None] * ab - x, axis=1)
        bad = (s < -tol) | (s > 1 + tol) | (off > tol * coarse.scale)
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"meshes are not nested: fine element {k} is not inside one "
                             f"coarse element (nearest: {int(idx[k])})")
    return idx


def _reference_coordinates(mesh: BoundaryMesh, elem, x) -> np.ndarray:
    """t in [-1, 1] of the points x (n, 2) on the straight elements ``elem``."""
    a, ab = mesh.a[elem], mesh.b[elem] - mesh.a[elem]
    return np.clip(2.0 * np.sum((x - a) * ab, 1) / np.sum(ab ** 2, 1) - 1.0, -1.0, 1.0)


def prolongate(coarse_space: _Space, U, fine_space: _Space, components: int = 1) -> np.ndarray:
    """Exact embedding of U (coefficients in ``coarse_space``, ``components`` interleaved)
    into ``fine_space`` of the same kind on a nested mesh (every fine element inside one
    coarse element, fine degree >= coarse degree).

    V_hp: nodal values at the Gauss-Lobatto points of the fine elements.  W_hp: the
    Legendre coefficients of the restriction to each fine element (Gauss rule exact for
    the polynomial degree).  Fine dofs removed by ``zero_on`` are dropped."""
    if components not in (1, 2):
        raise ValueError(f"components must be 1 or 2, got {components!r}")
    if type(coarse_space) is not type(fine_space):
        raise ValueError("coarse_space and fine_space must be of the same kind, got "
                         f"{type(coarse_space).__name__} and {type(fine_space).__name__}")
    U = np.asarray(U, dtype=float)
    if U.shape != (components * coarse_space.ndof,):
        raise ValueError(f"U must have {components * coarse_space.ndof} entries "
                         f"(components={components}), got shape {U.shape}")
    mc, mf = coarse_space.mesh, fine_space.mesh
    parent = containing_elements(mc, mf)
    low = mf.degrees < mc.degrees[parent]
    if np.any(low):
        k = int(np.flatnonzero(low)[0])
        raise ValueError(f"fine degree must be >= the coarse one: fine element {k} has "
                         f"p = {mf.degrees[k]}, its coarse element p = {mc.degrees[parent[k]]}")
    Uc = U.reshape(-1, components)
    Uf = np.zeros((fine_space.ndof, components))
    for p in np.unique(mf.degrees):
        p = int(p)
        els = np.flatnonzero(mf.degrees == p)
        if fine_space.kind == LAGRANGE_GLL:
            tq, _ = gauss_lobatto(p + 1)
        else:
            tq, wq = gauss_legendre(p)
        e = np.repeat(els, len(tq))
        tc = _reference_coordinates(mc, parent[e], mf.points(e, np.tile(tq, len(els))))
        vals = coarse_space.evaluate(Uc, parent[e], tc).reshape(len(els), len(tq), components)
        if fine_space.kind == LAGRANGE_GLL:
            coef = vals                                             # nodal values
        else:
            P = legendre_values(p, tq)                              # (nq, p)
            k = np.arange(p)
            coef = np.einsum("q,qk,eqc->ekc", wq, P, vals) * ((2 * k + 1) / 2.0)[:, None]
        d = fine_space.elem_dofs[els, :coef.shape[1]]
        Uf[d[d >= 0]] = coef[d >= 0]
    return Uf.ravel()
