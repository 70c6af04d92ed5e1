"""Polygonal boundary meshes of one or more closed curves.

A :class:`BoundaryMesh` is a list of straight elements ``I = [a_I, b_I]`` (node indices),
each with a boundary label (``"D"`` Dirichlet, ``"N"`` Neumann, ``"I"`` interface, ``"C"``
contact, or any user string) and its own polynomial degree ``p_I >= 1``.

Orientation: an element runs from its first to its second node; the unit normal is the
tangent turned clockwise, ``n = (t_y, -t_x)``.  Outer boundaries are counter-clockwise and
holes clockwise, so that ``n`` is the *outward* normal of a bounded domain (the convention
of the representation formula (1.2)).  Which curve is a hole follows from nesting (a curve
inside an odd number of other curves is a hole) and its direction from the sign of its
enclosed area.  The constructors :meth:`BoundaryMesh.polygon`,
:meth:`BoundaryMesh.from_segments` and :meth:`BoundaryMesh.join` *orient* every curve this
way (a reversed element keeps its label and degree); the plain constructor
``BoundaryMesh(nodes, elements, labels, degrees)`` *refuses* a wrongly oriented curve with a
ValueError naming it.  A curve enclosing no area (collinear vertices) is refused by all.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import numpy as np
from numba import njit

LABELS = {"D": "Dirichlet", "N": "Neumann", "I": "interface", "C": "contact"}


@njit(cache=True)
def _segments_cross(nodes, elements, k, l):
    """Whether elements k and l intersect (touching and collinear overlap included);
    elements sharing a node are never reported."""
    if (elements[l, 0] == elements[k, 0] or elements[l, 0] == elements[k, 1]
            or elements[l, 1] == elements[k, 0] or elements[l, 1] == elements[k, 1]):
        return False
    a0, a1 = nodes[elements[k, 0]], nodes[elements[k, 1]]
    b0, b1 = nodes[elements[l, 0]], nodes[elements[l, 1]]
    if (max(b0[0], b1[0]) < min(a0[0], a1[0]) or min(b0[0], b1[0]) > max(a0[0], a1[0])
            or max(b0[1], b1[1]) < min(a0[1], a1[1])
            or min(b0[1], b1[1]) > max(a0[1], a1[1])):
        return False
    d1 = (a1[0] - a0[0]) * (b0[1] - a0[1]) - (a1[1] - a0[1]) * (b0[0] - a0[0])
    d2 = (a1[0] - a0[0]) * (b1[1] - a0[1]) - (a1[1] - a0[1]) * (b1[0] - a0[0])
    d3 = (b1[0] - b0[0]) * (a0[1] - b0[1]) - (b1[1] - b0[1]) * (a0[0] - b0[0])
    d4 = (b1[0] - b0[0]) * (a1[1] - b0[1]) - (b1[1] - b0[1]) * (a1[0] - b0[0])
    if d1 * d2 <= 0.0 and d3 * d4 <= 0.0:
        # collinear disjoint segments give all d = 0: check the projections overlap
        if d1 == 0.0 and d2 == 0.0:
            ax = a1[0] - a0[0]
            ay = a1[1] - a0[1]
            la = ax * ax + ay * ay
            t0 = ((b0[0] - a0[0]) * ax + (b0[1] - a0[1]) * ay) / la
            t1 = ((b1[0] - a0[0]) * ax + (b1[1] - a0[1]) * ay) / la
            if max(t0, t1) < 0.0 or min(t0, t1) > 1.0:
                return False
        return True
    return False


@njit(cache=True)
def _grid_cells(nodes, elements, x0, y0, c, ny, pad, fill, keys, owner):
    """Cells of a uniform grid (size ``c``, origin ``(x0, y0)``) met by each element:
    column by column, the y-range of the segment inside the column (padded by ``pad``).
    Returns the number of (cell, element) pairs; fills ``keys``/``owner`` if ``fill``."""
    cnt = 0
    for k in range(elements.shape[0]):
        ax, ay = nodes[elements[k, 0], 0], nodes[elements[k, 0], 1]
        bx, by = nodes[elements[k, 1], 0], nodes[elements[k, 1], 1]
        i0 = int(np.floor((min(ax, bx) - pad - x0) / c))
        i1 = int(np.floor((max(ax, bx) + pad - x0) / c))
        for i in range(i0, i1 + 1):
            if ax == bx:
                ylo, yhi = min(ay, by), max(ay, by)
            else:
                xl = max(min(ax, bx), x0 + i * c)
                xr = min(max(ax, bx), x0 + (i + 1) * c)
                yl = ay + (by - ay) * (xl - ax) / (bx - ax)
                yr = ay + (by - ay) * (xr - ax) / (bx - ax)
                ylo, yhi = min(yl, yr), max(yl, yr)
            j0 = int(np.floor((ylo - pad - y0) / c))
            j1 = int(np.floor((yhi + pad - y0) / c))
            for j in range(j0, j1 + 1):
                if fill:
                    keys[cnt] = i * ny + j
                    owner[cnt] = k
                cnt += 1
    return cnt


@njit(cache=True)
def _first_crossing_in_cells(nodes, elements, owner, starts):
    """Smallest pair (k, l), k < l, of crossing elements registered in one grid cell
    (cell g holds ``owner[starts[g]:starts[g + 1]]``), or (-1, -1)."""
    bk, bl = -1, -1
    for g in range(starts.shape[0] - 1):
        for s in range(starts[g], starts[g + 1]):
            for t in range(s + 1, starts[g + 1]):
                k, l = min(owner[s], owner[t]), max(owner[s], owner[t])
                if k == l or (bk >= 0 and (k > bk or (k == bk and l >= bl))):
                    continue
                if _segments_cross(nodes, elements, k, l):
                    bk, bl = k, l
    return bk, bl


def _first_crossing(nodes, elements):
    """First pair (k, l) of elements that intersect without sharing a node, or (-1, -1).

    Near-linear: the elements are registered in the cells of a uniform grid of the mean
    element length that they pass through, and only elements sharing a cell are tested
    (expected O(ne) for meshes without strong grading; O(k^2) in a cell holding k
    elements)."""
    a, b = nodes[elements[:, 0]], nodes[elements[:, 1]]
    lengths = np.linalg.norm(b - a, axis=1)
    lo = np.minimum(a, b).min(axis=0)
    hi = np.maximum(a, b).max(axis=0)
    c = max(float(lengths.mean()), 1e-6 * float((hi - lo).max()), np.finfo(float).tiny)
    pad = 1e-9 * c
    x0, y0 = lo[0] - c, lo[1] - c
    ny = int(np.floor((hi[1] + pad - y0) / c)) + 2
    empty_i = np.zeros(0, dtype=np.int64)
    cnt = _grid_cells(nodes, elements, x0, y0, c, ny, pad, False, empty_i, empty_i)
    keys = np.empty(cnt, dtype=np.int64)
    owner = np.empty(cnt, dtype=np.int64)
    _grid_cells(nodes, elements, x0, y0, c, ny, pad, True, keys, owner)
    order = np.argsort(keys, kind="stable")
    keys, owner = keys[order], owner[order]
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1], True]).astype(np.int64)
    k, l = _first_crossing_in_cells(nodes, elements, owner, starts)
    return int(k), int(l)


def _curve_index(elements: np.ndarray, n_nodes: int) -> np.ndarray:
    """Curve number of every element (connected components of the element graph,
    numbered in the order of their first element)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    g = coo_matrix((np.ones(len(elements)), (elements[:, 0], elements[:, 1])),
                   shape=(n_nodes, n_nodes))
    _, comp = connected_components(g, directed=False)
    comp = comp[elements[:, 0]]
    _, first, inv = np.unique(comp, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    return rank[inv]


def _curve_orientation(nodes, elements, curve, scale):
    """Per curve: twice its signed area (> 0 counter-clockwise) and its nesting depth
    (the number of other curves enclosing it; even = an outer boundary, odd = a hole).

    ValueError for a curve enclosing no area (collinear vertices)."""
    a, b = nodes[elements[:, 0]], nodes[elements[:, 1]]
    nc = int(curve.max()) + 1
    area2 = np.bincount(curve, a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1], minlength=nc)
    for c in np.flatnonzero(np.abs(area2) <= 1e-12 * scale ** 2):
        el = np.flatnonzero(curve == c)
        raise ValueError(f"curve {c} (elements {_span(el)}) encloses zero area: its "
                         "vertices are collinear")
    depth = np.zeros(nc, dtype=np.int64)
    if nc > 1:
        probe = a[np.unique(curve, return_index=True)[1]]        # one node per curve
        for c in range(nc):   # crossing number of a ray to +x from every probe
            on = curve == c
            ya, yb, xa, xb = a[on, 1], b[on, 1], a[on, 0], b[on, 0]
            py, px = probe[:, 1:2], probe[:, 0:1]
            straddle = (ya <= py) != (yb <= py)
            with np.errstate(divide="ignore", invalid="ignore"):
                xc = xa + (py - ya) * (xb - xa) / (yb - ya)
            inside = (np.count_nonzero(straddle & (xc > px), axis=1) % 2) == 1
            inside[c] = False
            depth += inside
    return area2, depth


