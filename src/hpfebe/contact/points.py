"""The contact points of :class:`hpfebe.contact.two_body.TwoBodyContact` (Section 4.2,
the gap (4.18)): Gauss points on the slave's contact segments, split where master
vertices project onto them (segment-based Gauss-point-to-segment), the closest-point
projection onto the master polyline (:func:`project_onto_polyline`, Wriggers' "nearest
segment" rule at corners), the master normals and tangents, and the sparse trace maps
U -> dg_n, dg_t (:func:`trace_maps`); one pass or two (:func:`two_body_points`), or a
body against a rigid obstacle (:func:`rigid_points`).  The geometry is that of the
reference configuration (small deformation); see :mod:`hpfebe.contact.two_body`."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..bodies.body import pointwise
from ..quadrature import gauss_legendre


def project_onto_polyline(points: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Closest-point projection of ``points`` (n, 2) onto the segments a[k] -> b[k] (m, 2).

    Returns (seg, s, excess, dist): the chosen segment per point, the clipped parameter
    s in [0, 1] (x_m = a + s (b - a)), how far the unclipped parameter lies outside
    [0, 1] (0 for an interior projection) and the distance.  Ties between equally near
    segments (corners) go to the segment with the smallest excess."""
    P = np.asarray(points, dtype=float)[:, None, :]
    A, B = np.asarray(a, dtype=float)[None], np.asarray(b, dtype=float)[None]
    d = B - A
    L2 = np.sum(d * d, axis=2)
    s_raw = np.sum((P - A) * d, axis=2) / L2
    s = np.clip(s_raw, 0.0, 1.0)
    excess = np.abs(s_raw - s)
    dist = np.linalg.norm(P - (A + s[..., None] * d), axis=2)
    scale = np.sqrt(L2.max())
    dmin = dist.min(axis=1, keepdims=True)
    near = dist <= dmin + 1e-10 * scale
    key = np.where(near, excess, np.inf)
    seg = np.argmin(key, axis=1)
    i = np.arange(P.shape[0])
    return seg, s[i, seg], excess[i, seg], dist[i, seg]


def trace_maps(nm, sides, ndofs):
    """(G_n, G_t, t_m): the sparse maps U -> dg_n, dg_t at the points (one entry per
    trace basis function, component and side) for the normals n_m, tangents
    t_m = (n_m,y, -n_m,x); ``sides`` = [(body, ids, s, dof offset, sign)]."""
    tm = np.column_stack([nm[:, 1], -nm[:, 0]])
    n = nm.shape[0]
    rows, cols, vn, vt = [], [], [], []
    for body, ids, par, off, sign in sides:
        tc, tv = body.trace(ids, par)
        for j in range(tv.shape[1]):
            for c in (0, 1):
                rows.append(np.arange(n))
                cols.append(tc[:, c, j] + off)
                vn.append(sign * tv[:, j] * nm[:, c])
                vt.append(sign * tv[:, j] * tm[:, c])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    Gn = sp.csr_matrix((np.concatenate(vn), (rows, cols)), shape=(n, ndofs))
    Gt = sp.csr_matrix((np.concatenate(vt), (rows, cols)), shape=(n, ndofs))
    return Gn, Gt, tm


def rigid_points(S, obstacle, slave_boundary, nq, ndofs: int) -> dict:
    """Contact points of one body against a rigid obstacle: Gauss points on every
    slave contact segment; the obstacle's normal is -n (n the body's outward
    normal), its tangent the body's t, g_n = g(x) - U_n (``nq`` Gauss points per
    element, None: p_I + 1 on a BE body, 2 on an FE body); the per-point arrays."""
    seg = S.segments(slave_boundary)
    ids = seg["ids"]
    if ids.size == 0:
        raise ValueError(f"slave_boundary {slave_boundary!r}: no element carries this label")
    deg = np.full(ids.size, S.degree) if S.kind == "FE" else S.mesh.degrees[ids]
    pf, ps, pw = [], [], []
    for m in np.unique(deg if nq is None else [nq]):
        sel = np.flatnonzero(deg == m) if nq is None else np.arange(ids.size)
        t, w = gauss_legendre(int(m) + 1 if nq is None else int(m))
        pf.append(np.repeat(sel, t.size))
        ps.append(np.tile(0.5 * (1.0 + np.asarray(t)), sel.size))
        pw.append(np.tile(0.5 * np.asarray(w), sel.size))
    order = np.argsort(np.concatenate(pf), kind="stable")
    pf, ps, pw = (np.concatenate(v)[order] for v in (pf, ps, pw))
    a, b = seg["a"][pf], seg["b"][pf]
    points = a + ps[:, None] * (b - a)
    nm = -seg["normals"][pf]
    Gn, Gt, tm = trace_maps(nm, [(S, ids[pf], ps, 0, 1.0)], ndofs)
    return dict(points=points, weights=pw * np.linalg.norm(b - a, axis=1),
                point_facets=ids[pf], outside=np.zeros(pf.size, bool), normals=nm,
                tangents=tm, Gn=Gn, Gt=Gt, g0=pointwise("gap", obstacle.gap, points),
                motion=pointwise("obstacle_slip", obstacle.motion, points),
                passes=np.zeros(pf.size, dtype=np.intp))


