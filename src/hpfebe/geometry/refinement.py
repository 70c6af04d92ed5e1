"""Refinement of a boundary mesh: bisection of marked elements (h), degrees per element
(p), and the map of each element to the element of a coarser mesh containing it.  The
methods :meth:`BoundaryMesh.refine`, :meth:`~BoundaryMesh.with_degrees`,
:meth:`~BoundaryMesh.raise_degree` and :meth:`~BoundaryMesh.ancestor_map` call these;
the common refinement of several meshes: :mod:`hpfebe.geometry.common`.
"""

from __future__ import annotations

import numpy as np

from .. import checks
from .validation import _as_degrees


def marked_mask(mesh, marked) -> np.ndarray:
    """Boolean mask of the ``marked`` elements of ``mesh`` (all if None; a boolean mask
    or element indices)."""
    ne = mesh.n_elements
    if marked is None:
        return np.ones(ne, dtype=bool)
    if np.asarray(marked).dtype == bool:
        return checks.array("marked (mask)", marked, shape=(ne,), dtype=bool)
    # element indices: integers (1.5 is no element), never rounded
    marked = checks.array("marked (element indices)", marked, ndim=1, dtype=np.int64)
    if marked.size and (marked.min() < 0 or marked.max() >= ne):
        raise ValueError(f"marked element indices must lie in 0..{ne - 1}, got "
                         f"{marked.min()}..{marked.max()}")
    mask = np.zeros(ne, dtype=bool)
    mask[marked] = True
    return mask


def bisect(mesh, marked=None):
    """(:meth:`BoundaryMesh.refine`) Bisect the marked elements (all if ``marked`` is
    None); labels and degrees are inherited, element order along the curves is kept.
    The refined mesh carries ``parent`` (the element of this mesh each new element came
    from) and ``parent_mesh`` (this mesh)."""
    mask = marked_mask(mesh, marked)
    ne, nn = mesh.n_elements, len(mesh.nodes)
    mid_idx = nn + np.cumsum(mask) - 1
    new_nodes = np.vstack([mesh.nodes, 0.5 * (mesh.a[mask] + mesh.b[mask])])
    reps = np.where(mask, 2, 1)
    parent = np.repeat(np.arange(ne), reps)
    first = np.ones(len(parent), dtype=bool)
    first[1:] = parent[1:] != parent[:-1]
    el = mesh.elements[parent].copy()
    split = mask[parent]
    el[split & first, 1] = mid_idx[parent[split & first]]
    el[split & ~first, 0] = mid_idx[parent[split & ~first]]
    return mesh._replace(nodes=new_nodes, elements=el, labels=mesh.labels[parent],
                         degrees=mesh.degrees[parent], parent=parent, parent_mesh=mesh)


def with_degrees(mesh, p):
    """(:meth:`BoundaryMesh.with_degrees`) The same mesh with degree ``p`` (scalar or per
    element); its ``parent`` is the identity map into this mesh."""
    try:
        p = np.broadcast_to(_as_degrees(p, "p"), (mesh.n_elements,))
    except ValueError as err:
        if "broadcast" not in str(err):
            raise
        raise ValueError(f"p must be a scalar or one degree per element "
                         f"({mesh.n_elements})") from None
    if p.min() < 1:
        raise ValueError(f"degree p must be >= 1, got {p.min()}")
    return mesh._replace(degrees=p.copy(), parent=np.arange(mesh.n_elements),
                         parent_mesh=mesh)


def ancestor_map(mesh, ancestor) -> np.ndarray | None:
    """(:meth:`BoundaryMesh.ancestor_map`) For each element, the element of ``ancestor``
    containing it, by composing the ``parent`` maps up the chain of refinements; None if
    ``ancestor`` is not in the chain (then use geometry, e.g.
    :func:`hpfebe.spaces.prolongate`)."""
    m, idx = mesh, np.arange(mesh.n_elements)
    while m is not ancestor:
        if m.parent is None:
            return None
        idx = m.parent[idx]
        m = m.parent_mesh
    return idx