def _span(idx) -> str:
    idx = np.asarray(idx)
    if len(idx) and idx[-1] - idx[0] == len(idx) - 1:
        return f"{idx[0]}..{idx[-1]}"
    return str(idx.tolist()[:8])[:-1] + (", ...]" if len(idx) > 8 else "]")


def _as_degrees(p, name: str = "p") -> np.ndarray:
    """Integer degrees from ``p`` (scalar or array); ValueError for booleans, non-integer
    or non-finite values (never truncated: 2.7 is not 2, True is not 1)."""
    if not isinstance(p, np.ndarray):
        flat = p if isinstance(p, (list, tuple)) else [p]
        if any(isinstance(x, (bool, np.bool_)) for x in flat):
            raise ValueError(f"{name} must be integer degrees >= 1, got a boolean in {p!r}")
    arr = np.asarray(p)
    if arr.dtype.kind == "b":
        raise ValueError(f"{name} must be integer degrees >= 1, got booleans")
    if arr.dtype.kind in "iu":
        return arr.astype(np.int64)
    if arr.dtype.kind != "f":
        raise ValueError(f"{name} must be integer degrees >= 1, got {p!r}")
    bad = ~np.isfinite(arr) | (arr != np.round(arr))
    if np.any(bad):
        raise ValueError(f"{name} must be integer degrees >= 1, got "
                         f"{arr[bad].ravel()[0]!r} (degrees are never rounded)")
    return arr.astype(np.int64)


