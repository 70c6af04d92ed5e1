"""VTU export: files read back with meshio carry the geometry and the fields."""

import meshio
import numpy as np
import pytest
from skfem import MeshTri

from hpfebe import BoundaryMesh, ContinuousSpace
from hpfebe.io.vtu import fe_vtu, write_boundary_vtu, write_fe_vtu, write_pvd


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


def test_fe_vtu_cell_data_and_mode(tmp_path):
    """Cell data (scalars, 2-vectors, 2x2 tensors per element) round-trips; the file
    gets the usual mode (0644 under umask 022), not mkstemp's 0600."""
    import os
    import stat
    m = MeshTri().refined(2)
    nt = m.t.shape[1]
    eps_p = np.linspace(0.0, 1.0, nt)
    sigma = np.tile([[1.0, 2.0], [2.0, 3.0]], (nt, 1, 1))
    mask = os.umask(0o022)
    try:
        path = write_fe_vtu(tmp_path / "c.vtu", m, {"u": np.zeros((m.p.shape[1], 2))},
                            cell_data={"eps_p": eps_p, "sigma": sigma,
                                       "b": np.ones((nt, 2))})
    finally:
        os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644
    back = meshio.read(path)
    assert np.allclose(back.cell_data["eps_p"][0], eps_p)
    assert np.allclose(back.cell_data["sigma"][0], [1, 2, 2, 3])
    assert back.cell_data["b"][0].shape == (nt, 3)
    with pytest.raises(ValueError, match="one row per element"):
        write_fe_vtu(tmp_path / "d.vtu", m, cell_data={"eps_p": np.zeros(m.p.shape[1])})


def test_contact_vtu_and_pvd_series(tmp_path):
    """Contact-point fields go out as VTK vertices; a PVD collection lists the steps
    with paths relative to its folder."""
    import stat
    from types import SimpleNamespace

    from hpfebe.io import CONTACT_FIELDS, write_contact_vtu, write_pvd
    n = 5
    res = SimpleNamespace(points=np.column_stack([np.linspace(0, 1, n), np.zeros(n)]),
                          p_n=np.arange(n, dtype=float), t_t=-np.ones(n), g_n=-1e-6 * np.ones(n),
                          g_t=np.zeros(n), slip=np.zeros(n), state=np.array([0, 1, 2, 2, 1]),
                          weights=np.full(n, 0.2))
    paths = [write_contact_vtu(tmp_path / "steps" / f"c_{k}.vtu", res) for k in range(2)]
    back = meshio.read(paths[-1])
    assert set(back.point_data) == set(CONTACT_FIELDS)
    assert np.allclose(back.point_data["p_n"], res.p_n)
    assert np.array_equal(back.point_data["state"], res.state)
    pvd = write_pvd(tmp_path / "c.pvd", [(0.5, paths[0]), (1.0, paths[1])])
    text = pvd.read_text()
    assert 'file="steps/c_0.vtu"' in text and 'timestep="1.0"' in text
    assert stat.S_IMODE(pvd.stat().st_mode) == 0o666 & ~_umask()
    with pytest.raises(ValueError, match="pvd"):
        write_pvd(tmp_path / "c.xml", [])


def _umask():
    import os
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_vtu_series_and_its_hook(tmp_path):
    """write_vtu_series: <stem>_<k>.vtu per step, then <stem>.pvd naming them with their
    times; the hook is asked before every rename, and a refusal keeps the file out."""
    from hpfebe.io import write_vtu_series

    m = MeshTri.init_symmetric()
    steps = [(0.25, fe_vtu(m, {"u": np.full(m.p.shape[1], 1.0)})),
             (1.0, fe_vtu(m, {"u": np.full(m.p.shape[1], 2.0)}))]
    asked = []
    paths = write_vtu_series(tmp_path / "s.pvd", steps, before_rename=asked.append)
    assert [p.name for p in paths] == ["s_0.vtu", "s_1.vtu", "s.pvd"]
    assert [p.name for p in asked] == ["s_0.vtu", "s_1.vtu", "s.pvd"]
    text = paths[-1].read_text()
    assert 'timestep="0.25" part="0" file="s_0.vtu"' in text
    assert np.allclose(meshio.read(paths[1]).point_data["u"], 2.0)

    def refuse(path):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_pvd(tmp_path / "r.pvd", [(1.0, paths[0])], before_rename=refuse)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.pvd", "s_0.vtu", "s_1.vtu"]
    for bad, match in (([], "at least one"), ([(1.0, steps[0][1]), (1.0, steps[1][1])],
                                               "strictly increasing")):
        with pytest.raises(ValueError, match=match):
            write_vtu_series(tmp_path / "b.pvd", bad)
    with pytest.raises(ValueError, match="pvd"):
        write_vtu_series(tmp_path / "b.vtu", steps)
