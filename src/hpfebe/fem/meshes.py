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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from skfem import MeshQuad


def block_grid(breaks: Sequence[float], h_inv: float, rounding: str = "floor") -> np.ndarray:
    """1D grid of cells of size about 1/h_inv through all ``breaks``.

    ``rounding="floor"`` (default): the break b_k becomes grid line number
    floor((b_k - b_0) h_inv) of a uniform grid (the last one: ceil), and each block is
    divided equally: the total count is that of the uniform grid, a break that falls
    between grid lines takes the lower one.  ``rounding="ceil"``: every block of length L
    gets ceil(L h_inv) cells (no cell larger than 1/h_inv)."""
    b = np.unique(np.asarray(breaks, dtype=float))
    if b.size < 2:
        raise ValueError(f"breaks must contain at least two distinct values, got {breaks!r}")
    if not (np.isfinite(h_inv) and h_inv > 0):
        raise ValueError(f"h_inv must be positive, got {h_inv!r}")
    if rounding == "floor":
        k = np.floor((b - b[0]) * h_inv + 1e-9)
        k[-1] = np.ceil((b[-1] - b[0]) * h_inv - 1e-9)
        counts = np.maximum(np.diff(k), 1).astype(int)
    elif rounding == "ceil":
        counts = np.maximum(np.ceil(np.diff(b) * h_inv - 1e-9), 1).astype(int)
    else:
        raise ValueError(f"rounding must be 'floor' or 'ceil', got {rounding!r}")
    pts = [b[:1]]
    for lo, hi, n in zip(b[:-1], b[1:], counts):
        pts.append(np.linspace(lo, hi, n + 1)[1:])
    return np.concatenate(pts)


@dataclass(frozen=True)
class FEDomain:
    """A quadrilateral mesh with labelled boundary facets.

    ``facets[label]`` are the boundary facet indices of ``mesh`` carrying ``label``
    ("D", "N", "I", ...).  ``h_inv`` is the nominal inverse mesh size it was built for.
    """

    mesh: MeshQuad
    facets: dict
    h_inv: float

    @property
    def n_elements(self) -> int:
        return self.mesh.t.shape[1]

    def facet_length(self, facets) -> np.ndarray:
        p = self.mesh.p[:, self.mesh.facets[:, facets]]
        return np.linalg.norm(p[:, 1] - p[:, 0], axis=0)

    def cell_diameter(self, cells) -> np.ndarray:
        """Diameter of the (convex) quadrilaterals: the longer diagonal."""
        x = self.mesh.p[:, self.mesh.t[:, cells]]
        d1 = np.linalg.norm(x[:, 2] - x[:, 0], axis=0)
        d2 = np.linalg.norm(x[:, 3] - x[:, 1], axis=0)
        return np.maximum(d1, d2)


def tensor_block_mesh(xbreaks, ybreaks, h_inv: float,
                      inside: Callable[[np.ndarray, np.ndarray], np.ndarray],
                      label: Callable[[np.ndarray, np.ndarray], np.ndarray],
                      rounding: str = "floor") -> FEDomain:
    """Conforming rectangle mesh of the subdomain ``inside(x, y)`` (see module doc).

    ``label(x, y)`` returns one label string per boundary facet midpoint."""
    xs, ys = block_grid(xbreaks, h_inv, rounding), block_grid(ybreaks, h_inv, rounding)
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