def _as_per_side(value, nsides: int, name: str):
    if isinstance(value, (str, int, float, np.integer, np.floating)) or value is None:
        return [value] * nsides
    value = list(value)
    if len(value) != nsides:
        raise ValueError(f"{name} must be a scalar or one value per side ({nsides}), "
                         f"got {len(value)} values")
    return value


COORD_MIN, COORD_MAX = 1e-100, 1e100   # extent and size of a mesh's coordinates


@dataclass(frozen=True, eq=False)
class BoundaryMesh:
    """Straight elements on closed polygonal curves.

    Parameters
    ----------
    nodes : (nn, 2) float array
    elements : (ne, 2) int array of node indices (direction = orientation)
    labels : (ne,) str array, one label per element
    degrees : (ne,) int array, polynomial degree p_I >= 1 of each element
    parent : (ne,) int array or None; set by :meth:`refine` and :meth:`with_degrees`:
        ``parent[k]`` is the element of ``parent_mesh`` that contains element k
    parent_mesh : the mesh this one was refined from (None for a built mesh)
    """

    nodes: np.ndarray
    elements: np.ndarray
    labels: np.ndarray
    degrees: np.ndarray
    _checked: bool = field(default=False, repr=False)
    _orient: bool = field(default=False, repr=False)
    parent: np.ndarray | None = field(default=None, repr=False)
    parent_mesh: "BoundaryMesh | None" = field(default=None, repr=False)

    def __post_init__(self):
        nodes = np.ascontiguousarray(self.nodes, dtype=float)
        elements = np.ascontiguousarray(self.elements, dtype=np.int64)
        labels = np.asarray(self.labels, dtype=str)
        degrees = np.ascontiguousarray(
            self.degrees if self._checked else _as_degrees(self.degrees, "degrees"),
            dtype=np.int64)
        for name, arr in (("nodes", nodes), ("elements", elements), ("labels", labels),
                          ("degrees", degrees)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if (self.parent is None) != (self.parent_mesh is None):
            raise ValueError("parent and parent_mesh must be given together")
        if self.parent is not None:
            parent = np.ascontiguousarray(self.parent, dtype=np.int64)
            if parent.shape != (len(elements),):
                raise ValueError(f"parent must have one entry per element ({len(elements)}),"
                                 f" got shape {parent.shape}")
            parent.setflags(write=False)
            object.__setattr__(self, "parent", parent)
        if not self._checked:
            self._validate()

    # ------------------------------------------------------------------ validation
    def _validate(self):
        nodes, elements = self.nodes, self.elements
        if nodes.ndim != 2 or nodes.shape[1] != 2 or len(nodes) == 0:
            raise ValueError(f"nodes must have shape (n, 2), got {nodes.shape}")
        if not np.all(np.isfinite(nodes)):
            raise ValueError("nodes contain NaN or infinite coordinates")
        size, extent = float(np.abs(nodes).max()), float(np.ptp(nodes, axis=0).max())
        if size > COORD_MAX or extent < COORD_MIN:
            # lengths, kernels and quadrature square distances: beyond these they
            # overflow or underflow (a 1e-170 square had "zero-length" elements)
            raise ValueError(f"nodes: coordinates up to {size:.3g} with extent {extent:.3g} "
                             f"are outside [{COORD_MIN:g}, {COORD_MAX:g}], where squared "
                             "distances overflow or underflow; rescale the geometry")
        if elements.ndim != 2 or elements.shape[1] != 2 or len(elements) < 3:
            raise ValueError(f"elements must have shape (ne, 2) with ne >= 3, "
                             f"got {elements.shape}")
        if elements.min() < 0 or elements.max() >= len(nodes):
            raise ValueError("elements refer to node indices outside 0..len(nodes)-1")
        ne = len(elements)
        if self.labels.shape != (ne,):
            raise ValueError(f"labels must have one entry per element ({ne}), "
                             f"got shape {self.labels.shape}")
        if self.degrees.shape != (ne,):
            raise ValueError(f"degrees must have one entry per element ({ne}), "
                             f"got shape {self.degrees.shape}")
        if self.degrees.min() < 1:
            k = int(np.argmin(self.degrees))
            raise ValueError(f"degree p_I must be >= 1, got p={self.degrees[k]} on element {k}")
        lengths = np.linalg.norm(nodes[elements[:, 1]] - nodes[elements[:, 0]], axis=1)
        scale = max(np.ptp(nodes, axis=0).max(), np.finfo(float).tiny)
        if lengths.min() <= 1e-13 * scale:
            k = int(np.argmin(lengths))
            raise ValueError(f"zero-length element: element {k} (nodes {elements[k].tolist()})"
                             f" has length {lengths[k]:.3g}")
        used = np.unique(elements)
        # repeated points: two distinct used nodes at the same place
        pts = nodes[used]
        order = np.lexsort((pts[:, 1], pts[:, 0]))
        gaps = np.linalg.norm(np.diff(pts[order], axis=0), axis=1)
        if gaps.size and gaps.min() <= 1e-13 * scale:
            k = int(np.argmin(gaps))
            a, b = used[order[k]], used[order[k + 1]]
            raise ValueError(f"repeated point: nodes {a} and {b} coincide at "
                             f"{nodes[a].tolist()}")
        # closed curves: every node starts exactly one element and ends exactly one
        starts = np.bincount(elements[:, 0], minlength=len(nodes))
        ends = np.bincount(elements[:, 1], minlength=len(nodes))
        bad = np.flatnonzero((starts != ends) | (starts > 1))
        if bad.size:
            k = int(bad[0])
            raise ValueError(f"curve is not closed: node {k} at {nodes[k].tolist()} starts "
                             f"{starts[k]} and ends {ends[k]} elements (each node must end "
                             "one element and start the next)")
        k, l = _first_crossing(nodes, elements)
        if k >= 0:
            raise ValueError(f"self-intersecting boundary: elements {k} and {l} cross")
        self._check_orientation(scale)

    def _check_orientation(self, scale: float):
        """Outer curves counter-clockwise, holes clockwise: flip wrongly oriented curves
        if ``_orient`` (reversing their elements in place, with labels and degrees),
        else ValueError naming the first wrong curve."""
        curve = _curve_index(self.elements, len(self.nodes))
        area2, depth = _curve_orientation(self.nodes, self.elements, curve, scale)
        wrong = np.flatnonzero(np.sign(area2) != np.where(depth % 2 == 0, 1.0, -1.0))
        if wrong.size == 0:
            return
        if not self._orient:
            c = int(wrong[0])
            el = np.flatnonzero(curve == c)
            kind = "an outer boundary" if depth[c] % 2 == 0 else \
                f"a hole (inside {depth[c]} other curve(s))"
            want = "counter-clockwise" if depth[c] % 2 == 0 else "clockwise"
            raise ValueError(
                f"wrongly oriented curve {c} (elements {_span(el)}, from node "
                f"{self.elements[el[0], 0]} at {self.nodes[self.elements[el[0], 0]].tolist()})"
                f": it is {kind} and must run {want} so that the normal points out of the "
                "domain; reverse its elements, or build the mesh with "
                "BoundaryMesh.from_segments / join / polygon, which orient every curve")
        perm = np.arange(self.n_elements)
        for c in wrong:   # reverse the order of the curve's elements within their slots
            el = np.flatnonzero(curve == c)
            perm[el] = el[::-1]
        elements = self.elements[perm].copy()
        flip = np.isin(curve[perm], wrong)
        elements[flip] = elements[flip][:, ::-1]
        for name, arr in (("elements", np.ascontiguousarray(elements)),
                          ("labels", self.labels[perm]), ("degrees", self.degrees[perm])):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_segments(cls, nodes, segments, labels="N", p=1) -> "BoundaryMesh":
        """Mesh from explicit nodes and segments (any number of closed curves).

        ``labels`` and ``p`` are one value for all or one per segment.  Every curve is
        oriented (outer curves counter-clockwise, holes clockwise; see the module
        docstring): the elements of a wrongly oriented curve are reversed, keeping
        their labels and degrees, so ``mesh.elements`` may differ from ``segments``."""
        segments = np.asarray(segments)
        ne = len(segments)
        labels = np.asarray(_as_per_side(labels, ne, "labels"), dtype=str)
        degrees = _as_degrees(_as_per_side(p, ne, "p"), "p")
        return cls(nodes, segments, labels, degrees, _orient=True)

    @classmethod
    def polygon(cls, vertices, n=None, h=None, labels="N", p=1) -> "BoundaryMesh":
        """Mesh of one closed polygon.

        Parameters
        ----------
        vertices : (m, 2) corners, in order (either orientation; the mesh is made
            counter-clockwise so that normals point outward)
        n : int or list of int, number of elements per side
        h : float or list of float, maximal element size per side (if ``n`` is None)
        labels : str or list of str, one label per side (side k joins vertex k and k+1)
        p : int or list of int, polynomial degree per side
        """
        try:
            v = np.asarray(vertices, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"vertices must be an (m, 2) array of numbers, got "
                             f"{vertices!r}") from None
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3:
            raise ValueError(f"vertices must have shape (m, 2) with m >= 3, got {v.shape}")
        m = len(v)
        labels = _as_per_side(labels, m, "labels")
        ps = _as_per_side(p, m, "p")
        if n is None and h is None:
            n = 1
        if n is not None:
            ns = _as_per_side(n, m, "n")
            for k in ns:
                if isinstance(k, (bool, np.bool_)) or not isinstance(
                        k, (int, float, np.integer, np.floating)) or not np.isfinite(k) \
                        or int(k) != k or k < 1:
                    raise ValueError(f"n (elements per side) must be integers >= 1, got {n!r}")
        else:
            hs = _as_per_side(h, m, "h")
            for k in hs:
                if isinstance(k, (bool, np.bool_)) or not isinstance(
                        k, (int, float, np.integer, np.floating)) or not (
                        np.isfinite(k) and k > 0):
                    raise ValueError(f"h (element size) must be positive, got {h!r}")
        ps = list(_as_degrees(ps, "p"))
        side_len = np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
        if n is None:
            ns = [max(1, int(np.ceil(L / hk - 1e-9))) for L, hk in zip(side_len, hs)]
        pts, lab, deg = [], [], []
        for k in range(m):
            t = np.arange(int(ns[k]))[:, None] / int(ns[k])
            pts.append(v[k] + t * (v[(k + 1) % m] - v[k]))
            lab += [labels[k]] * int(ns[k])
            deg += [ps[k]] * int(ns[k])
        nodes = np.vstack(pts)
        ne = len(nodes)
        seg = np.column_stack([np.arange(ne), (np.arange(ne) + 1) % ne])
        # side k joins v_k and v_k+1 as given; from_segments reverses a clockwise polygon
        # element by element, so each side keeps its label, element count and degree
        return cls.from_segments(nodes, seg, lab, deg)

    @classmethod
    def join(cls, *meshes: "BoundaryMesh") -> "BoundaryMesh":
        """Several closed curves in one mesh (e.g. an outer boundary and a hole).

        Every curve is oriented by nesting (see the module docstring): a hole built with
        :meth:`polygon` (counter-clockwise) is reversed to run clockwise."""
        for k, m in enumerate(meshes):
            if not isinstance(m, BoundaryMesh):
                raise ValueError(f"meshes[{k}] must be a BoundaryMesh, got "
                                 f"{type(m).__name__}")
        if not meshes:
            raise ValueError("join needs at least one BoundaryMesh")
        offs = np.cumsum([0] + [len(m.nodes) for m in meshes])
        return cls(np.vstack([m.nodes for m in meshes]),
                   np.vstack([m.elements + o for m, o in zip(meshes, offs)]),
                   np.concatenate([m.labels for m in meshes]),
                   np.concatenate([m.degrees for m in meshes]), _orient=True)

    # ------------------------------------------------------------------ geometry
    @property
    def n_elements(self) -> int:
        return len(self.elements)

    @property
    def n_curves(self) -> int:
        """Number of closed curves (connected components of the element graph)."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        used = np.unique(self.elements)
        nn = len(self.nodes)
        g = coo_matrix((np.ones(self.n_elements), (self.elements[:, 0], self.elements[:, 1])),
                       shape=(nn, nn))
        ncomp, lab = connected_components(g, directed=False)
        return int(len(np.unique(lab[used])))

    @property
    def a(self) -> np.ndarray:
        """Start points of the elements, (ne, 2)."""
        return self.nodes[self.elements[:, 0]]

    @property
    def b(self) -> np.ndarray:
        """End points of the elements, (ne, 2)."""
        return self.nodes[self.elements[:, 1]]

    @property
    def lengths(self) -> np.ndarray:
        return np.linalg.norm(self.b - self.a, axis=1)

    @property
    def tangents(self) -> np.ndarray:
        return (self.b - self.a) / self.lengths[:, None]

    @property
    def normals(self) -> np.ndarray:
        """Unit normals (t_y, -t_x): outward for counter-clockwise outer boundaries."""
        t = self.tangents
        return np.column_stack([t[:, 1], -t[:, 0]])

    @property
    def h_max(self) -> float:
        return float(self.lengths.max())

    @property
    def diameter(self) -> float:
        """Largest distance between two nodes (attained at vertices of the convex hull)."""
        from scipy.spatial import ConvexHull

        used = self.nodes[np.unique(self.elements)]
        hull = used[ConvexHull(used).vertices]
        return float(np.max(np.linalg.norm(hull[:, None, :] - hull[None, :, :], axis=2)))

    def points(self, elem, t) -> np.ndarray:
        """Physical points of reference coordinates ``t`` in [-1, 1] on elements ``elem``."""
        elem = np.asarray(elem)
        t = np.asarray(t, dtype=float)
        s = 0.5 * (t + 1.0)
        return self.a[elem] + s[..., None] * (self.b[elem] - self.a[elem])

    def where(self, *labels: str) -> np.ndarray:
        """Boolean mask of the elements carrying any of ``labels``."""
        return np.isin(self.labels, labels)

    @property
    def scale(self) -> float:
        """Largest coordinate extent of the used nodes (the length scale of tolerances)."""
        used = self.nodes[np.unique(self.elements)]
        return max(float(np.ptp(used, axis=0).max()), np.finfo(float).tiny)

    def locate(self, points, tol: float = 5e-11, chunk: int = 2048):
        """Element and reference coordinate of points lying on the boundary.

        Returns ``(elem, t)``: for each point the element nearest to it (the first one on
        ties, e.g. at a vertex) and ``t`` in [-1, 1] of the nearest point on it; ``elem``
        is -1 (and ``t`` NaN) for points farther than ``tol * scale`` from the mesh."""
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
        if not (np.isfinite(tol) and tol >= 0):
            raise ValueError(f"tol must be finite and >= 0, got {tol!r}")
        a, ab = self.a, self.b - self.a
        L2 = np.sum(ab ** 2, 1)
        elem = np.full(len(pts), -1, dtype=np.int64)
        t = np.full(len(pts), np.nan)
        for i0 in range(0, len(pts), chunk):
            p = pts[i0:i0 + chunk]
            d = p[:, None, :] - a[None, :, :]                       # (m, ne, 2)
            s = np.clip(np.einsum("mek,ek->me", d, ab) / L2, 0.0, 1.0)
            dist = np.linalg.norm(d - s[..., None] * ab, axis=2)
            e = np.argmin(dist, axis=1)
            rows = np.arange(len(p))
            on = dist[rows, e] <= tol * self.scale
            elem[i0:i0 + chunk] = np.where(on, e, -1)
            t[i0:i0 + chunk] = np.where(on, 2.0 * s[rows, e] - 1.0, np.nan)
        return elem, t

    # ------------------------------------------------------------------ refinement
    def _replace(self, **kw) -> "BoundaryMesh":
        args = dict(nodes=self.nodes, elements=self.elements, labels=self.labels,
                    degrees=self.degrees, _checked=True, parent=None, parent_mesh=None)
        args.update(kw)
        return BoundaryMesh(**args)

    def _marked(self, marked) -> np.ndarray:
        ne = self.n_elements
        if marked is None:
            return np.ones(ne, dtype=bool)
        marked = np.asarray(marked)
        if marked.dtype == bool:
            if marked.shape != (ne,):
                raise ValueError(f"marked mask must have shape ({ne},), got {marked.shape}")
            return marked
        if marked.size and (marked.min() < 0 or marked.max() >= ne):
            raise ValueError(f"marked element indices must lie in 0..{ne - 1}")
        mask = np.zeros(ne, dtype=bool)
        mask[marked.astype(int)] = True
        return mask

    def refine(self, marked=None) -> "BoundaryMesh":
        """Bisect the marked elements (all if ``marked`` is None); labels and degrees are
        inherited, element order along the curves is kept.  The refined mesh carries
        ``parent`` (the element of this mesh each new element came from) and
        ``parent_mesh`` (this mesh)."""
        mask = self._marked(marked)
        ne, nn = self.n_elements, len(self.nodes)
        mid_idx = nn + np.cumsum(mask) - 1
        new_nodes = np.vstack([self.nodes, 0.5 * (self.a[mask] + self.b[mask])])
        reps = np.where(mask, 2, 1)
        parent = np.repeat(np.arange(ne), reps)
        first = np.ones(len(parent), dtype=bool)
        first[1:] = parent[1:] != parent[:-1]
        el = self.elements[parent].copy()
        split = mask[parent]
        el[split & first, 1] = mid_idx[parent[split & first]]
        el[split & ~first, 0] = mid_idx[parent[split & ~first]]
        return self._replace(nodes=new_nodes, elements=el, labels=self.labels[parent],
                             degrees=self.degrees[parent], parent=parent, parent_mesh=self)

    def with_degrees(self, p) -> "BoundaryMesh":
        """The same mesh with degree ``p`` (scalar or per element); its ``parent`` is the
        identity map into this mesh."""
        try:
            p = np.broadcast_to(_as_degrees(p, "p"), (self.n_elements,))
        except ValueError as err:
            if "broadcast" not in str(err):
                raise
            raise ValueError(f"p must be a scalar or one degree per element "
                             f"({self.n_elements})") from None
        if p.min() < 1:
            raise ValueError(f"degree p must be >= 1, got {p.min()}")
        return self._replace(degrees=p.copy(), parent=np.arange(self.n_elements),
                             parent_mesh=self)

    def ancestor_map(self, ancestor: "BoundaryMesh") -> np.ndarray | None:
        """For each element, the element of ``ancestor`` containing it, by composing the
        ``parent`` maps up the chain of refinements; None if ``ancestor`` is not in the
        chain (then use geometry, e.g. :func:`hpfebe.spaces.prolongate`)."""
        m, idx = self, np.arange(self.n_elements)
        while m is not ancestor:
            if m.parent is None:
                return None
            idx = m.parent[idx]
            m = m.parent_mesh
        return idx

    def raise_degree(self, marked=None, by: int = 1) -> "BoundaryMesh":
        """Raise the degree of the marked elements by ``by``."""
        return self.with_degrees(self.degrees + by * self._marked(marked))


def common_refinement(*meshes: BoundaryMesh, tol: float = 5e-11) -> BoundaryMesh:
    """The coarsest mesh refining all given meshes of one boundary.

    The elements of the first mesh are split at every node of the others lying inside
    them (element order, orientation and labels of the first mesh; each new element
    gets the largest degree of the elements containing it, so that every mesh's spaces
    embed in its own).  ValueError if the meshes do not cover the same boundary or
    disagree on a label."""
    if not meshes:
        raise ValueError("meshes: give at least one mesh")
    for k, m in enumerate(meshes):
        if not isinstance(m, BoundaryMesh):
            raise ValueError(f"meshes[{k}] must be a BoundaryMesh, got {type(m).__name__}")
    base = meshes[0]
    # every mesh's nodes lie on every other mesh (same boundary)
    for k, m in enumerate(meshes):
        for j, other in enumerate(meshes):
            if j != k and np.any(other.locate(m.nodes[np.unique(m.elements)], tol)[0] < 0):
                raise ValueError(f"meshes: a node of mesh {k} does not lie on mesh {j} "
                                 "(not the same boundary)")
    # points inside the base elements where another mesh has a node
    pts = np.vstack([m.nodes[np.unique(m.elements)] for m in meshes[1:]] or
                    [np.zeros((0, 2))])
    e, t = base.locate(pts, tol)
    s = 0.5 * (t + 1.0)
    inner = (s * base.lengths[e] > tol * base.scale) & \
        ((1.0 - s) * base.lengths[e] > tol * base.scale)
    e, s, pts = e[inner], s[inner], pts[inner]
    order = np.lexsort((s, e))
    e, s, pts = e[order], s[order], pts[order]
    # drop repeated points (the same node in several meshes)
    keep = np.ones(len(e), dtype=bool)
    keep[1:] = (e[1:] != e[:-1]) | ((s[1:] - s[:-1]) * base.lengths[e[1:]] > tol * base.scale)
    e, pts = e[keep], pts[keep]
    # new elements, in base element order: start node of each, then the interior ones
    nb = base.n_elements
    counts = np.bincount(e, minlength=nb) + 1
    owner = np.repeat(np.arange(nb), counts)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    starts = np.empty((len(owner), 2))
    starts[first] = base.a
    is_inner = np.ones(len(owner), dtype=bool)
    is_inner[first] = False
    starts[is_inner] = pts
    # node numbering by first appearance as a start point; an element ends where the next
    # element of its base element starts, or at the base element's end node
    is_last = np.zeros(len(owner), dtype=bool)
    is_last[np.append(first[1:], len(owner)) - 1] = True
    start_id = np.arange(len(owner))
    base_start_id = np.zeros(len(base.nodes), dtype=np.int64)
    base_start_id[base.elements[:, 0]] = first
    end_id = np.where(is_last, base_start_id[base.elements[owner, 1]], start_id + 1)
    seg = np.column_stack([start_id, end_id])
    mid = 0.5 * (starts + starts[end_id])
    labels = base.labels[owner]
    degrees = base.degrees[owner].copy()
    for k, m in enumerate(meshes[1:], start=1):
        em, _ = m.locate(mid, tol)
        if np.any(m.labels[em] != labels):
            raise ValueError(f"meshes: mesh {k} has other boundary labels than mesh 0")
        degrees = np.maximum(degrees, m.degrees[em])
    return BoundaryMesh(starts, seg, labels, degrees)
