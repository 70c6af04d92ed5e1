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
j on element e, -1 for padding or for a function removed by ``zero_on``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from numba import njit
from numpy.polynomial import legendre as npleg

from .geometry import BoundaryMesh
from .quadrature import gauss_legendre, gauss_lobatto

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


def lagrange_values(p: int, t: np.ndarray, derivative: bool = False) -> np.ndarray:
    """GLL Lagrange basis of degree p at points t, shape (len(t), p+1) (numpy)."""
    xp, _ = gauss_lobatto(p + 1)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    # coefficients of each l_j in the Legendre basis by exact interpolation at the nodes
    vand = npleg.legvander(xp, p)
    coef = np.linalg.solve(vand, np.eye(p + 1))  # column j: Legendre coeffs of l_j
    if derivative:
        coef = npleg.legder(coef, axis=0)
    return npleg.legvander(t, coef.shape[0] - 1) @ coef


def legendre_values(p: int, t: np.ndarray, derivative: bool = False) -> np.ndarray:
    """Legendre P_0..P_{p-1} at points t, shape (len(t), p) (numpy)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    coef = np.eye(p)
    if derivative:
        return npleg.legvander(t, p - 1) @ np.vstack([npleg.legder(coef, axis=0),
                                                      np.zeros((1, p))])
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
        L = mesh.lengths
        rows, cols, vals = [], [], []
        for p in np.unique(mesh.degrees):
            p = int(p)
            els = np.flatnonzero(mesh.degrees == p)
            xq, wq = gauss_legendre(p + 1)
            Pk = legendre_values(p, xq)                     # (nq, p)
            lj = lagrange_values(p, xq, derivative)         # (nq, p+1)
            if derivative:
                # Legendre coefficients of dl_j/dt, times dt/ds = 2/|I|
                loc = (Pk * wq[:, None]).T @ lj * ((2 * np.arange(p) + 1) / 2.0)[:, None]
                scale = 2.0 / L[els]
            else:
                loc = (Pk * wq[:, None]).T @ lj            # int P_k l_j dt
                scale = L[els] / 2.0
            r = W.elem_dofs[els, :p][:, :, None].repeat(p + 1, axis=2)
            c = self.elem_dofs[els, :p + 1][:, None, :].repeat(p, axis=1)
            v = scale[:, None, None] * loc[None, :, :]
            keep = c >= 0
            rows.append(r[keep])
            cols.append(c[keep])
            vals.append(v[keep])
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(W.ndof, self.ndof))
