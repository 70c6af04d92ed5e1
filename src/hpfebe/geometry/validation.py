"""Input checks of a boundary mesh: degrees, per-side values, coordinates, elements,
closed curves, no repeated point and no self-intersection (:func:`validate`, run by
:class:`hpfebe.geometry.BoundaryMesh` on construction).  Every violation is a ValueError
that names the offending element, node or value.
"""

from __future__ import annotations

import numpy as np

from .crossing import _first_crossing


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


def validate(nodes, elements, labels, degrees) -> float:
    """ValueError unless ``nodes``, ``elements``, ``labels``, ``degrees`` (arrays as
    :class:`~hpfebe.geometry.BoundaryMesh` holds them) form closed curves of straight
    elements of positive length, without repeated points or crossings, with one label and
    one degree p_I >= 1 per element.  Returns the coordinate extent (the length scale of
    the tolerances)."""
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
    if labels.shape != (ne,):
        raise ValueError(f"labels must have one entry per element ({ne}), "
                         f"got shape {labels.shape}")
    if degrees.shape != (ne,):
        raise ValueError(f"degrees must have one entry per element ({ne}), "
                         f"got shape {degrees.shape}")
    if degrees.min() < 1:
        k = int(np.argmin(degrees))
        raise ValueError(f"degree p_I must be >= 1, got p={degrees[k]} on element {k}")
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
    return scale
