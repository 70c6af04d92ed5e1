"""Self-intersection test of a boundary mesh: the segment-crossing grid.

The elements are registered in the cells of a uniform grid that they pass through, and
only elements sharing a cell are tested for crossing (:func:`_first_crossing`, used by
:func:`hpfebe.geometry.validation.validate`).
"""

from __future__ import annotations

import numpy as np
from numba import njit


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
