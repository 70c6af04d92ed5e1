"""Mesh files in: gmsh files written by meshio (MSH 2.2 and 4.1, with and without
$PhysicalNames, lines in any order and direction) and by gmsh's own Python API load into
a scikit-fem mesh with named boundaries and a BoundaryMesh with chained, oriented curves."""

import meshio
import numpy as np
import pytest
from skfem import MeshTri

from hpfebe.io import read_boundary_mesh, read_fe_mesh

FORMATS = [("gmsh22", False), ("gmsh22", True), ("gmsh", False), ("gmsh", True)]
GROUPS = {"bottom": 1, "right": 2, "top": 3, "left": 4}


def _square_with_hole():
    """Triangles of [0, 4]^2 minus [1, 2]^2 (from a refined square mesh), the outer
    sides as 4 groups and the hole as a 5th, every second line reversed and the lines
    shuffled."""
    m = MeshTri.init_tensor(np.linspace(0, 4, 9), np.linspace(0, 4, 9))
    c = m.p[:, m.t].mean(axis=1)
    keep = ~((c[0] > 1) & (c[0] < 2) & (c[1] > 1) & (c[1] < 2))
    m = MeshTri(m.p, m.t[:, keep]).remove_unused_nodes() if hasattr(
        MeshTri, "remove_unused_nodes") else MeshTri(m.p, m.t[:, keep])
    f = m.facets[:, m.boundary_facets()]
    mid = m.p[:, f].mean(axis=1)
    side = np.select([mid[1] < 1e-12, mid[0] > 4 - 1e-12, mid[1] > 4 - 1e-12,
                      mid[0] < 1e-12], [1, 2, 3, 4], 5)
    rng = np.random.default_rng(0)
    lines = f.T.copy()
    lines[::2] = lines[::2, ::-1]
    perm = rng.permutation(len(lines))
    return m, lines[perm], side[perm]


def _write(tmp_path, fmt, binary, names, points, tri, lines, side):
    field = {}
    if names:
        field = {n: np.array([t, 1]) for n, t in GROUPS.items()}
        field["hole"] = np.array([5, 1])
        field["body"] = np.array([1, 2])
    pts = np.column_stack([points, np.zeros(len(points))])
    # one cell block per gmsh entity (the MSH 4.1 writer takes one tag per block)
    cells = [("line", lines[side == t]) for t in range(1, 6)] + [("triangle", tri)]
    phys = [np.full(len(c), t, dtype=np.int32) for t, (_, c) in enumerate(cells[:5], 1)]
    phys.append(np.ones(len(tri), dtype=np.int32))
    dim_tags = np.tile([2, 1], (len(points), 1))         # entity of each node (MSH 4.1)
    dim_tags[lines.ravel()] = np.column_stack([np.ones(2 * len(lines), dtype=int),
                                               np.repeat(side, 2)])
    mesh = meshio.Mesh(pts, cells, field_data=field, point_data={"gmsh:dim_tags": dim_tags},
                       cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys})
    path = tmp_path / f"m_{fmt}_{int(binary)}_{int(names)}.msh"
    meshio.write(path, mesh, file_format=fmt, binary=binary)
    return path


