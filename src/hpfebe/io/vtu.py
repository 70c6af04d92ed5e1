"""VTU export of meshes and fields (for ParaView), written atomically.

* :func:`boundary_vtu` - a :class:`~hpfebe.geometry.BoundaryMesh` as a polyline: each
  element of degree p is sampled at its p+1 Gauss-Lobatto points (so higher-order fields
  are shown at their nodes), with point data such as a displacement U in V_hp^d.
* :func:`fe_vtu` - a scikit-fem mesh with nodal point data (P1/Q1 fields, or the vertex
  values of higher-order ones) and cell data (one value per element: a stress, the
  plastic strain or hardening of a cell, a subdomain number).
* :func:`contact_vtu` - the contact points of a contact result (on Gamma_C^s) as VTK
  vertices with the contact pressure p_n, tangential traction t_t, gaps g_n, g_t, slip
  and state (0 open, 1 stick, 2 slip).
* :func:`write_pvd` - a ParaView collection (``.pvd``) of VTU files over load steps;
  :func:`write_vtu_series` writes the VTU files of a series and their collection.
* :func:`write_vtu` writes such a ``meshio.Mesh``; experiments return them in
  ``ArtefactResult.exports`` and :func:`hpfebe.suite.results.write_result` writes them into
  the folder ``vtu/`` of the results (``results/vtu/<artefact>_<key>.vtu``; a series:
  ``<artefact>_<key>_<k>.vtu`` and ``<artefact>_<key>.pvd``).
* A BE body's interior field on a sampling mesh (representation formula):
  :mod:`hpfebe.io.fields`.

Like every file of the suite, the VTU is written to a temporary name in the target folder
and renamed, so an interrupted run never leaves a half file; it gets the usual mode
(0644 under the usual umask 022), like the CSV, PNG and JSON files.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable

import meshio
import numpy as np

from ..geometry import BoundaryMesh
from ..quadrature import gauss_lobatto


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_vtu(path, mesh: meshio.Mesh, before_rename: Callable[[Path], None] | None = None
              ) -> Path:
    """Write a meshio mesh as VTU, atomically (temporary name, then rename).

    Parameters
    ----------
    path : str or Path
        the file, ending in ``.vtu``
    mesh : meshio.Mesh
        the mesh with its point and cell data (e.g. from :func:`fe_vtu`)
    before_rename : callable, optional
        called with ``path`` just before the rename; if it raises, the temporary file is
        removed and ``path`` is left as it was (the suite passes its job watch,
        :func:`hpfebe.suite.watch.before_rename`)

    Returns
    -------
    Path
        ``path``, with the usual mode (0644 under umask 022).
    """
    path = Path(path)
    if path.suffix != ".vtu":
        raise ValueError(f"path must end in .vtu, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".vtu", dir=path.parent)
    os.close(fd)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
        meshio.write(tmp, mesh, file_format="vtu")
        if before_rename is not None:
            before_rename(path)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def boundary_vtu(mesh: BoundaryMesh, space=None, fields: dict | None = None,
                 d: int = 1) -> meshio.Mesh:
    """A boundary mesh as a VTU polyline, with fields in V_hp or W_hp.

    Parameters
    ----------
    mesh : BoundaryMesh
        sampled at the p_I + 1 Gauss-Lobatto points of every element
    space : ContinuousSpace or DiscontinuousSpace, optional
        the space of the fields (required with ``fields``)
    fields : dict, optional
        {name: coefficients in ``space``, ``d`` components interleaved}
    d : int
        the number of components of every field (1 or 2)

    Returns
    -------
    meshio.Mesh
        line segments between consecutive samples, point data ``fields`` (2-vectors
        padded to 3D), cell data ``element`` and ``degree`` (the parent element and its
        p_I).
    """
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


def _vtk_field(kind: str, name: str, v, n: int, what: str) -> np.ndarray:
    """``v`` checked to have ``n`` finite rows; 2-vectors padded to 3D for VTK; a 2x2
    tensor per row flattened to its 4 entries (xx, xy, yx, yy)."""
    v = np.asarray(v, dtype=float)
    if v.shape[0] != n:
        raise ValueError(f"{kind} {name!r} must have one row per {what} ({n}), "
                         f"got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{kind} {name!r} has non-finite values")
    if v.ndim == 3 and v.shape[1:] == (2, 2):
        v = v.reshape(n, 4)
    if v.ndim == 2 and v.shape[1] == 2:
        v = np.column_stack([v, np.zeros(len(v))])
    return v


def fe_vtu(mesh, point_data: dict | None = None,
           cell_data: dict | None = None) -> meshio.Mesh:
    """A scikit-fem MeshTri / MeshQuad with nodal and element fields as a VTU mesh.

    Parameters
    ----------
    mesh : skfem.MeshTri or skfem.MeshQuad
        a 2D mesh
    point_data : dict, optional
        {name: nodal values, shape (n_vertices,), (n_vertices, 2) or (n_vertices, 2, 2)}
    cell_data : dict, optional
        {name: one value per element (e.g. a cell's plastic strain), shape
        (n_elements,), (n_elements, 2) or (n_elements, 2, 2)}

    Returns
    -------
    meshio.Mesh
        2-vectors padded to 3D for VTK; 2x2 tensors as 4 components (xx, xy, yx, yy).

    Raises
    ------
    ValueError
        on a wrong number of rows or non-finite values.
    """
    kinds = {3: "triangle", 4: "quad"}
    nverts = mesh.t.shape[0]
    if nverts not in kinds or mesh.p.shape[0] != 2:
        raise ValueError(f"mesh must be a 2D triangle or quadrilateral mesh, got "
                         f"{type(mesh).__name__}")
    data = {name: _vtk_field("point_data", name, v, mesh.p.shape[1], "vertex")
            for name, v in (point_data or {}).items()}
    cells = {name: [_vtk_field("cell_data", name, v, mesh.t.shape[1], "element")]
             for name, v in (cell_data or {}).items()}
    pts = np.column_stack([mesh.p.T, np.zeros(mesh.p.shape[1])])
    return meshio.Mesh(pts, [(kinds[nverts], mesh.t.T)], point_data=data, cell_data=cells)


def write_boundary_vtu(path, mesh: BoundaryMesh, space=None, fields: dict | None = None,
                       d: int = 1) -> Path:
    """:func:`boundary_vtu` written to ``path``."""
    return write_vtu(path, boundary_vtu(mesh, space, fields, d))


def write_fe_vtu(path, mesh, point_data: dict | None = None,
                 cell_data: dict | None = None) -> Path:
    """:func:`fe_vtu` written to ``path``."""
    return write_vtu(path, fe_vtu(mesh, point_data, cell_data))


#: the point fields of a contact result written by :func:`contact_vtu`
CONTACT_FIELDS = ("p_n", "t_t", "g_n", "g_t", "slip", "state", "weights")


def contact_vtu(result) -> meshio.Mesh:
    """The contact state along Gamma_C^s as VTK vertices.

    Parameters
    ----------
    result : ContactResult
        a contact result (:class:`~hpfebe.contact.ContactResult`), or any object with
        ``points`` (n, 2) on the slave contact boundary and the fields below

    Returns
    -------
    meshio.Mesh
        one vertex per contact point, with point data :data:`CONTACT_FIELDS`: pressure
        ``p_n`` >= 0, tangential traction ``t_t``, signed gap ``g_n`` (< 0:
        penetration), relative tangential displacement ``g_t``, ``slip``, ``state`` (0
        open, 1 stick, 2 slip) and the quadrature ``weights``.
    """
    pts = np.asarray(result.points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"result.points must have shape (n, 2), got {pts.shape}")
    n = len(pts)
    data = {name: _vtk_field("point_data", name, getattr(result, name), n, "contact point")
            for name in CONTACT_FIELDS if getattr(result, name, None) is not None}
    return meshio.Mesh(np.column_stack([pts, np.zeros(n)]),
                       [("vertex", np.arange(n).reshape(-1, 1))], point_data=data)


def write_contact_vtu(path, result) -> Path:
    """:func:`contact_vtu` written to ``path``."""
    return write_vtu(path, contact_vtu(result))


def write_pvd(path, steps, before_rename: Callable[[Path], None] | None = None) -> Path:
    """A ParaView collection (``.pvd``) of VTU files, e.g. one per load step.

    Parameters
    ----------
    path : str or Path
        the collection, ending in ``.pvd``
    steps : sequence of (float, str or Path)
        (time or load factor, VTU file) pairs; the paths are written relative to the
        collection's folder
    before_rename : callable, optional
        called with ``path`` just before the rename (see :func:`write_vtu`)

    Returns
    -------
    Path
        ``path``, written atomically (temporary name, then rename) with the usual mode.
    """
    path = Path(path)
    if path.suffix != ".pvd":
        raise ValueError(f"path must end in .pvd, got {str(path)!r}")
    rows = []
    for t, vtu in steps:
        rel = os.path.relpath(Path(vtu).resolve(), path.parent.resolve())
        rows.append(f'    <DataSet timestep="{float(t)!r}" part="0" file="{rel}"/>')
    text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
            "  <Collection>\n" + "\n".join(rows) + "\n  </Collection>\n</VTKFile>\n")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".pvd", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.chmod(tmp, 0o666 & ~_umask())
        if before_rename is not None:
            before_rename(path)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_vtu_series(path, steps, before_rename: Callable[[Path], None] | None = None
                     ) -> list[Path]:
    """A load-step series for ParaView: ``<stem>_<k>.vtu`` (k = 0, 1, ...) beside the
    collection ``path`` = ``<stem>.pvd``, which is written last.

    Parameters
    ----------
    path : str or Path
        the collection, ending in ``.pvd``
    steps : sequence of (float, meshio.Mesh)
        (time or load factor, mesh with its fields) per step, times increasing
    before_rename : callable, optional
        called before every rename (see :func:`write_vtu`)

    Returns
    -------
    list of Path
        the VTU files, then the collection.
    """
    path = Path(path)
    if path.suffix != ".pvd":
        raise ValueError(f"path must end in .pvd, got {str(path)!r}")
    steps = list(steps)
    if not steps:
        raise ValueError("steps must hold at least one (time, mesh) pair, got none")
    times = np.array([float(t) for t, _ in steps])
    if not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        raise ValueError(f"steps: the times must be finite and strictly increasing, got "
                         f"{times.tolist()}")
    vtus = [write_vtu(path.with_name(f"{path.stem}_{k}.vtu"), mesh, before_rename)
            for k, (_, mesh) in enumerate(steps)]
    return [*vtus, write_pvd(path, list(zip(times, vtus)), before_rename)]
