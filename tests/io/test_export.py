"""VTU export: files read back with meshio carry the geometry and the fields."""

import meshio
import numpy as np
import pytest
from skfem import MeshTri

from hpfebe import BoundaryMesh, ContinuousSpace
from hpfebe.io.vtu import write_boundary_vtu, write_fe_vtu


def test_boundary_vtu_roundtrip(tmp_path):
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=[1, 2, 3, 1])
    V = ContinuousSpace(mesh)
    u = V.interpolate(lambda x: x[:, 0] ** 2)
    uv = np.column_stack([u, -u]).ravel()          # interleaved 2-vector field
    path = write_boundary_vtu(tmp_path / "b.vtu", mesh, V, {"u": u}, d=1)
    back = meshio.read(path)
    assert back.cells_dict["line"].shape[0] == mesh.degrees.sum()
    assert np.allclose(back.point_data["u"], back.points[:, 0] ** 2)
    path2 = write_boundary_vtu(tmp_path / "v.vtu", mesh, V, {"U": uv}, d=2)
    U = meshio.read(path2).point_data["U"]
    assert U.shape[1] == 3 and np.allclose(U[:, 0], -U[:, 1])
    assert not list(tmp_path.glob(".*"))           # no temporary files left behind


def test_fe_vtu_roundtrip_and_errors(tmp_path):
    m = MeshTri().refined(2)
    disp = np.column_stack([m.p[0], 2 * m.p[1]])
    back = meshio.read(write_fe_vtu(tmp_path / "f.vtu", m, {"u": disp}))
    assert np.allclose(back.point_data["u"][:, :2], disp)
    with pytest.raises(ValueError, match="point_data"):
        write_fe_vtu(tmp_path / "g.vtu", m, {"u": np.zeros(3)})
    with pytest.raises(ValueError, match="vtu"):
        write_fe_vtu(tmp_path / "g.txt", m)
    with pytest.raises(ValueError, match="non-finite"):
        write_fe_vtu(tmp_path / "g.vtu", m, {"u": np.full(m.p.shape[1], np.nan)})
