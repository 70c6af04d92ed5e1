"""Q_p finite elements for the Poisson part of the FE/BE coupling (Chapter 2, Omega1).

Space: V1_hp of Section 2.1 on a rectangle mesh (:mod:`hpfebe.fem.meshes`), the tensor
product element Q_p of scikit-fem (``ElementQuadP``: vertex functions, integrated-Legendre
edge and interior functions; ``ElementQuad1`` for p = 1, the same space).  It is
H1-conforming on meshes whose cells share one orientation, which
:func:`~hpfebe.fem.meshes.tensor_block_mesh` guarantees (a test checks the traces from both
sides of every interior edge).  Dirichlet data are zero on Gamma_D (the thesis's examples);
Dirichlet dofs are removed by selection (``free``), the matrices keep all dofs.
"""

from __future__ import annotations

import logging
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from skfem import (Basis, BilinearForm, ElementLineP1, ElementQuad1, ElementQuadP,
                   FacetBasis, Functional, MappingIsoparametric, MeshQuad)
from skfem import LinearForm, asm
from skfem.helpers import dot, grad

from .meshes import FEDomain

P_MAX_FE = 10


@BilinearForm
def laplace(u, v, w):
    """(grad u, grad v): the FE part of a_h in (2.4)."""
    return dot(grad(u), grad(v))


def stiffness(basis) -> sp.csr_matrix:
    """The matrix of :data:`laplace` on ``basis`` (a scalar skfem CellBasis): the
    element matrices K_e[i, j] = sum_q dx_q grad phi_i(x_q) . grad phi_j(x_q) as one
    batched product G_e diag(dx) G_e^T (skfem's ``asm(laplace, basis)`` forms the Nbfun^2
    pairs one by one: 6561 of them at p = 8), symmetrised, and entries below
    64 macheps of their element matrix's largest set to zero: the integrated-Legendre
    shape functions are orthogonal in most pairs on a rectangle, and their round-off
    (1e-17) would fill the pattern (Q_8 on 75 cells: 35201 nonzeros instead of 480617;
    the matrices agree to 1.3e-15 of the largest entry)."""
    nb, nel = basis.Nbfun, basis.nelems
    G = np.stack([np.stack(phi[0].grad) for phi in basis.basis])    # (nb, 2, nel, nq)
    A = G.transpose(2, 0, 1, 3).reshape(nel, nb, -1)                 # (nel, nb, 2 nq)
    dx = np.concatenate([basis.dx, basis.dx], axis=1)
    Ke = (A * dx[:, None, :]) @ A.transpose(0, 2, 1)
    Ke = 0.5 * (Ke + Ke.transpose(0, 2, 1))
    Ke[np.abs(Ke) <= 64 * np.finfo(float).eps * np.abs(Ke).max(axis=(1, 2))[:, None, None]] \
        = 0.0
    dofs = basis.element_dofs.T                                      # (nel, nb)
    rows = np.broadcast_to(dofs[:, :, None], Ke.shape).ravel()
    cols = np.broadcast_to(dofs[:, None, :], Ke.shape).ravel()
    K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(basis.N, basis.N))
    K.eliminate_zeros()
    return K


def quad_element(p: int):
    """The Q_p element (H1-conforming on consistently oriented rectangle meshes)."""
    if int(p) != p or not 1 <= p <= P_MAX_FE:
        raise ValueError(f"p (FE degree) must be an integer in 1..{P_MAX_FE}, got {p!r}")
    if p == 1:
        return ElementQuad1()
    log = logging.getLogger("skfem")
    level = log.level
    log.setLevel(logging.ERROR)  # silence the "use ElementQuad2 for speed" advice
    try:
        return ElementQuadP(int(p))
    finally:
        log.setLevel(level)


class _MemoInvDF:
    """The mesh's skfem mapping, remembering invDF(X, tind) of the last (X, tind) pair
    (by identity): a CellBasis evaluates all its basis functions at one X and tind, and
    each gbasis call would compute the same inverse Jacobians again (most of the time
    of building a Q_p basis for p >= 2).  The same arrays, so the same numbers."""

    def __init__(self, mapping):
        self._mapping = mapping
        self._last = None

    def __getattr__(self, name):
        return getattr(self._mapping, name)

    def invDF(self, X, tind=None):
        last = self._last
        if last is not None and last[0] is X and last[1] is tind:
            return last[2]
        out = self._mapping.invDF(X, tind)
        self._last = (X, tind, out)
        return out

    def forget(self):
        self._last = None


