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

Grading.  Any ratio of element lengths is accepted, without a warning (decided in issue
25).  cond(V) grows like (h_max / h_min)^2 on a graded mesh (4e13 at a ratio 1e-6, p = 3),
but that is the scaling of the basis, not a loss of accuracy: the diagonally scaled
D^-1/2 V D^-1/2 has cond ~1e2 up to a ratio 1e-8, and the Cholesky solve of Psi is
accurate to the scaled condition number in the length-weighted norm (van der Sluis;
measured at a ratio 1e-8, cond(V) 4e17: Psi equals the scaled solve to 9e-16 in that
norm, tests/hostile/test_hostile_bem.py; single coefficients on the 1e-8 elements differ
by 8e-10).  The larger error of Psi on such a mesh (1.4e-3 at a ratio 1e-6 with 8
elements on the graded side, the issue's 7e-4) is the discretisation error of its large
elements: one uniform bisection divides it by 10.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..checks import array, integer, real
from .orientation import orient_curves
from . import refinement
from .validation import _as_degrees, _as_per_side, validate

LABELS = {"D": "Dirichlet", "N": "Neumann", "I": "interface", "C": "contact"}
#: the most elements :meth:`BoundaryMesh.polygon` builds (a dense BEM on 1e7 elements
#: would need 1e14 matrix entries)
MAX_ELEMENTS = 10 ** 7


@dataclass(frozen=True, eq=False)
class BoundaryMesh:
    """Straight elements on closed polygonal curves.

    Parameters
    ----------
    nodes
        (nn, 2) float array
    elements
        (ne, 2) int array of node indices (direction = orientation)
    labels
        (ne,) str array, one label per element
    degrees
        (ne,) int array, polynomial degree p_I >= 1 of each element
    parent
        (ne,) int array or None; set by :meth:`refine` and :meth:`with_degrees`:
        ``parent[k]`` is the element of ``parent_mesh`` that contains element k
    parent_mesh
        the mesh this one was refined from (None for a built mesh)
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

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        """The mesh itself: it is immutable (frozen, read-only arrays).  A deep copy would
        make its arrays writable, a new argument type for every numba kernel that takes
        them (a scene copied by ``copy.deepcopy`` compiled the BEM kernels once more)."""
        return self

    # ------------------------------------------------------------------ validation
    def _validate(self):
        """The checks of :func:`.validation.validate`; then every curve oriented
        (:func:`.orientation.orient_curves`): outer curves counter-clockwise, holes
        clockwise, wrongly oriented curves flipped if ``_orient`` (their elements
        reversed in place, with labels and degrees), else a ValueError naming the first
        wrong curve."""
        scale = validate(self.nodes, self.elements, self.labels, self.degrees)
        fixed = orient_curves(self.nodes, self.elements, scale, self._orient)
        if fixed is None:
            return
        elements, perm = fixed
        for name, arr in (("elements", elements),
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
        nodes = array("nodes", nodes, shape=(None, 2))
        segments = array("segments", segments, shape=(None, 2), dtype=np.int64)
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
        v = array("vertices", vertices, shape=(None, 2))      # finite numbers, (m, 2)
        if len(v) < 3:
            raise ValueError(f"vertices must have shape (m, 2) with m >= 3, got {v.shape}")
        m = len(v)
        labels = _as_per_side(labels, m, "labels")
        ps = _as_per_side(p, m, "p")
        if n is None and h is None:
            n = 1
        if n is not None:     # elements per side: integers >= 1, never rounded
            ns = [integer("n" if np.ndim(n) == 0 else f"n[{k}]", x, lo=1)
                  for k, x in enumerate(_as_per_side(n, m, "n"))]
        else:                 # element sizes: finite and positive
            hs = [real("h" if np.ndim(h) == 0 else f"h[{k}]", x, positive=True)
                  for k, x in enumerate(_as_per_side(h, m, "h"))]
        ps = list(_as_degrees(ps, "p"))
        side_len = np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
        if n is None:
            ns = [max(1, int(np.ceil(L / hk - 1e-9))) for L, hk in zip(side_len, hs)]
        if sum(ns) > MAX_ELEMENTS:      # h = 1e-20 asked numpy for 1e20 nodes
            name, value = ("h", h) if n is None else ("n", n)
            raise ValueError(f"{name} gives {sum(ns):.3g} elements, more than "
                             f"{MAX_ELEMENTS:.0e}: got {name}={value!r}")
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
        """Unit normals (t_y, -t_x), outward for counter-clockwise outer boundaries."""
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

    def refine(self, marked=None) -> "BoundaryMesh":
        """Bisect the marked elements (all if ``marked`` is None); labels and degrees are
        inherited, element order along the curves is kept.  The refined mesh carries
        ``parent`` (the element of this mesh each new element came from) and
        ``parent_mesh`` (this mesh)."""
        return refinement.bisect(self, marked)

    def with_degrees(self, p) -> "BoundaryMesh":
        """The same mesh with degree ``p`` (scalar or per element); its ``parent`` is the
        identity map into this mesh."""
        return refinement.with_degrees(self, p)

    def ancestor_map(self, ancestor: "BoundaryMesh") -> np.ndarray | None:
        """For each element, the element of ``ancestor`` containing it, by composing the
        ``parent`` maps up the chain of refinements; None if ``ancestor`` is not in the
        chain (then use geometry, e.g. :func:`hpfebe.spaces.prolongate`)."""
        return refinement.ancestor_map(self, ancestor)

    def raise_degree(self, marked=None, by: int = 1) -> "BoundaryMesh":
        """Raise the degree of the marked elements by ``by``."""
        return self.with_degrees(self.degrees + by * refinement.marked_mask(self, marked))
