"""Where points and segments lie with respect to the region a boundary mesh encloses:
inside, on Gamma or outside (:func:`classify_points`, the crossing number over all curves,
holes included), and the first convex polygon whose interior Gamma cuts
(:func:`first_cut`).
Used to check data that must lie in a body, e.g. the cells of an elastoplastic BE body
(:class:`hpfebe.bodies.cell_operators.CellStrainOperators`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: codes of :func:`classify_points`
OUTSIDE, ON, INSIDE = -1, 0, 1


@njit(cache=True)
def _classify(a, b, pts, tol):
    """Per point: ON if its distance to a segment [a_k, b_k] is <= tol, else INSIDE for
    an odd crossing number of the horizontal ray to +x (the even-odd rule: a point in a
    hole crosses the outer curve and the hole's), else OUTSIDE."""
    out = np.empty(pts.shape[0], dtype=np.int64)
    for i in range(pts.shape[0]):
        px, py = pts[i, 0], pts[i, 1]
        odd = False
        on = False
        for k in range(a.shape[0]):
            ax, ay, bx, by = a[k, 0], a[k, 1], b[k, 0], b[k, 1]
            dx, dy = bx - ax, by - ay
            L2 = dx * dx + dy * dy
            t = ((px - ax) * dx + (py - ay) * dy) / L2
            t = min(max(t, 0.0), 1.0)
            ex, ey = px - ax - t * dx, py - ay - t * dy
            if ex * ex + ey * ey <= tol * tol:
                on = True
                break
            if (ay > py) != (by > py):
                if px < ax + (py - ay) * dx / dy:
                    odd = not odd
        out[i] = ON if on else (INSIDE if odd else OUTSIDE)
    return out


def classify_points(mesh, points, tol: float | None = None) -> np.ndarray:
    """For points (n, 2): :data:`INSIDE` (1), :data:`ON` (0: within ``tol`` of Gamma,
    default 1e-9 times the mesh's diameter) or :data:`OUTSIDE` (-1) of the region that
    the closed curves of ``mesh`` (a :class:`~hpfebe.geometry.BoundaryMesh`) enclose."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
    tol = 1e-9 * mesh.diameter if tol is None else float(tol)
    return _classify(np.ascontiguousarray(mesh.a), np.ascontiguousarray(mesh.b), pts, tol)


@njit(cache=True)
def _first_cut(a, b, nodes, polys, tol):
    """(c, k): the first convex counter-clockwise polygon c (vertex indices ``polys[c]``
    into ``nodes``) whose interior the segment [a_k, b_k] meets by more than ``tol`` (a
    point of it at a distance > tol inside every edge), or (-1, -1).  The segment's
    points P(t) = a + t (b - a) inside edge j satisfy f_j(t) = cross(e_j, P(t) - v_j)
    > tol |e_j|, linear in t: the interval of t in [0, 1] where all hold is cut down
    edge by edge (Cyrus-Beck)."""
    nc, m = polys.shape
    for c in range(nc):
        xlo, xhi = nodes[polys[c, 0], 0], nodes[polys[c, 0], 0]
        ylo, yhi = nodes[polys[c, 0], 1], nodes[polys[c, 0], 1]
        for j in range(1, m):
            xlo, xhi = min(xlo, nodes[polys[c, j], 0]), max(xhi, nodes[polys[c, j], 0])
            ylo, yhi = min(ylo, nodes[polys[c, j], 1]), max(yhi, nodes[polys[c, j], 1])
        for k in range(a.shape[0]):
            if (max(a[k, 0], b[k, 0]) <= xlo or min(a[k, 0], b[k, 0]) >= xhi
                    or max(a[k, 1], b[k, 1]) <= ylo or min(a[k, 1], b[k, 1]) >= yhi):
                continue
            t0, t1 = 0.0, 1.0
            for j in range(m):
                v0, v1 = nodes[polys[c, j]], nodes[polys[c, (j + 1) % m]]
                ex, ey = v1[0] - v0[0], v1[1] - v0[1]
                f0 = ex * (a[k, 1] - v0[1]) - ey * (a[k, 0] - v0[0]) \
                    - tol * np.sqrt(ex * ex + ey * ey)
                df = ex * (b[k, 1] - a[k, 1]) - ey * (b[k, 0] - a[k, 0])
                if df == 0.0:
                    if f0 <= 0.0:
                        t1 = -1.0
                        break
                elif df > 0.0:
                    t0 = max(t0, -f0 / df)
                else:
                    t1 = min(t1, -f0 / df)
                if t1 <= t0:
                    break
            if t1 > t0:
                return c, k
    return -1, -1


def first_cut(mesh, nodes, polygons, tol: float | None = None):
    """(c, k): the first convex counter-clockwise polygon c (rows of ``polygons``, indices
    into ``nodes``) whose interior the element k of ``mesh`` meets (at points more than
    ``tol`` inside, default 1e-9 times the mesh's diameter), or (-1, -1).  With its
    centroid inside the body, a polygon no element of Gamma cuts lies in the closed body
    (its interior is connected and meets Gamma nowhere); an element that merely touches
    it (at a vertex, or along an edge on Gamma) does not cut it."""
    tol = 1e-9 * mesh.diameter if tol is None else float(tol)
    c, k = _first_cut(np.ascontiguousarray(mesh.a), np.ascontiguousarray(mesh.b),
                      np.ascontiguousarray(nodes, dtype=float),
                      np.ascontiguousarray(polygons, dtype=np.int64), tol)
    return int(c), int(k)