class _AffineQuadMapping(MappingIsoparametric):
    """scikit-fem's bilinear mapping of a MeshQuad whose cells are parallelograms (the
    rectangles of :func:`~hpfebe.fem.meshes.tensor_block_mesh`): there it is affine,
    x = x_0 + (x_1 - x_0) X + (x_3 - x_0) Y, with the constant Jacobian [x_1 - x_0,
    x_3 - x_0] (the general one sums the derivatives of the four vertex functions at
    every point: most of the time of building a basis on a large mesh; the two agree to
    the round-off of that sum, which cancels: 6e-14 relative on 1/256 cells)."""

    def __init__(self, mesh, x0: np.ndarray, E: np.ndarray):
        super().__init__(mesh, ElementQuad1(), ElementLineP1())
        self._x0, self._E = x0, E                       # (2, nel), (2, 2, nel)

    @classmethod
    def of(cls, mesh):
        """The mapping of ``mesh``, or None if a cell is not a parallelogram (to
        4 macheps of the coordinates) or is degenerate."""
        if not isinstance(mesh, MeshQuad) or mesh.elem is not ElementQuad1:
            return None
        x = mesh.p[:, mesh.t]                           # (2, 4, nel)
        E = np.stack([x[:, 1] - x[:, 0], x[:, 3] - x[:, 0]], axis=1)
        tol = 4 * np.finfo(float).eps * max(np.abs(mesh.p).max(), 1.0)
        det = E[0, 0] * E[1, 1] - E[0, 1] * E[1, 0]      # either orientation (skfem: |det|)
        if np.abs(x[:, 2] - x[:, 1] - E[:, 1]).max() > tol or np.any(det == 0):
            return None
        return cls(mesh, x[:, 0], E)

    def Fmap(self, i, X, tind=None):
        x0, E = (self._x0, self._E) if tind is None else (self._x0[:, tind],
                                                           self._E[:, :, tind])
        return x0[i][:, None] + E[i, 0][:, None] * X[0] + E[i, 1][:, None] * X[1]

    def J(self, i, j, X, tind=None):
        e = self._E[i, j] if tind is None else self._E[i, j, tind]
        return np.broadcast_to(e[:, None], (len(e), X.shape[-1])).copy()

    _J = J


def _basis(mesh, element, intorder: int) -> Basis:
    """skfem ``Basis(mesh, element, intorder=...)`` built with :class:`_MemoInvDF` (over
    :class:`_AffineQuadMapping` where the cells allow it)."""
    mapping = _MemoInvDF(_AffineQuadMapping.of(mesh) or mesh._mapping())
    basis = Basis(mesh, element, mapping=mapping, intorder=intorder)
    mapping.forget()
    return basis