def two_body_points(S, M, slave_boundary, master_boundary, offset: int, ndofs: int,
                    nq, split: bool, two_pass: bool) -> dict:
    """Contact points of two deformable bodies: pass 0 (points on the slave's contact
    segments, projected onto the master polyline, master normals); with ``two_pass``
    also pass 1 (the roles swapped: points on the master's segments, slave normals).
    Every per-point array is the concatenation of the passes (pass 0 first);
    ``passes`` says which pass a point belongs to."""
    slave = (S, S.segments(slave_boundary), 0)
    master = (M, M.segments(master_boundary), offset)
    parts = [contact_pass(slave, master, nq, split, ndofs)]
    if two_pass:
        parts.append(contact_pass(master, slave, nq, split, ndofs))
    out = {key: np.concatenate([q[key] for q in parts])
           for key in ("points", "weights", "outside", "master_points", "point_facets",
                       "g0", "normals", "tangents")}
    for key in ("Gn", "Gt"):
        out[key] = parts[0][key] if len(parts) == 1 \
            else sp.vstack([q[key] for q in parts], format="csr")
    out["passes"] = np.concatenate([np.full(q["points"].shape[0], k, dtype=np.intp)
                                    for k, q in enumerate(parts)])
    out["motion"] = np.zeros(len(out["points"]))
    return out


def contact_pass(point_side, target_side, nq, split: bool, ndofs: int) -> dict:
    """One master-slave pass (Section 4.2, the gap (4.18)): ``point_side`` = (body,
    its contact segments, dof offset) carries the contact points, ``target_side`` the
    polyline they are projected onto and whose outward normals n_T give the gap
    g_n = (x_P + u_P - x_T - u_T) . n_T and slip g_t = (u_P - u_T) . t_T (traces with
    sign +1 for the point body, -1 for the target).  Pass 0: (slave, master); pass 1
    of ``two_pass``: (master, slave).  Returns the per-point arrays (points, weights,
    outside, master_points = the projections x_T, point_facets = the point body's
    facet/element ids, g0, normals, tangents, Gn, Gt)."""
    P, psg, poff = point_side
    T, tsg, toff = target_side
    fs, xa, xb = psg["ids"], psg["a"], psg["b"]
    A, B, ma, mb = tsg["a"], tsg["b"], tsg["va"], tsg["vb"]
    # integration segments: every point segment is split where a target vertex
    # projects onto it, so that both traces are polynomial on each piece (a BE trace
    # of degree p needs p + 1 Gauss points per piece)
    mpts = np.vstack([A, B])
    mseg, ms, mexc, _ = project_onto_polyline(mpts, xa, xb)
    inner = (mexc == 0) & (ms > 1e-12) & (ms < 1 - 1e-12)
    if not split:
        inner[:] = False
    nq = 2 if nq is None else nq
    if P.kind == "BE" or T.kind == "BE":
        nq = max(nq, max(P.degree, T.degree) + 1)
    t, w = gauss_legendre(nq)
    t, w = np.asarray(t, dtype=float), np.asarray(w, dtype=float)
    pf, ps, pw = [], [], []
    for i in range(fs.size):
        br = np.unique(np.concatenate([[0.0, 1.0], ms[inner & (mseg == i)]]))
        # drop breakpoints closer than rounding (a target vertex seen from two segments)
        br = br[np.concatenate([[True], np.diff(br) > 1e-12])]
        br[-1] = 1.0
        lo, hi = br[:-1], br[1:]
        sp_ = (lo[:, None] + 0.5 * (1 + t)[None, :] * (hi - lo)[:, None]).ravel()
        pf.append(np.full(sp_.size, i))
        ps.append(sp_)
        pw.append((0.5 * (hi - lo)[:, None] * w[None, :]).ravel())
    pf, ps, pw = np.concatenate(pf), np.concatenate(ps), np.concatenate(pw)
    length = np.linalg.norm(xb - xa, axis=1)
    pts = xa[pf] + ps[:, None] * (xb[pf] - xa[pf])
    wts = pw * length[pf]
    # target segments
    seg, s, excess, _ = project_onto_polyline(pts, A, B)
    seg_len = np.linalg.norm(B - A, axis=1)
    # outside: clipped onto an end vertex of the target polyline (a vertex of one
    # target segment only); clipped onto an inner corner vertex is a valid contact
    _, inv = np.unique(np.concatenate([ma, mb]), return_inverse=True)
    counts = np.bincount(inv)
    vid = np.where(s < 0.5, inv[seg], inv[ma.size + seg])
    outside = (excess * seg_len[seg] > 1e-10 * seg_len.max()) & (counts[vid] == 1)
    xm = A[seg] + s[:, None] * (B[seg] - A[seg])
    nm = tsg["normals"][seg]
    Gn, Gt, tm = trace_maps(nm, [(P, fs[pf], ps, poff, 1.0),
                                  (T, tsg["ids"][seg], s, toff, -1.0)], ndofs)
    return dict(points=pts, weights=np.where(outside, 0.0, wts), outside=outside,
                master_points=xm, point_facets=fs[pf],
                g0=np.sum((pts - xm) * nm, axis=1), normals=nm, tangents=tm,
                Gn=Gn, Gt=Gt)
