"""VTU export of meshes and fields (for ParaView), written atomically.

* :func:`boundary_vtu` - a :class:`~hpfebe.geometry.BoundaryMesh` as a polyline: each
  element of degree p is sampled at its p+1 Gauss-Lobatto points (so higher-order fields
  are shown at their nodes), with point data such as a displacement U in V_hp^d.
* :func:`fe_vtu` - a scikit-fem mesh with nodal point data (P1/Q1 fields, or the vertex
  values of higher-order ones).
* :func:`write_vtu` writes such a ``meshio.Mesh``; experiments return them in
  ``ArtefactResult.exports`` and :func:`hpfebe.suite.results.write_result` writes them next to
  the other result files (``<out>/<artefact>_<key>.vtu``).

Like every file of the suite, the VTU is written to a temporary name in the target folder
and renamed, so an interrupted run never leaves a half file.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import meshio
import numpy as np

from ..geometry import BoundaryMesh
from ..quadrature import gauss_lobatto


def write_vtu(path, mesh: meshio.Mesh) -> Path:
    """Write a meshio mesh as VTU, atomically (temporary name, then rename)."""
    path = Path(path)
    if path.suffix != ".vtu":
        raise ValueError(f"path must end in .vtu, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".vtu", dir=path.parent)
    os.close(fd)
    try:
        meshio.write(tmp, mesh, file_format="vtu")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def boundary_vtu(mesh: BoundaryMesh, space=None, fields: dict | None = None,
                 d: int = 1) -> meshio.Mesh:
    """The boundary mesh, sampled at the Gauss-Lobatto points of every element, with
    ``fields`` = {name: coefficients in ``space`` (V_hp or W_hp), d components
    interleaved}.  Cells are line segments between consecutive samples; cell data
    ``element`` and ``degree`` give the parent element and its p_I."""
    if not isinstance(mesh, BoundaryMesh):
        raise ValueError(f"mesh must be a BoundaryMesh, got {type(mesh).__name__}")
    fields = fields or {}
    if fields and space is None:
        raise ValueError("space is required to evaluate fields")
    elem, t = [], []
    for e, p in enumerate(mesh.degrees):
        xl, _ = gauss_lobatto(int(p) + 1)
        elem.append(np.full(len(xl), e))
        t.append(xl)
    elem = np.concatenate(elem)
    t = np.concatenate(t)
    pts = mesh.points(elem, t)
    start = np.concatenate([[0], np.cumsum(mesh.degrees + 1)[:-1]])
    cells = np.concatenate([np.column_stack([s + np.arange(p), s + np.arange(1, p + 1)])
                            for s, p in zip(start, mesh.degrees)])
    cell_elem = np.repeat(np.arange(mesh.n_elements), mesh.degrees)
    point_data = {}
    for name, coeffs in fields.items():
        c = np.asarray(coeffs, dtype=float).reshape(-1, d)
        vals = space.evaluate(c, elem, t)
        if not np.all(np.isfinite(vals)):
            raise ValueError(f"field {name!r} has non-finite values")
        if d == 2:
            vals = np.column_stack([vals, np.zeros(len(vals))])  # VTK vectors are 3D
        point_data[name] = vals.reshape(len(pts), -1).squeeze()
    return meshio.Mesh(np.column_stack([pts, np.zeros(len(pts))]), [("line", cells)],
                       point_data=point_data,
                       cell_data={"element": [cell_elem], "degree": [mesh.degrees[cell_elem]]})


def fe_vtu(mesh, point_data: dict | None = None) -> meshio.Mesh:
    """A scikit-fem MeshTri / MeshQuad with nodal ``point_data`` ({name: array of
    shape (n_vertices,) or (n_vertices, 2)}; 2-vectors are padded to 3D for VTK)."""
    kinds = {3: "triangle", 4: "quad"}
    nverts = mesh.t.shape[0]
    if nverts not in kinds or mesh.p.shape[0] != 2:
        raise ValueError(f"mesh must be a 2D triangle or quadrilateral mesh, got "
                         f"{type(mesh).__name__}")
    data = {}
    for name, v in (point_data or {}).items():
        v = np.asarray(v, dtype=float)
        if v.shape[0] != mesh.p.shape[1]:
            raise ValueError(f"point_data {name!r} must have one row per vertex "
                             f"({mesh.p.shape[1]}), got {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"point_data {name!r} has non-finite values")
        if v.ndim == 2 and v.shape[1] == 2:
            v = np.column_stack([v, np.zeros(len(v))])
        data[name] = v
    pts = np.column_stack([mesh.p.T, np.zeros(mesh.p.shape[1])])
    return meshio.Mesh(pts, [(kinds[nverts], mesh.t.T)], point_data=data)


def write_boundary_vtu(path, mesh: BoundaryMesh, space=None, fields: dict | None = None,
                       d: int = 1) -> Path:
    """:func:`boundary_vtu` written to ``path``."""
    return write_vtu(path, boundary_vtu(mesh, space, fields, d))


def write_fe_vtu(path, mesh, point_data: dict | None = None) -> Path:
    """:func:`fe_vtu` written to ``path``."""
    return write_vtu(path, fe_vtu(mesh, point_data))
