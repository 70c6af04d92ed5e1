"""Quadrilateral meshes of polygonal FE subdomains built from per-block tensor grids.

The FE subdomains of Chapter 2 are unions of axis-parallel rectangles (Omega1 = Omega minus
Omega2).  A mesh of size ``h = 1/h_inv`` is built as follows (the thesis gives only h):

* the break points ``xbreaks`` / ``ybreaks`` (every x / y coordinate of a corner of Omega
  or Omega2) split each axis into blocks;
* each axis gets the cell count of the uniform grid of size h (2 h_inv cells on [-1, 1]);
  a break point that falls between two lines of that uniform grid takes the lower one
  (``rounding="floor"``) and each block is divided into equal cells, so that every
  interface and corner is resolved by mesh lines;
* the tensor product of the two 1D grids is cut to the cells whose centre lies in the
  subdomain (``inside``).

The result is a conforming mesh of axis-parallel rectangles, all oriented alike (local
x along global x), which keeps the hierarchical edge functions of ``ElementQuadP``
conforming without orientation flips.  Where the block lengths are multiples of h the grid
is uniform (Example 2: h_inv = 4, 8, ...; Example 1 with h_inv = 2).  Otherwise (Example 1,
h_inv = 5, 11, 23, 47) the blocks y in [-1, -1/2] and [1/2, 1] get floor(h_inv/2) and
ceil(h_inv/2) rows: for h_inv = 5 this is the thesis's "75 finite elements" (Section
2.2.5), and it reproduces the FE errors of Table 2.2 for p = 1, 2 to within 3 %
(``rounding="ceil"``, 3 rows in both blocks, 85 elements, gives errors 15-40 % smaller).
Every interface edge has size exactly 1/h_inv.

Labelled meshes (any scikit-fem mesh with named boundary facets ``mesh.boundaries``):

* :func:`cell_diameter` - h_K = diam K, the largest distance between two vertices of K
  (the longest edge of a triangle, the longer diagonal of a rectangle): the one cell size
  of the package (FE indicators, Nitsche weights, mesh statistics);
* :func:`refine_labelled` - conforming refinement (scikit-fem's ``refined``: red
  refinement of all cells, or red-green-blue refinement of the marked triangles with
  closure) whose boundary facets inherit the labels of the facets they lie on (scikit-fem
  drops the labels in its adaptive refinement);
* :func:`is_conforming` - no hanging nodes: every facet with one neighbour lies on the
  boundary of a reference mesh (the initial, conforming one), every vertex is used;
* :func:`new_vertices`, :func:`local_mesh_size`, :func:`distance_to_set`,
  :func:`refinement_concentration` - where a refinement put its new vertices.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np
from skfem import MeshQuad

from ..checks import array, choice, real


def block_grid(breaks: Sequence[float], h_inv: float, rounding: str = "floor") -> np.ndarray:
    """1D grid of cells of size about 1/h_inv through all ``breaks``.

    ``rounding="floor"`` (default): the break b_k becomes grid line number
    floor((b_k - b_0) h_inv) of a uniform grid (the last one: ceil), and each block is
    divided equally: the total count is that of the uniform grid, a break that falls
    between grid lines takes the lower one.  ``rounding="ceil"``: every block of length L
    gets ceil(L h_inv) cells (no cell larger than 1/h_inv)."""
    b = np.unique(array("breaks", breaks, ndim=1))          # finite numbers
    if b.size < 2:
        raise ValueError(f"breaks must contain at least two distinct values, got {breaks!r}")
    h_inv = real("h_inv", h_inv, positive=True)
    choice("rounding", rounding, ("floor", "ceil"))
    if rounding == "floor":
        k = np.floor((b - b[0]) * h_inv + 1e-9)
        k[-1] = np.ceil((b[-1] - b[0]) * h_inv - 1e-9)
        counts = np.maximum(np.diff(k), 1)
    else:
        counts = np.maximum(np.ceil(np.diff(b) * h_inv - 1e-9), 1)
    if counts.sum() > 10 ** 7:            # h_inv = 1e20 asked numpy for 1e20 cells
        raise ValueError(f"h_inv must give at most 1e7 cells along an axis, got "
                         f"h_inv={h_inv!r}: {float(counts.sum()):.3g} cells")
    counts = counts.astype(int)
    pts = [b[:1]]
    for lo, hi, n in zip(b[:-1], b[1:], counts):
        pts.append(np.linspace(lo, hi, n + 1)[1:])
    return np.concatenate(pts)


@dataclass(frozen=True)
class FEDomain:
    """A labelled mesh and the nominal inverse mesh size ``h_inv`` it was built for.

    The labels are the mesh's own named boundaries (scikit-fem ``mesh.boundaries``, the
    one labelled-mesh notion of the package, kept by :func:`refine_labelled`):
    ``facets[label]`` are the boundary facet indices carrying ``label`` ("D", "N", "I",
    ...), and ``facets`` is ``mesh.boundaries`` itself (labels given as ``facets`` are
    attached to the mesh).
    """

    mesh: MeshQuad
    facets: dict | None = None
    h_inv: float = math.nan

    def __post_init__(self):
        if not (hasattr(self.mesh, "p") and hasattr(self.mesh, "facets")):
            raise ValueError(f"mesh must be a scikit-fem mesh, got {type(self.mesh).__name__}")
        mesh = self.mesh
        if self.facets is not None and self.facets is not mesh.boundaries:
            mesh = replace(mesh, _boundaries=dict(self.facets))
        elif mesh.boundaries is None:
            mesh = replace(mesh, _boundaries={})
        object.__setattr__(self, "mesh", mesh)
        object.__setattr__(self, "facets", mesh.boundaries)

    @property
    def n_elements(self) -> int:
        return self.mesh.t.shape[1]

    def facet_length(self, facets) -> np.ndarray:
        p = self.mesh.p[:, self.mesh.facets[:, facets]]
        return np.linalg.norm(p[:, 1] - p[:, 0], axis=0)

    def cell_diameter(self, cells) -> np.ndarray:
        """Diameter of the cells ``cells`` (:func:`cell_diameter`; the longer diagonal of
        a rectangle)."""
        return cell_diameter(self.mesh, cells)


def tensor_block_mesh(xbreaks, ybreaks, h_inv: float,
                      inside: Callable[[np.ndarray, np.ndarray], np.ndarray],
                      label: Callable[[np.ndarray, np.ndarray], np.ndarray],
                      rounding: str = "floor") -> FEDomain:
    """Conforming rectangle mesh of the subdomain ``inside(x, y)`` (see module doc).

    ``label(x, y)`` returns one label string per boundary facet midpoint."""
    xs = block_grid(array("xbreaks", xbreaks, ndim=1), h_inv, rounding)
    ys = block_grid(array("ybreaks", ybreaks, ndim=1), h_inv, rounding)
    nx, ny = len(xs) - 1, len(ys) - 1
    I, J = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    I, J = I.ravel(), J.ravel()
    cx, cy = 0.5 * (xs[I] + xs[I + 1]), 0.5 * (ys[J] + ys[J + 1])
    keep = np.asarray(inside(cx, cy), dtype=bool)
    if not keep.any():
        raise ValueError("inside() selects no cell: the subdomain is empty")
    I, J = I[keep], J[keep]
    node = lambda i, j: j * (nx + 1) + i  # noqa: E731
    t = np.vstack([node(I, J), node(I + 1, J), node(I + 1, J + 1), node(I, J + 1)])
    used, t = np.unique(t, return_inverse=True)
    t = t.reshape(4, -1)
    jj, ii = np.divmod(used, nx + 1)
    p = np.vstack([xs[ii], ys[jj]])
    mesh = MeshQuad(p, t)
    bf = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    labs = np.asarray(label(mid[0], mid[1]))
    facets = {str(lab): bf[labs == lab] for lab in np.unique(labs)}
    return FEDomain(mesh, facets, float(h_inv))


# --------------------------------------------------------------------------- labelled meshes
def cell_diameter(mesh, cells=None) -> np.ndarray:
    """h_K = diam K of the cells ``cells`` (all if None): the largest distance between two
    vertices of K (cells are convex polygons with straight sides)."""
    t = mesh.t if cells is None else mesh.t[:, np.asarray(cells, dtype=np.int64)]
    x = mesh.p[:, t]                                   # (2, n_vertices_per_cell, n)
    h = np.zeros(t.shape[1])
    for i in range(t.shape[0]):
        for j in range(i + 1, t.shape[0]):
            h = np.maximum(h, np.linalg.norm(x[:, i] - x[:, j], axis=0))
    return h


def _scale(mesh) -> float:
    return float(max(np.ptp(mesh.p, axis=1).max(), np.finfo(float).tiny))


def facet_containing(mesh, facets, points, tol: float = 1e-10,
                     chunk: int = 4_000_000) -> np.ndarray:
    """For each of the points (2, n): the index into ``facets`` of a facet of ``mesh``
    containing it (distance <= tol times the mesh's extent), -1 if there is none."""
    facets = np.asarray(facets, dtype=np.int64)
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[0] != 2:
        raise ValueError(f"points must have shape (2, n), got {pts.shape}")
    out = np.full(pts.shape[1], -1, dtype=np.int64)
    if facets.size == 0 or pts.shape[1] == 0:
        return out
    a = mesh.p[:, mesh.facets[0, facets]].T            # (m, 2)
    ab = mesh.p[:, mesh.facets[1, facets]].T - a
    L2 = np.sum(ab ** 2, axis=1)
    eps = tol * _scale(mesh)
    step = max(1, chunk // facets.size)
    for s in range(0, pts.shape[1], step):
        q = pts[:, s:s + step].T[:, None, :]           # (k, 1, 2)
        lam = np.clip(np.sum((q - a) * ab, axis=-1) / L2, 0.0, 1.0)
        d = np.linalg.norm(q - (a + lam[..., None] * ab), axis=-1)
        j = np.argmin(d, axis=1)
        hit = d[np.arange(j.size), j] <= eps
        out[s:s + step] = np.where(hit, j, -1)
    return out


def _facet_midpoints(mesh, facets) -> np.ndarray:
    return mesh.p[:, mesh.facets[:, facets]].mean(axis=1)


def refine_labelled(mesh, marked=None):
    """Conforming refinement of a labelled scikit-fem mesh: all cells if ``marked`` is
    None or marks every cell (scikit-fem's uniform red refinement), else the cells of the
    boolean mask ``marked`` (red-green-blue refinement with closure, ``MeshTri`` only).
    Every boundary facet of the new mesh carries the labels of the facet of ``mesh`` it
    lies on (labels survive any number of refinements; the labelled facet sets are
    sorted)."""
    if marked is not None:
        marked = np.asarray(marked)
        if marked.dtype != bool or marked.shape != (mesh.t.shape[1],):
            raise ValueError(f"marked must be a boolean mask of the {mesh.t.shape[1]} cells, "
                             f"got dtype {marked.dtype}, shape {marked.shape}")
    skfem_log = logging.getLogger("skfem.mesh.mesh")
    level = skfem_log.level
    skfem_log.setLevel(logging.ERROR)   # "Named boundaries invalidated": relabelled below
    try:
        new = mesh.refined() if marked is None or marked.all() else \
            mesh.refined(np.flatnonzero(marked))
    finally:
        skfem_log.setLevel(level)
    labels = mesh.boundaries or {}
    if not labels:
        return new
    old_bf = mesh.boundary_facets()
    bf = new.boundary_facets()
    parent = facet_containing(mesh, old_bf, _facet_midpoints(new, bf))
    has = np.zeros(mesh.facets.shape[1], dtype=bool)
    out = {}
    for name, facets in labels.items():
        has[:] = False
        has[np.asarray(facets, dtype=np.int64)] = True
        sel = (parent >= 0) & has[old_bf[np.maximum(parent, 0)]]
        out[name] = np.sort(bf[sel]).astype(np.int32)
    return new.with_boundaries(out)


def is_conforming(mesh, reference) -> bool:
    """No hanging nodes: every facet of ``mesh`` with one neighbour lies on a boundary
    facet of ``reference`` (a conforming mesh of the same domain, e.g. the initial one),
    and every vertex belongs to some cell."""
    bf = mesh.boundary_facets()
    on = facet_containing(reference, reference.boundary_facets(), _facet_midpoints(mesh, bf))
    used = np.zeros(mesh.p.shape[1], dtype=bool)
    used[mesh.t.ravel()] = True
    return bool(np.all(on >= 0) and np.all(used))


def new_vertices(mesh0, mesh) -> np.ndarray:
    """Boolean mask of the vertices of ``mesh`` that are not vertices of ``mesh0``
    (coordinates compared after rounding to 12 decimals)."""
    key = np.round(np.hstack([mesh0.p, mesh.p]).T, 12) + 0.0     # + 0.0: -0.0 -> 0.0
    _, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    n0 = mesh0.p.shape[1]
    return ~np.isin(inv[n0:], inv[:n0])


def distance_to_set(points, segments=(), vertices=()) -> np.ndarray:
    """Distance of the points (2, n) to the union of the ``segments`` ((a, b) pairs of
    points) and the single points ``vertices``."""
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[0] != 2:
        raise ValueError(f"points must have shape (2, n), got {p.shape}")
    d = np.full(p.shape[1], np.inf)
    for a, b in segments:
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        ab = b - a
        lam = ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / (ab @ ab)
        # beyond an end: the distance to that end point, computed from it
        dx = np.where(lam <= 0, p[0] - a[0], np.where(lam >= 1, p[0] - b[0],
                                                      p[0] - a[0] - lam * ab[0]))
        dy = np.where(lam <= 0, p[1] - a[1], np.where(lam >= 1, p[1] - b[1],
                                                      p[1] - a[1] - lam * ab[1]))
        d = np.minimum(d, np.hypot(dx, dy))
    if len(vertices):
        v = np.asarray(vertices, dtype=float).reshape(-1, 2)
        d = np.minimum(d, np.min(np.hypot(p[0][None] - v[:, :1], p[1][None] - v[:, 1:]),
                                 axis=0))
    return d


def local_mesh_size(mesh, points) -> np.ndarray:
    """Mesh size at each of the points (n, 2): the largest diameter h_K of the cells whose
    centroid lies within h_K of the point (NaN if there is none)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    h = cell_diameter(mesh)
    cent = mesh.p[:, mesh.t].mean(axis=1)
    dc = np.hypot(cent[0][None] - pts[:, :1], cent[1][None] - pts[:, 1:])   # (n, cells)
    near = dc <= np.maximum(h, 1e-14)[None]
    hn = np.where(near, h[None], -np.inf).max(axis=1)
    return np.where(near.any(axis=1), hn, math.nan)


@dataclass(frozen=True)
class Concentration:
    """Where a refinement put its vertices: ``n_new`` vertices added, ``share`` of them
    within the radius of a set, ``area_share`` of the domain within that radius."""

    n_new: int
    share: float
    area_share: float

    @property
    def enrichment(self) -> float:
        """Density of the new vertices near the set relative to their mean density."""
        if self.area_share > 0 and not math.isnan(self.share):
            return self.share / self.area_share
        return math.nan


def refinement_concentration(mesh0, mesh, distance, radius: float,
                             n_sample: int = 400) -> Concentration:
    """Share of the vertices of ``mesh`` added since ``mesh0`` with ``distance(p) <=
    radius`` (``distance`` maps points (2, n) to distances, e.g. :func:`distance_to_set`),
    and the share of the area within the radius, sampled on an n_sample x n_sample grid
    of the bounding box of ``mesh0`` (its area for a rectangle)."""
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be positive, got {radius!r}")
    if int(n_sample) != n_sample or n_sample < 2:
        raise ValueError(f"n_sample must be an integer >= 2, got {n_sample!r}")
    new = new_vertices(mesh0, mesh)
    d = np.asarray(distance(mesh.p[:, new]))
    share = float(np.mean(d <= radius)) if new.any() else math.nan
    (x0, y0), (x1, y1) = mesh0.p.min(axis=1), mesh0.p.max(axis=1)
    X, Y = np.meshgrid(np.linspace(x0, x1, int(n_sample)), np.linspace(y0, y1, int(n_sample)))
    area = float(np.mean(np.asarray(distance(np.vstack([X.ravel(), Y.ravel()]))) <= radius))
    return Concentration(int(new.sum()), share, area)