@pytest.mark.parametrize("fmt,binary", FORMATS)
@pytest.mark.parametrize("names", [True, False])
def test_meshio_files_load_into_both_mesh_kinds(tmp_path, fmt, binary, names):
    m, lines, side = _square_with_hole()
    path = _write(tmp_path, fmt, binary, names, m.p.T, m.t.T, lines, side)
    label = {t: (n if names else str(t)) for n, t in {**GROUPS, "hole": 5}.items()}

    fe = read_fe_mesh(path)
    assert fe.t.shape[1] == m.t.shape[1]
    assert set(fe.boundaries) == set(label.values())
    for t, name in label.items():
        assert len(fe.boundaries[name]) == np.sum(side == t)
    mid = fe.p[:, fe.facets[:, fe.boundaries[label[1]]]].mean(axis=1)
    assert np.allclose(mid[1], 0.0)
    assert list(fe.subdomains) == ["body" if names else "1"]

    bm = read_boundary_mesh(path, p={label[1]: 2, label[2]: 1, label[3]: 3,
                                     label[4]: 1, label[5]: 2})
    assert bm.n_elements == len(lines) and bm.n_curves == 2
    assert np.isclose(bm.lengths.sum(), 16 + 4)
    for t, name in label.items():
        assert np.sum(bm.labels == name) == np.sum(side == t)
    assert np.all(bm.degrees[bm.labels == label[3]] == 3)
    # outward normals: down on the bottom side, into the hole's centre on the hole
    assert np.allclose(bm.normals[bm.labels == label[1]], [0, -1])
    hole = bm.labels == label[5]
    mid = 0.5 * (bm.a[hole] + bm.b[hole])
    assert np.all(np.sum(bm.normals[hole] * (mid - 1.5), axis=1) < 0)


def test_selected_groups_and_errors(tmp_path):
    m, lines, side = _square_with_hole()
    path = _write(tmp_path, "gmsh", False, True, m.p.T, m.t.T, lines, side)
    outer = read_boundary_mesh(path, groups=["bottom", "right", "top", "left"])
    assert outer.n_curves == 1 and np.isclose(outer.lengths.sum(), 16)
    with pytest.raises(ValueError, match="closed curves"):
        read_boundary_mesh(path, groups=["bottom", "right"])
    with pytest.raises(ValueError, match="no physical group"):
        read_boundary_mesh(path, groups=["nope"])
    with pytest.raises(ValueError, match="no degree"):
        read_boundary_mesh(path, p={"bottom": 2})
    with pytest.raises(FileNotFoundError):
        read_fe_mesh(tmp_path / "missing.msh")


def test_gmsh_api_file_with_reversed_curves(tmp_path):
    """A rectangle whose curve loop uses two curves backwards, 4 physical boundary
    groups, written by gmsh itself in MSH 2.2 and 4.1."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("rect")
        g = gmsh.model.geo
        p = [g.addPoint(x, y, 0, 0.25) for x, y in [(0, 0), (2, 0), (2, 1), (0, 1)]]
        c = [g.addLine(p[0], p[1]), g.addLine(p[1], p[2]),
             g.addLine(p[3], p[2]), g.addLine(p[0], p[3])]   # top and left run backwards
        s = g.addPlaneSurface([g.addCurveLoop([c[0], c[1], -c[2], -c[3]])])
        g.synchronize()
        for k, name in enumerate(["D", "N", "C", "left"]):
            gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [c[k]]), name)
        gmsh.model.addPhysicalGroup(2, [s])                  # unnamed: "5"
        gmsh.model.mesh.generate(2)
        paths = []
        for version in (2.2, 4.1):
            gmsh.option.setNumber("Mesh.MshFileVersion", version)
            paths.append(str(tmp_path / f"rect{version}.msh"))
            gmsh.write(paths[-1])
    finally:
        gmsh.finalize()
    for path in paths:
        fe = read_fe_mesh(path)
        assert set(fe.boundaries) == {"D", "N", "C", "left"}
        assert list(fe.subdomains) == ["5"]
        assert np.isclose(fe.p[:, fe.facets[:, fe.boundaries["C"]]][1].min(), 1.0)
        bm = read_boundary_mesh(path, p={"D": 1, "N": 2, "C": 3, "left": 1})
        assert bm.n_curves == 1 and np.isclose(bm.lengths.sum(), 6)
        assert np.allclose(bm.normals[bm.labels == "C"], [0, 1])
        assert np.allclose(bm.normals[bm.labels == "left"], [-1, 0])
        assert np.all(bm.degrees[bm.labels == "C"] == 3)
