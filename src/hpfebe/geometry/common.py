"""The common refinement of several meshes of one boundary (mortar and adaptive
comparisons on non-nested meshes)."""

from __future__ import annotations

import numpy as np

from .mesh import BoundaryMesh


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
