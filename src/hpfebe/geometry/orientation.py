"""Orientation of the closed curves of a boundary mesh: outer curves counter-clockwise,
holes clockwise, so that the normal (t_y, -t_x) points out of the domain (the convention
of :mod:`hpfebe.geometry`).  Which curve is a hole follows from nesting (a curve inside an
odd number of other curves), its direction from the sign of its enclosed area.
"""

from __future__ import annotations

import numpy as np


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


def orient_curves(nodes, elements, scale: float, fix: bool):
    """Outer curves counter-clockwise, holes clockwise: None if every curve is so;
    otherwise, if ``fix``, ``(elements, perm)`` with the wrongly oriented curves flipped
    (their elements reversed in place; the labels and degrees of the new elements are
    those of the old ones at ``perm``), else ValueError naming the first wrong curve."""
    curve = _curve_index(elements, len(nodes))
    area2, depth = _curve_orientation(nodes, elements, curve, scale)
    wrong = np.flatnonzero(np.sign(area2) != np.where(depth % 2 == 0, 1.0, -1.0))
    if wrong.size == 0:
        return None
    if not fix:
        c = int(wrong[0])
        el = np.flatnonzero(curve == c)
        kind = "an outer boundary" if depth[c] % 2 == 0 else \
            f"a hole (inside {depth[c]} other curve(s))"
        want = "counter-clockwise" if depth[c] % 2 == 0 else "clockwise"
        raise ValueError(
            f"wrongly oriented curve {c} (elements {_span(el)}, from node "
            f"{elements[el[0], 0]} at {nodes[elements[el[0], 0]].tolist()})"
            f": it is {kind} and must run {want} so that the normal points out of the "
            "domain; reverse its elements, or build the mesh with "
            "BoundaryMesh.from_segments / join / polygon, which orient every curve")
    perm = np.arange(len(elements))
    for c in wrong:   # reverse the order of the curve's elements within their slots
        el = np.flatnonzero(curve == c)
        perm[el] = el[::-1]
    new = elements[perm].copy()
    flip = np.isin(curve[perm], wrong)
    new[flip] = new[flip][:, ::-1]
    return np.ascontiguousarray(new), perm
