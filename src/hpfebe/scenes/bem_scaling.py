"""Scaling of the dense and the compressed hp-BEM (issue 27; beyond the thesis).

The interior Dirichlet problem on the unit square Omega = (0, 1)^2 with N uniform
elements (N / 4 per side) of degree p, solved for its Neumann data through the Calderon
identity of Section 1.4, V psi_h = (K + M/2) g (:meth:`BoundaryOperators.Psi`), g the
Gauss-Lobatto interpolant of the exact trace in V_hp, psi_h in W_hp:

* Laplace: u(x) = log|x - x0|, x0 = :data:`X0_LAPLACE` outside the closed square, exact
  Neumann data psi = (x - x0) . n / |x - x0|^2 (the experiment of figure_bem_laplace);
* Lame (plane strain, E and nu of :mod:`.materials`): Kelvin's field u = G(x, x0) f of a
  point force f = :data:`F0_LAME` at x0 = :data:`X0_LAME` outside, exact traction
  t = sigma(u) n with sigma = lambda div u I + mu (grad u + grad u^T).

Both exact data have zero total flux / force, so the default constraint of Psi holds for
them.  :func:`solve` runs one :class:`ScalingRun` (dense, ``compression=None``, or the
H-matrices of :mod:`hpfebe.bem.hmatrix`, ``compression="hmatrix"`` with tolerance
``tol``) and returns times, operator storage and the L2(Gamma) error against the exact
data; :func:`far_field_rows` is the independent check of a compressed Laplace matvec at
large N: rows of V x by the dense path's local blocks on the near pairs and a tensor
Gauss rule on every other pair, no H-matrix and no dense matrix involved.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..analysis import boundary_l2_error
from ..bem import LameBEM, LaplaceBEM
from ..bem.laplace import local_blocks
from ..checks import choice, integer, real
from ..geometry import BoundaryMesh
from ..quadrature import gauss_legendre
from ..spaces import P_MAX, legendre_values
from .materials import E, NU

__all__ = ["SQUARE", "X0_LAPLACE", "X0_LAME", "F0_LAME", "PDES", "ScalingRun",
           "ScalingResult", "square_mesh", "operators", "exact_data", "solve",
           "relative_difference", "far_field_rows", "result_row", "scaling_rows",
           "tolerance_rows"]

SQUARE = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))
X0_LAPLACE = np.array([1.5, 1.5])
X0_LAME, F0_LAME = np.array([0.4, -3.0]), np.array([0.6, -1.1])
PDES = ("laplace", "lame")
EXTRA_POINTS = 8            # Gauss points beyond p of the L2(Gamma) error


@dataclass(frozen=True)
class ScalingRun:
    """One solve: ``pde`` (:data:`PDES`), ``n_elements`` N (a multiple of 4: N / 4 per
    side of the square), degree ``p``, ``compression`` (None: dense; "hmatrix") and its
    relative tolerance ``tol`` in (0, 1)."""

    pde: str = "laplace"
    n_elements: int = 64
    p: int = 1
    compression: str | None = None
    tol: float = 1e-8

    def __post_init__(self):
        choice("pde", self.pde, PDES)
        n = integer("n_elements", self.n_elements, lo=4)
        if n % 4:
            raise ValueError(f"n_elements must be a multiple of 4 (N / 4 per side), got {n}")
        integer("p", self.p, lo=1, hi=P_MAX)
        choice("compression", self.compression, (None, "hmatrix"))
        real("tol", self.tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True)


@dataclass
class ScalingResult:
    """What :func:`solve` measured: ``dof`` (d x dim W_hp), ``assembly_s`` (V and B),
    ``solve_s`` (Psi), ``storage_bytes`` of V and K (dense arrays or H-matrices),
    ``dense_bytes`` (their dense size), ``error`` ||psi - psi_h||_L2(Gamma) against the
    exact data, the coefficients ``psi`` and the H-matrix report ``info`` (or None)."""

    run: ScalingRun
    dof: int
    assembly_s: float
    solve_s: float
    storage_bytes: int
    dense_bytes: int
    error: float
    psi: np.ndarray
    info: dict | None = None

    @property
    def ratio(self) -> float:
        """Compression ratio: storage / dense storage (1 for the dense path)."""
        return self.storage_bytes / self.dense_bytes


def square_mesh(n_elements: int, p: int) -> BoundaryMesh:
    """The unit square with n_elements / 4 uniform elements per side, degree p."""
    return BoundaryMesh.polygon(SQUARE, n=n_elements // 4, p=p)


def operators(run: ScalingRun):
    """The LaplaceBEM / LameBEM of ``run`` (default scale and constraint)."""
    mesh = square_mesh(run.n_elements, run.p)
    kw = dict(compression=run.compression, tol=run.tol) if run.compression else {}
    if run.pde == "laplace":
        return LaplaceBEM(mesh, **kw)
    return LameBEM(mesh, E, NU, **kw)


def _kelvin(x, lam, mu):
    """Kelvin's field u = G(x, x0) f (scale 1) and its gradient g[:, j, l] = du_j/dx_l,
    G = c1 (-log r I + c2 r r^T / r^2) (:mod:`hpfebe.bem.lame`)."""
    c1 = (lam + 3 * mu) / (4 * np.pi * mu * (lam + 2 * mu))
    c2 = (lam + mu) / (lam + 3 * mu)
    f = F0_LAME
    r = x - X0_LAME
    r2 = np.einsum("ij,ij->i", r, r)
    fr = r @ f
    u = c1 * (-0.5 * np.log(r2)[:, None] * f + c2 * r * (fr / r2)[:, None])
    rr = r[:, :, None] * r[:, None, :]
    g = c1 * (-f[None, :, None] * r[:, None, :] / r2[:, None, None]
              + c2 * ((np.eye(2) * fr[:, None, None] + r[:, :, None] * f[None, None, :])
                      / r2[:, None, None] - 2 * rr * (fr / r2 ** 2)[:, None, None]))
    return u, g


def exact_data(op, pde: str):
    """(trace, flux): the exact u(x) ((n,) or (n, 2)) and Neumann data psi(x, n)."""
    if pde == "laplace":
        def trace(x):
            return np.log(np.linalg.norm(x - X0_LAPLACE, axis=1))

        def flux(x, n):
            d = x - X0_LAPLACE
            return np.einsum("ij,ij->i", d, n) / np.einsum("ij,ij->i", d, d)
        return trace, flux

    def trace(x):
        return _kelvin(x, op.lam, op.mu)[0]

    def flux(x, n):
        g = _kelvin(x, op.lam, op.mu)[1]
        div = g[:, 0, 0] + g[:, 1, 1]
        sig = op.lam * div[:, None, None] * np.eye(2) + op.mu * (g + np.swapaxes(g, 1, 2))
        return np.einsum("ijk,ik->ij", sig, n)
    return trace, flux


def _dirichlet(op, trace):
    """g in V_hp (interleaved components for Lame): the GLL interpolant of the trace."""
    if op.d == 1:
        return op.V_space.interpolate(trace)
    return np.stack([op.V_space.interpolate(lambda x, c=c: trace(x)[:, c])
                     for c in range(2)], axis=1).ravel()


def _l2_error(op, psi, flux) -> float:
    """||flux - psi_h||_L2(Gamma) (both components for Lame)."""
    if op.d == 1:
        return boundary_l2_error(op.W_space, psi, flux, extra=EXTRA_POINTS)
    parts = [boundary_l2_error(op.W_space, psi[c::2], lambda x, n, c=c: flux(x, n)[:, c],
                               extra=EXTRA_POINTS) for c in range(2)]
    return float(np.hypot(*parts))


def _storage(op) -> tuple[int, int, dict | None]:
    """(bytes of V and K as stored, their dense bytes 8 d^2 n_W (n_W + n_V), the
    H-matrix report or None)."""
    nW, nV = op.W_space.ndof, op.V_space.ndof
    dense = 8 * op.d ** 2 * nW * (nW + nV)
    if getattr(op, "hm", None) is None:
        return int(op.V.nbytes + op.K.nbytes), dense, None
    info = op.hmatrix_info()
    return int(info["V"]["bytes"] + info["K"]["bytes"]), dense, info


def solve(run: ScalingRun) -> ScalingResult:
    """Assemble V and B = K + M/2, solve for psi_h (:meth:`Psi`), measure (module doc)."""
    op = operators(run)
    trace, flux = exact_data(op, run.pde)
    g = _dirichlet(op, trace)
    t0 = time.perf_counter()
    op.V, op.B
    t1 = time.perf_counter()
    psi = op.Psi(g)
    t2 = time.perf_counter()
    storage, dense, info = _storage(op)
    return ScalingResult(run, op.d * op.W_space.ndof, t1 - t0, t2 - t1, storage, dense,
                         _l2_error(op, psi, flux), psi, info)


def relative_difference(a, b) -> float:
    """||a - b||_2 / ||b||_2 of two coefficient vectors (b the reference)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def result_row(res: ScalingResult, dense: ScalingResult | None = None) -> dict:
    """One table row of a result: the run, dof, storage (MB of V and K), compression
    ratio, error against the exact data and (``dense`` given) against the dense psi."""
    r = res.run
    return dict(pde=r.pde, p=r.p, N=r.n_elements,
                method="dense" if r.compression is None else r.compression,
                tol=r.tol if r.compression else float("nan"), dof=res.dof,
                storage_mb=res.storage_bytes / 2**20, dense_mb=res.dense_bytes / 2**20,
                ratio=res.ratio, error_exact=res.error,
                err_vs_dense=(relative_difference(res.psi, dense.psi) if dense is not None
                              else float("nan")),
                assembly_s=res.assembly_s, solve_s=res.solve_s,
                wall_time_s=res.assembly_s + res.solve_s)