class PoissonFE:
    """Q_p finite elements on an :class:`FEDomain` (or a labelled rectangle ``MeshQuad``)
    with u = 0 on the facets ``dirichlet``.

    Attributes: ``basis`` (skfem CellBasis), ``ndof``, ``free`` (dofs not on Gamma_D),
    ``K`` (stiffness, all dofs, assembled once; the name of every FE body's stiffness).
    """

    def __init__(self, domain: FEDomain, p: int, dirichlet: tuple[str, ...] = ("D",)):
        if isinstance(domain, MeshQuad):
            domain = FEDomain(domain)
        if not isinstance(domain, FEDomain):
            raise ValueError(f"domain must be an FEDomain or a MeshQuad, got "
                             f"{type(domain).__name__}")
        self.domain = domain
        self.p = int(p)
        self.element = quad_element(p)
        # Q_p x Q_p products on rectangles are polynomials of degree 2p per direction
        self.basis = _basis(domain.mesh, self.element, 2 * self.p + 1)
        self.ndof = self.basis.N
        fixed = [domain.facets[lab] for lab in dirichlet if lab in domain.facets]
        fixed = np.concatenate(fixed) if fixed else np.zeros(0, dtype=np.int64)
        self.fixed = (np.unique(self.basis.get_dofs(facets=fixed).all()) if fixed.size
                      else np.zeros(0, dtype=np.int64))
        mask = np.ones(self.ndof, dtype=bool)
        mask[self.fixed] = False
        self.free = np.flatnonzero(mask)

    @property
    def mesh(self):
        return self.domain.mesh

    @cached_property
    def K(self) -> sp.csr_matrix:
        """Stiffness matrix (grad U, grad V)_Omega1, all dofs: :func:`stiffness`."""
        return stiffness(self.basis)

    # ----------------------------------------------------------------- right-hand side
    def load(self, f) -> np.ndarray:
        """(f, Phi1)_Omega1 for f(x, y) (vectorised); f = None gives zeros."""
        if f is None:
            return np.zeros(self.ndof)

        @LinearForm
        def lf(v, w):
            return f(w.x[0], w.x[1]) * v
        return asm(lf, self.basis)

    def neumann_load(self, grad_u, labels: tuple[str, ...] = ("N",)) -> np.ndarray:
        """<t_hat, Phi1>_{Gamma_N} with t_hat = grad u . n (outward normal of Omega1)."""
        facets = [self.domain.facets[lab] for lab in labels if lab in self.domain.facets]
        if not facets:
            return np.zeros(self.ndof)
        fb = FacetBasis(self.domain.mesh, self.element, facets=np.concatenate(facets),
                        intorder=2 * self.p + 4)

        @LinearForm
        def lf(v, w):
            gx, gy = grad_u(w.x[0], w.x[1])
            return (gx * w.n[0] + gy * w.n[1]) * v
        return asm(lf, fb)

    # ----------------------------------------------------------------- point evaluation
    def eval_matrices(self, points: np.ndarray, cells: np.ndarray):
        """Sparse (npts x ndof) matrices of the basis values and of the x- and
        y-derivatives at physical ``points`` (npts, 2) lying in (the closure of) the
        given ``cells``.  Reference coordinates by the inverse element map."""
        pts = np.asarray(points, dtype=float)
        cells = np.asarray(cells, dtype=np.int64)
        if pts.ndim != 2 or pts.shape[1] != 2 or cells.shape != (pts.shape[0],):
            raise ValueError(f"points must be (n, 2) with one cell each, got {pts.shape}, "
                             f"{cells.shape}")
        mapping = self.basis.mapping
        X = mapping.invF(pts.T[:, :, None], tind=cells)          # (2, npts, 1)
        if np.abs(X - np.clip(X, 0.0, 1.0)).max(initial=0.0) > 1e-8:
            raise ValueError("a point lies outside its cell")
        X = np.clip(X, 0.0, 1.0)
        nb = self.basis.Nbfun
        val = np.empty((nb, pts.shape[0]))
        gx = np.empty_like(val)
        gy = np.empty_like(val)
        for k in range(nb):
            f = self.element.gbasis(mapping, X, k, tind=cells)[0]
            val[k] = np.asarray(f)[:, 0]
            gx[k] = f.grad[0][:, 0]
            gy[k] = f.grad[1][:, 0]
        if isinstance(mapping, _MemoInvDF):
            mapping.forget()
        rows = np.tile(np.arange(pts.shape[0]), nb)
        cols = self.basis.element_dofs[:, cells].ravel()
        shape = (pts.shape[0], self.ndof)
        mk = lambda v: sp.csr_matrix((v.ravel(), (rows, cols)), shape=shape)  # noqa: E731
        return mk(val), mk(gx), mk(gy)

    # ----------------------------------------------------------------- errors
    def errors(self, U: np.ndarray, u, grad_u, intorder: int | None = None) -> dict:
        """L2 and H1-seminorm ('energy') errors of the FE solution against the exact
        solution u(x, y) with gradient grad_u(x, y) -> (ux, uy), on Omega1."""
        U = np.asarray(U, dtype=float)
        if U.shape != (self.ndof,):
            raise ValueError(f"U must have {self.ndof} entries, got {U.shape}")
        order = intorder or 2 * self.p + 6
        cache = self.__dict__.setdefault("_error_bases", {})   # one per order (lambda sweeps)
        if order not in cache:
            cache[order] = _basis(self.domain.mesh, self.element, order)
        basis = cache[order]

        @Functional
        def e_l2(w):
            return (w["uh"] - u(w.x[0], w.x[1])) ** 2

        @Functional
        def e_h1(w):
            gx, gy = grad_u(w.x[0], w.x[1])
            return (w["uh"].grad[0] - gx) ** 2 + (w["uh"].grad[1] - gy) ** 2

        uh = basis.interpolate(U)
        l2 = float(np.sqrt(e_l2.assemble(basis, uh=uh)))
        h1 = float(np.sqrt(e_h1.assemble(basis, uh=uh)))
        if not (np.isfinite(l2) and np.isfinite(h1)):
            raise FloatingPointError("FE error is not finite (solution contains NaN/inf)")
        return {"l2": l2, "h1": h1}
