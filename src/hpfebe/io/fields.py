r"""A BE body's interior field on a sampling mesh, for ParaView.

A boundary element solution lives on Gamma only: the Dirichlet trace U in V_hp (the
potential, or the displacement in V_hp^2) and the Neumann trace psi in W_hp (the flux
du/dn, or the traction sigma(u) n).  Inside the body Omega the field is given by the
representation formula (1.2) with f = 0 (Green's, resp. Somigliana's identity),

.. math::

   u(x) = \int_\Gamma G(x, y)\,\psi(y)\,ds_y
          - \int_\Gamma \partial_{n_y} G(x, y)\,U(y)\,ds_y,
   \qquad x \in \Omega,

the single layer potential of psi minus the double layer potential of U
(:meth:`hpfebe.bem.LaplaceBEM.representation`, :meth:`hpfebe.bem.LameBEM.representation`;
for Lame the double layer kernel is the traction T_{n_y} G^T).  For Lame the stress
sigma(u) = lambda tr eps(u) I + 2 mu eps(u) comes from the x-gradient of the same formula
(:meth:`hpfebe.bem.LameBEM.stress`).

* :func:`sampling_mesh` - a triangular mesh of the body (a :class:`skfem.MeshTri`) with
  vertices on Gamma and a lattice of spacing ``h`` inside, when the user has none;
* :func:`interior_vtu` - the field at the vertices of a sampling mesh (the user's
  scikit-fem or meshio mesh, or the generated one) as a ``meshio.Mesh`` with point data
  ``potential`` (Laplace) or ``displacement`` and ``stress`` (Lame), written by
  :func:`write_interior_vtu`.

At a vertex on Gamma the formula does not hold (the double layer jumps): there the
potential / displacement is the trace U itself, and the stress is the formula's value at
a point 10^-4 of the way from the vertex to the centroid of a sampling cell that has it
(inside the body; the potentials are accurate up to Gamma, see
:mod:`hpfebe.bem.potentials`).  A vertex outside the body is refused.
"""

from __future__ import annotations

import math
from pathlib import Path

import meshio
import numpy as np
from scipy.spatial import Delaunay
from skfem import MeshQuad, MeshTri

from .. import checks
from ..bem import LameBEM, LaplaceBEM
from ..geometry import BoundaryMesh
from .vtu import _vtk_field, write_vtu

__all__ = ["sampling_mesh", "interior_vtu", "write_interior_vtu", "ON_GAMMA_TOL",
           "INWARD_STEP"]

#: a vertex within ON_GAMMA_TOL * mesh.scale (the coordinate extent) of Gamma is on it
ON_GAMMA_TOL = 1e-9
#: the stress at a vertex on Gamma: the formula at this fraction of the way to a centroid
INWARD_STEP = 1e-4
_CHUNK = 1024


def _distance_and_winding(mesh: BoundaryMesh, pts: np.ndarray):
    """(dist, w): distance of every point to Gamma and the winding number of Gamma
    about it, sum over the elements of the angle they subtend / (2 pi): 1 inside Omega
    (outer curves counter-clockwise), 0 outside and in holes (clockwise); meaningless
    for points on Gamma."""
    a, b = mesh.a, mesh.b
    ab = b - a
    L2 = np.sum(ab ** 2, 1)
    dist, w = np.empty(len(pts)), np.empty(len(pts))
    for i0 in range(0, len(pts), _CHUNK):
        p = pts[i0:i0 + _CHUNK]
        da = a[None, :, :] - p[:, None, :]                        # (m, ne, 2)
        db = b[None, :, :] - p[:, None, :]
        s = np.clip(-np.einsum("mek,ek->me", da, ab) / L2, 0.0, 1.0)
        dist[i0:i0 + _CHUNK] = np.linalg.norm(da + s[..., None] * ab, axis=2).min(axis=1)
        cross = da[..., 0] * db[..., 1] - da[..., 1] * db[..., 0]
        dot = np.sum(da * db, axis=2)
        w[i0:i0 + _CHUNK] = np.arctan2(cross, dot).sum(axis=1) / (2.0 * math.pi)
    return dist, w


def _boundary_samples(mesh: BoundaryMesh, h: float) -> np.ndarray:
    """The nodes of Gamma and points on every element at spacing <= h."""
    n = np.maximum(1, np.ceil(mesh.lengths / h).astype(int))
    e = np.repeat(np.arange(mesh.n_elements), n)
    s = np.concatenate([np.arange(k) / k for k in n])
    return mesh.a[e] + s[:, None] * (mesh.b - mesh.a)[e]


