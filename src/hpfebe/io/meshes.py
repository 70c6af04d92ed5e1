"""Mesh files in: gmsh ``.msh`` files (MSH 2.2 and 4.1) read through meshio.

* :func:`read_fe_mesh` - the file's triangles (or quadrilaterals) as a scikit-fem mesh,
  its ``boundaries`` (facet indices) and ``subdomains`` (element indices) named by the
  file's physical groups.
* :func:`read_boundary_mesh` - the file's boundary lines as a
  :class:`~hpfebe.geometry.BoundaryMesh`, each element labelled by its physical group.

A physical group is named by its ``$PhysicalNames`` entry, or by its number (``"3"``)
when the file has none.  Gmsh writes the lines of a curve in the direction of the curve,
which is often not the direction of the boundary (a curve loop ``[1, 2, -3, -4]`` uses
curves 3 and 4 backwards), and the lines of different physical groups in any order:
:func:`read_boundary_mesh` chains the lines into closed curves itself, each line turned
to follow its curve, and :meth:`BoundaryMesh.from_segments` then orients every curve
(outer boundaries counter-clockwise, holes clockwise).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np

from ..geometry import BoundaryMesh

#: meshio cell type -> (scikit-fem mesh class name, its facet type)
_FE_CELLS = {"triangle": "MeshTri", "quad": "MeshQuad"}


def _read(path) -> meshio.Mesh:
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no mesh file {str(path)!r}")
    return meshio.read(path)


def _group_names(m: meshio.Mesh) -> dict:
    """(dim, tag) -> name of every physical group in ``$PhysicalNames``."""
    return {(int(dim), int(tag)): name for name, (tag, dim) in
            ((n, np.asarray(v).ravel()[:2]) for n, v in m.field_data.items())}


def _cells(m: meshio.Mesh, kind: str, dim: int):
    """The cells of type ``kind`` (all blocks joined) and the name of each one's
    physical group (``None`` for a cell in no group)."""
    names = _group_names(m)
    tags = m.cell_data.get("gmsh:physical")
    conn, group = [], []
    for k, block in enumerate(m.cells):
        if block.type != kind:
            continue
        conn.append(np.asarray(block.data, dtype=np.int64))
        if tags is None:
            group.append(np.full(len(block.data), None, dtype=object))
        else:
            tag = np.asarray(tags[k]).astype(int)
            group.append(np.array([names.get((dim, int(t)), str(int(t))) if t > 0 else None
                                   for t in tag], dtype=object))
    if not conn:
        return None, None
    return np.concatenate(conn), np.concatenate(group)


def _planar_points(m: meshio.Mesh, path) -> np.ndarray:
    pts = np.asarray(m.points, dtype=float)
    if pts.shape[1] == 3:
        if np.any(np.abs(pts[:, 2]) > 1e-12 * max(1.0, np.abs(pts[:, :2]).max())):
            raise ValueError(f"{path}: the mesh is not planar (z != 0)")
        pts = pts[:, :2]
    return pts


def _named_sets(group) -> dict:
    """{group name: indices of its cells}, in order of first appearance."""
    out = {}
    for name in dict.fromkeys(g for g in group if g is not None):
        out[name] = np.flatnonzero(group == name).astype(np.int64)
    return out


def read_fe_mesh(path):
    """A scikit-fem mesh from a gmsh file (MSH 2.2 or 4.1).

    Parameters
    ----------
    path : str or Path
        a ``.msh`` file with triangles or quadrilaterals (first order, planar: z = 0)

    Returns
    -------
    skfem.MeshTri or skfem.MeshQuad
        Only the vertices of the 2D cells are kept (renumbered in file order).
        ``mesh.boundaries`` = {physical group name: facet indices} for every physical
        group of lines, ``mesh.subdomains`` = {name: element indices} for every physical
        group of 2D cells; groups without a ``$PhysicalNames`` entry are named by their
        number (``"3"``).

    Raises
    ------
    ValueError
        if the file has no (or two kinds of) 2D cells, or a line of a physical group
        is not a facet of the 2D mesh.
    """
    import skfem

    m = _read(path)
    kinds = [k for k in _FE_CELLS if any(b.type == k for b in m.cells)]
    if len(kinds) != 1:
        found = sorted({b.type for b in m.cells})
        raise ValueError(f"{path}: need triangles or quadrilaterals (one kind), "
                         f"found cells {found}")
    kind = kinds[0]
    cells, cell_group = _cells(m, kind, 2)
    used = np.unique(cells)
    renumber = np.full(len(m.points), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    pts = _planar_points(m, path)[used]
    mesh = getattr(skfem, _FE_CELLS[kind])(np.ascontiguousarray(pts.T),
                                           np.ascontiguousarray(renumber[cells].T))
    boundaries = {}
    lines, line_group = _cells(m, "line", 1)
    if lines is not None:
        facet_of = {tuple(f): k for k, f in enumerate(np.sort(mesh.facets, axis=0).T)}
        for name, idx in _named_sets(line_group).items():
            ends = np.sort(renumber[lines[idx]], axis=1)
            facets = [facet_of.get(tuple(e), -1) for e in ends]
            if np.any(ends < 0) or -1 in facets:
                raise ValueError(f"{path}: a line of physical group {name!r} is not a "
                                 "facet of the 2D mesh")
            boundaries[name] = np.asarray(facets, dtype=np.int64)
    subdomains = _named_sets(cell_group)
    return replace(mesh, _boundaries=boundaries or None, _subdomains=subdomains or None)


def _chain(segments: np.ndarray, path) -> tuple[np.ndarray, np.ndarray]:
    """The segments (undirected node pairs) chained into closed curves.

    Returns ``(order, flip)``: walking the curves one after the other, the k-th element
    is ``segments[order[k]]``, reversed where ``flip[k]``.  ValueError if a node does
    not end exactly two segments (an open curve, a T-junction)."""
    ne = len(segments)
    nodes, count = np.unique(segments, return_counts=True)
    if np.any(count != 2):
        bad = nodes[count != 2][0]
        raise ValueError(f"{path}: the boundary lines do not form closed curves (file "
                         f"node {bad} ends {count[count != 2][0]} lines, not 2)")
    incident = {}
    for s, (a, b) in enumerate(segments):
        incident.setdefault(int(a), []).append(s)
        incident.setdefault(int(b), []).append(s)
    done = np.zeros(ne, dtype=bool)
    order, flip = [], []
    for start in range(ne):
        if done[start]:
            continue
        s, at = start, int(segments[start, 1])
        order.append(s); flip.append(False); done[s] = True
        while True:
            s = next(t for t in incident[at] if t != s)
            if done[s]:
                break
            reverse = int(segments[s, 1]) == at
            order.append(s); flip.append(reverse); done[s] = True
            at = int(segments[s, 0] if reverse else segments[s, 1])
    return np.asarray(order), np.asarray(flip)


def read_boundary_mesh(path, p=1, groups=None) -> BoundaryMesh:
    """A :class:`~hpfebe.geometry.BoundaryMesh` from the lines of a gmsh file.

    Parameters
    ----------
    path : str or Path
        a ``.msh`` file (MSH 2.2 or 4.1; planar) whose lines in physical groups form
        closed curves
    p : int or dict
        the polynomial degree of every element, or {group name: degree} (every group
        read must be in it)
    groups : list of str, optional
        the physical groups of lines to read (default: all)

    Returns
    -------
    BoundaryMesh
        One element per line of the file, labelled by its physical group's name (or
        number, ``"3"``, without ``$PhysicalNames``), the lines chained into closed
        curves whatever their direction in the file and every curve oriented (outer
        curves counter-clockwise, holes clockwise), so the normals point out of the
        domain.  Only the nodes on the lines are kept.

    Raises
    ------
    ValueError
        if the file has no lines in physical groups, ``groups`` or ``p`` name a group
        the file lacks (or ``p`` misses one), or the lines do not form closed curves.
    """
    m = _read(path)
    lines, group = _cells(m, "line", 1)
    if lines is None or all(g is None for g in group):
        raise ValueError(f"{path}: the file has no lines in physical groups")
    present = list(_named_sets(group))
    if groups is None:
        groups = present
    else:
        groups = [str(g) for g in groups]
        missing = [g for g in groups if g not in present]
        if missing:
            raise ValueError(f"{path}: no physical group of lines named {missing}; the "
                             f"file has {present}")
    keep = np.isin(group.astype(str), groups) & np.array([g is not None for g in group])
    lines, group = lines[keep], group[keep].astype(str)
    if isinstance(p, dict):
        p = {str(k): v for k, v in p.items()}
        missing = [g for g in groups if g not in p]
        if missing:
            raise ValueError(f"p: no degree for the physical groups {missing}")
        degrees = np.array([p[g] for g in group])
    else:
        degrees = p
    order, flip = _chain(lines, path)
    segments = lines[order]
    segments[flip] = segments[flip][:, ::-1]
    used, local = np.unique(segments, return_inverse=True)
    pts = _planar_points(m, path)[used]
    degrees = degrees[order] if isinstance(degrees, np.ndarray) else degrees
    return BoundaryMesh.from_segments(pts, local.reshape(segments.shape), group[order],
                                      p=degrees)