def scaling_rows(pde: str, p: int, sizes, dense_max_dof: int, tol: float) -> list[dict]:
    """For each N of ``sizes``: the dense solve (if its dof <= ``dense_max_dof``) and the
    compressed one at ``tol`` (with its difference to the dense psi where both ran)."""
    rows = []
    for N in sizes:
        dense = None
        if (1 if pde == "laplace" else 2) * p * N <= dense_max_dof:
            dense = solve(ScalingRun(pde, N, p))
            rows.append(result_row(dense))
        rows.append(result_row(solve(ScalingRun(pde, N, p, "hmatrix", tol)), dense))
    return rows


def tolerance_rows(pde: str, p: int, N: int, tols) -> list[dict]:
    """The dense solve and the compressed ones at each tolerance of ``tols`` (N, p
    fixed): error against the exact data and against the dense psi as tol varies."""
    dense = solve(ScalingRun(pde, N, p))
    return [result_row(dense)] + [result_row(solve(ScalingRun(pde, N, p, "hmatrix", t)),
                                             dense) for t in tols]


def far_field_rows(op, x, elements, n_gauss: int = 16) -> np.ndarray:
    """Rows of V x (Laplace, W_hp x W_hp) for the test ``elements``, shape
    (len(elements), p): the pairs (i, j) with i == j or a shared vertex by the dense
    path's local blocks (:func:`hpfebe.bem.laplace.local_blocks`, the singular
    quadrature), every other pair by an ``n_gauss`` x ``n_gauss`` tensor Gauss rule of
    G(x, y) = -log(|x - y| / R) / (2 pi) (elements separated by at least one element
    length: the rule is exact to ~1e-16 there).  Uniform degree p."""
    mesh, Ws = op.mesh, op.W_space
    p = int(mesh.degrees[0])
    if not np.all(mesh.degrees == p):
        raise ValueError("far_field_rows needs a uniform degree")
    t, w = gauss_legendre(n_gauss)
    P = legendre_values(p, t)                                     # (q, p)
    ne = mesh.n_elements
    allx = mesh.points(np.repeat(np.arange(ne), n_gauss), np.tile(t, ne))   # (ne q, 2)
    psi = Ws.evaluate(x, np.repeat(np.arange(ne), n_gauss), np.tile(t, ne))
    wy = np.tile(w, ne) * np.repeat(mesh.lengths, n_gauss) / 2.0 * psi
    elems = mesh.elements
    out = np.empty((len(elements), p))
    for row, i in enumerate(np.asarray(elements, dtype=int)):
        near = np.flatnonzero((elems == elems[i, 0]).any(axis=1)
                              | (elems == elems[i, 1]).any(axis=1))
        xi = mesh.points(np.full(n_gauss, i), t)                  # (q, 2)
        far = np.ones(ne, bool)
        far[near] = False
        fy = np.repeat(far, n_gauss)
        d = xi[:, None, :] - allx[None, fy, :]
        G = -np.log(np.sqrt(np.einsum("abk,abk->ab", d, d)) / op.scale) / (2 * np.pi)
        u = G @ wy[fy]                                            # (q,)
        out[row] = (P * (w * mesh.lengths[i] / 2.0 * u)[:, None]).sum(axis=0)
        for j in near:
            out[row] += local_blocks(mesh, i, int(j), op.scale)["V"] @ x[Ws.elem_dofs[j, :p]]
    return out