def sampling_mesh(mesh: BoundaryMesh, h: float | None = None) -> MeshTri:
    """A triangular sampling mesh of the body bounded by ``mesh``.

    Parameters
    ----------
    mesh : BoundaryMesh
        the body's boundary Gamma (outer curves counter-clockwise, holes clockwise)
    h : float, optional
        the spacing of the vertices, on Gamma and of the triangular lattice inside
        (default: 1/30 of the diameter of Gamma)

    Returns
    -------
    skfem.MeshTri
        the Delaunay triangulation of the points of Gamma at spacing <= h and the lattice
        points farther than h/3 from Gamma, restricted to the triangles whose centroid
        and edge midpoints lie in the body (a mesh for sampling and plotting fields, not
        for finite elements: it is not graded, and it follows Gamma only at its
        vertices).
    """
    checks.instance("mesh", mesh, BoundaryMesh)
    diam = float(mesh.diameter)
    h = diam / 30.0 if h is None else checks.real("h", h, positive=True)
    lo, hi = mesh.nodes.min(axis=0), mesh.nodes.max(axis=0)
    if h < diam / 2000.0:
        raise ValueError(f"h must be at least diameter / 2000 = {diam / 2000.0:.3g} "
                         f"(about 4e6 lattice points), got {h!r}")
    dy = h * math.sqrt(3.0) / 2.0
    ys = np.arange(lo[1] + dy / 2, hi[1], dy)
    xs = np.arange(lo[0], hi[0] + h, h)
    grid = np.array([(x + (0.5 * h if k % 2 else 0.0), y) for k, y in enumerate(ys)
                     for x in xs]).reshape(-1, 2)
    dist, w = _distance_and_winding(mesh, grid)
    inner = grid[(w > 0.5) & (dist > h / 3.0)]
    pts = np.vstack([_boundary_samples(mesh, h), inner])
    tri = Delaunay(pts).simplices
    # keep triangles whose centroid and edge midpoints are in the body (or on Gamma)
    probes = np.concatenate([pts[tri].mean(axis=1)]
                            + [0.5 * (pts[tri[:, i]] + pts[tri[:, j]])
                               for i, j in ((0, 1), (1, 2), (2, 0))])
    dist, w = _distance_and_winding(mesh, probes)
    tol = ON_GAMMA_TOL * mesh.scale
    ok = (w > 0.5) | (dist <= tol)
    ok = ok.reshape(4, -1).all(axis=0) & (dist[:len(tri)] > tol)
    tri = tri[ok]
    used = np.unique(tri)
    renum = np.full(len(pts), -1)
    renum[used] = np.arange(len(used))
    return MeshTri(pts[used].T.copy(), renum[tri].T.copy())


def _as_cells(sampling):
    """(points (n, 2), cell type, cells) of a scikit-fem MeshTri / MeshQuad or a planar
    meshio.Mesh with one block of triangles or quadrilaterals."""
    if isinstance(sampling, (MeshTri, MeshQuad)):
        kind = "triangle" if isinstance(sampling, MeshTri) else "quad"
        return np.asarray(sampling.p.T, dtype=float), kind, np.asarray(sampling.t.T)
    if isinstance(sampling, meshio.Mesh):
        blocks = [c for c in sampling.cells if c.type in ("triangle", "quad")]
        if len(blocks) != 1:
            raise ValueError("sampling must have one block of triangles or quadrilaterals, "
                             f"got cell types {[c.type for c in sampling.cells]}")
        pts = np.asarray(sampling.points, dtype=float)
        if pts.shape[1] == 3 and np.any(pts[:, 2] != 0):
            raise ValueError("sampling must be planar (z = 0)")
        return pts[:, :2], blocks[0].type, np.asarray(blocks[0].data)
    raise checks.InputTypeError(
        "sampling must be a skfem MeshTri / MeshQuad, a meshio.Mesh or None (a generated "
        f"mesh), got {type(sampling).__name__}")


def _classify(op, pts: np.ndarray):
    """Boolean mask of the points on Gamma; ValueError naming the first point outside
    the body."""
    dist, w = _distance_and_winding(op.mesh, pts)
    on = dist <= ON_GAMMA_TOL * op.mesh.scale
    out = ~on & (w < 0.5)
    if np.any(out):
        k = int(np.flatnonzero(out)[0])
        raise ValueError(f"sampling vertices must lie in the body or on Gamma: vertex {k} "
                         f"= {tuple(pts[k].tolist())} is outside ({int(out.sum())} of "
                         f"{len(pts)} are)")
    return on


