"""Quadrature on the common refinement T^12_{h,I} of two non-matching interface meshes.

Section 2.2 ("The nodes of T^1_{h,I} and T^2_{h,I} together produce a finer partition
T^12_{h,I} of Gamma_I"): every piece J is the overlap of one FE edge on Gamma_I (a boundary
facet of the FE element K_J) and one boundary element I_J.  On J both traces are
polynomials (straight edges, affine FE maps), so a Gauss rule of ``order`` points per piece
integrates the interface terms of (2.4) exactly when 2 order - 1 >= p1 + p2 (mass terms)
and >= 2 p1 (flux terms: dn of Q_p is of degree p along an edge).

Pieces are found for all (FE edge, BE element) pairs at once: collinear pairs whose
parameter intervals overlap with positive length.  The total length of the pieces must
equal the length of the FE interface and of the BE interface (checked: a mismatch means
the two meshes do not describe the same Gamma_I).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..fem.meshes import FEDomain
from ..geometry import BoundaryMesh
from ..quadrature import gauss_legendre

H_DEFINITIONS = ("diameter", "edge")


@dataclass(frozen=True)
class InterfaceRule:
    """Quadrature points on Gamma_I with everything the terms of (2.4) need.

    Per point: ``x`` (nq, 2), weight ``w``, FE element ``fe_cell``, BE element
    ``be_elem`` and its reference coordinate ``t_be`` in [-1, 1], the unit normal ``n1``
    (outward for Omega1), the FE element size ``h1`` and ``piece`` (index of J)."""

    x: np.ndarray
    w: np.ndarray
    fe_cell: np.ndarray
    be_elem: np.ndarray
    t_be: np.ndarray
    n1: np.ndarray
    h1: np.ndarray
    piece: np.ndarray
    n_pieces: int
    length: float


def common_refinement(domain: FEDomain, be_mesh: BoundaryMesh, label: str = "I",
                      tol: float = 1e-10, chunk: int = 2_000_000):
    """Pieces J = (FE facet) cap (BE element) of positive length.

    Returns ``(P0, P1, facet, elem)``: piece end points (n, 2) and the FE facet and BE
    element of each piece."""
    facets = domain.facets.get(label, np.zeros(0, dtype=np.int64))
    elems = np.flatnonzero(be_mesh.where(label))
    if facets.size == 0 or elems.size == 0:
        raise ValueError(f"no interface: FE facets labelled {label!r}: {facets.size}, "
                         f"BE elements labelled {label!r}: {elems.size}")
    m = domain.mesh
    A = m.p[:, m.facets[0, facets]].T
    B = m.p[:, m.facets[1, facets]].T
    C, D = be_mesh.a[elems], be_mesh.b[elems]
    scale = max(np.ptp(m.p, axis=1).max(), 1.0)
    out = []
    step = max(1, chunk // len(elems))
    for s in range(0, len(facets), step):
        a, b = A[s:s + step, None, :], B[s:s + step, None, :]
        d = b - a
        L2 = (d ** 2).sum(-1)
        L = np.sqrt(L2)
        cross = lambda v: (d[..., 0] * v[..., 1] - d[..., 1] * v[..., 0]) / L  # noqa: E731
        collinear = ((np.abs(cross(C[None] - a)) < tol * scale)
                     & (np.abs(cross(D[None] - a)) < tol * scale))
        tc = ((C[None] - a) * d).sum(-1) / L2
        td = ((D[None] - a) * d).sum(-1) / L2
        lo = np.maximum(0.0, np.minimum(tc, td))
        hi = np.minimum(1.0, np.maximum(tc, td))
        i, j = np.nonzero(collinear & ((hi - lo) * L > tol * scale))
        out.append((a[i, 0] + lo[i, j, None] * d[i, 0], a[i, 0] + hi[i, j, None] * d[i, 0],
                    facets[s + i], elems[j]))
    P0, P1, f, e = (np.concatenate(z) for z in zip(*out))
    lengths = np.linalg.norm(P1 - P0, axis=1)
    L_fe = domain.facet_length(facets).sum()
    L_be = be_mesh.lengths[elems].sum()
    if not (np.isclose(lengths.sum(), L_fe, rtol=1e-9) and
            np.isclose(lengths.sum(), L_be, rtol=1e-9)):
        raise ValueError(f"FE and BE interface meshes do not cover the same Gamma_I: "
                         f"pieces {lengths.sum():.12g}, FE {L_fe:.12g}, BE {L_be:.12g}")
    return P0, P1, f, e


def interface_rule(domain: FEDomain, be_mesh: BoundaryMesh, order: int,
                   h_def: str = "diameter", label: str = "I") -> InterfaceRule:
    """Gauss rule with ``order`` points on every piece of the common refinement.

    ``h_def`` chooses h1(x) = h_K of the FE element K owning the piece: "diameter" (the
    thesis's definition, Section 2.1: h_K = diam K) or "edge" (the length of K's edge on
    Gamma_I)."""
    if h_def not in H_DEFINITIONS:
        raise ValueError(f"h_def must be one of {H_DEFINITIONS}, got {h_def!r}")
    if int(order) != order or order < 1:
        raise ValueError(f"order must be a positive integer, got {order!r}")
    P0, P1, facet, elem = common_refinement(domain, be_mesh, label)
    m = domain.mesh
    cell = m.f2t[0, facet]
    if np.any(m.f2t[1, facet] >= 0):
        raise ValueError("interface facets must be boundary facets of the FE mesh")
    xq, wq = gauss_legendre(int(order))
    s = 0.5 * (xq + 1.0)
    x = P0[:, None, :] + s[None, :, None] * (P1 - P0)[:, None, :]
    w = 0.5 * np.linalg.norm(P1 - P0, axis=1)[:, None] * wq[None, :]
    # BE reference coordinate t in [-1, 1] of x on its element
    a, b = be_mesh.a[elem], be_mesh.b[elem]
    ab = b - a
    t = 2.0 * ((x - a[:, None]) * ab[:, None]).sum(-1) / (ab ** 2).sum(-1)[:, None] - 1.0
    # n1 = -n2: the outward normal of Omega2 points into Omega1
    n1 = -be_mesh.normals[elem]
    centre = m.p[:, m.t[:, cell]].mean(axis=1).T
    if np.any(((P0 - centre) * n1).sum(-1) <= 0.0):
        raise ValueError("BE normals are not outward for Omega2 (mesh orientation)")
    if h_def == "diameter":
        h1 = domain.cell_diameter(cell)
    else:
        h1 = domain.facet_length(facet)
    nq = int(order)
    rep = lambda v: np.repeat(v, nq, axis=0)  # noqa: E731
    return InterfaceRule(x=x.reshape(-1, 2), w=w.ravel(), fe_cell=rep(cell),
                         be_elem=rep(elem), t_be=np.clip(t.ravel(), -1.0, 1.0),
                         n1=rep(n1), h1=rep(h1), piece=rep(np.arange(len(P0))),
                         n_pieces=len(P0), length=float(w.sum()))