def _inward_points(pts, cells, on):
    """For each vertex on Gamma, the point INWARD_STEP of the way to the centroid of the
    first sampling cell that has it (inside the body)."""
    idx = np.flatnonzero(on)
    owner = np.full(len(pts), -1)
    flat = cells.ravel()
    owner[flat[::-1]] = np.repeat(np.arange(len(cells)), cells.shape[1])[::-1]
    if np.any(owner[idx] < 0):
        k = int(idx[np.argmax(owner[idx] < 0)])
        raise ValueError(f"sampling vertex {k} on Gamma belongs to no cell")
    c = pts[cells[owner[idx]]].mean(axis=1)
    return pts[idx] + INWARD_STEP * (c - pts[idx])


def interior_vtu(op, U, psi=None, sampling=None, h: float | None = None) -> meshio.Mesh:
    r"""The interior field of a BE solution at the vertices of a sampling mesh.

    Parameters
    ----------
    op : LaplaceBEM or LameBEM
        the body's boundary element operators
    U : array
        the Dirichlet trace in V_hp (Lame: V_hp^2, interleaved or of shape (ndof, 2))
    psi : array, optional
        the Neumann trace (flux du/dn, or traction sigma(u) n) in W_hp (W_hp^2); default
        ``op.Psi(U)``, the one of the Dirichlet problem with trace U (what a mixed or
        contact solution's Psi is too)
    sampling : skfem.MeshTri, skfem.MeshQuad or meshio.Mesh, optional
        a mesh of the body (vertices inside Omega or on Gamma), e.g. the FE mesh of a gmsh
        file (:func:`hpfebe.io.read_fe_mesh`); default :func:`sampling_mesh` of
        ``op.mesh``
    h : float, optional
        the spacing of the generated sampling mesh (only without ``sampling``)

    Returns
    -------
    meshio.Mesh
        the sampling mesh (z = 0) with point data ``potential`` (Laplace, scalar) or
        ``displacement`` (3-vectors, z = 0) and ``stress`` (xx, xy, yx, yy) (Lame), and
        ``on_gamma`` (1 at the vertices on Gamma, where the trace U is shown).

    Raises
    ------
    ValueError
        for data of the wrong length, a vertex outside the body, or ``h`` given with
        ``sampling``.
    """
    lame = isinstance(op, LameBEM)
    checks.instance("op", op, (LaplaceBEM, LameBEM), "a LaplaceBEM or LameBEM")
    if sampling is None:
        sampling = sampling_mesh(op.mesh, h)
    elif h is not None:
        raise ValueError("h sets the generated sampling mesh: give sampling or h, not both")
    pts, kind, cells = _as_cells(sampling)
    d = 2 if lame else 1
    Uc = checks.array("U", U)
    if Uc.size != d * op.V_space.ndof:
        raise ValueError(f"U must have {d * op.V_space.ndof} entries ({d} x "
                         f"{op.V_space.ndof} V_hp dofs), got shape {Uc.shape}")
    Uc = Uc.reshape(-1)
    psi = op.Psi(Uc) if psi is None else psi
    on = _classify(op, pts)
    inside = ~on
    vals = np.empty((len(pts), d))
    vals[inside] = op.representation(pts[inside], Uc, psi).reshape(-1, d)
    if np.any(on):
        vals[on] = op.V_space.evaluate_at(Uc.reshape(-1, d), pts[on],
                                          tol=ON_GAMMA_TOL).reshape(-1, d)
    data = {"on_gamma": on.astype(float)}
    if lame:
        data["displacement"] = _vtk_field("point_data", "displacement", vals, len(pts),
                                          "vertex")
        sig = np.empty((len(pts), 2, 2))
        sig[inside] = op.stress(pts[inside], Uc, psi)
        if np.any(on):
            sig[on] = op.stress(_inward_points(pts, cells, on), Uc, psi)
        data["stress"] = _vtk_field("point_data", "stress", sig, len(pts), "vertex")
    else:
        data["potential"] = _vtk_field("point_data", "potential", vals[:, 0], len(pts),
                                       "vertex")
    return meshio.Mesh(np.column_stack([pts, np.zeros(len(pts))]), [(kind, cells)],
                       point_data=data)


def write_interior_vtu(path, op, U, psi=None, sampling=None, h: float | None = None
                       ) -> Path:
    """:func:`interior_vtu` written to ``path`` (atomically, the usual mode)."""
    return write_vtu(path, interior_vtu(op, U, psi, sampling, h))
