"""hpfebe.io.fields: a BE body's interior field on a sampling mesh, against exact
solutions whose Cauchy data the discrete spaces hold exactly (harmonic and Navier
polynomials of degree 2 at p = 2): the representation formula then reproduces the field
to round-off, and the trace at the vertices on Gamma."""

import os
import stat

import meshio
import numpy as np
import pytest
from skfem import MeshTri

from hpfebe import BoundaryMesh, LameBEM, LaplaceBEM
from hpfebe.io import interior_vtu, sampling_mesh, write_interior_vtu

L_SHAPE = [(-1, -1), (0, -1), (0, 0), (1, 0), (1, 1), (-1, 1)]


def harmonic(x):                       # x^2 - y^2
    return x[:, 0] ** 2 - x[:, 1] ** 2


def navier(x):                         # grad of (x^3 - 3 x y^2) / 3: harmonic, div-free
    return np.column_stack([x[:, 0] ** 2 - x[:, 1] ** 2, -2 * x[:, 0] * x[:, 1]])


def navier_stress(x, mu):              # sigma = 2 mu eps (tr eps = 0), as xx, xy, yx, yy
    return 2 * mu * np.column_stack([2 * x[:, 0], -2 * x[:, 1], -2 * x[:, 1], -2 * x[:, 0]])


def _area(m):
    a, b, c = (m.p[:, m.t[k]].T for k in range(3))
    u, v = b - a, c - a
    return 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum()


@pytest.fixture(scope="module")
def l_shape():
    mesh = BoundaryMesh.polygon(L_SHAPE, n=4, p=2)
    return mesh, sampling_mesh(mesh, 0.125)


def test_sampling_mesh_fills_the_body(l_shape):
    mesh, sm = l_shape
    assert isinstance(sm, MeshTri)
    assert _area(sm) == pytest.approx(3.0, rel=1e-12)
    # every vertex of Gamma is a vertex of the sampling mesh
    d = np.linalg.norm(mesh.nodes[:, None, :] - sm.p.T[None], axis=2).min(axis=1)
    assert d.max() < 1e-14


def test_sampling_mesh_of_a_body_with_a_hole():
    outer = BoundaryMesh.polygon([(0, 0), (3, 0), (3, 2), (0, 2)], n=3)
    hole = BoundaryMesh.polygon([(1, 0.5), (1, 1.5), (2, 1.5), (2, 0.5)], n=2)  # any sense
    body = BoundaryMesh.join(outer, hole)
    sm = sampling_mesh(body, 0.2)
    assert _area(sm) == pytest.approx(6.0 - 1.0, rel=1e-12)
    c = sm.p[:, sm.t].mean(axis=1).T
    assert not np.any((c[:, 0] > 1) & (c[:, 0] < 2) & (c[:, 1] > 0.5) & (c[:, 1] < 1.5))


def test_laplace_potential_is_exact(l_shape):
    mesh, sm = l_shape
    op = LaplaceBEM(mesh)
    U = op.V_space.interpolate(harmonic)          # exact: quadratic on every side
    out = interior_vtu(op, U, sampling=sm)        # psi = op.Psi(U), exact too
    x = out.points[:, :2]
    assert set(out.point_data) == {"potential", "on_gamma"}
    on = out.point_data["on_gamma"] > 0
    assert 0 < on.sum() < len(x)
    assert np.abs(out.point_data["potential"] - harmonic(x)).max() < 1e-11


def test_lame_displacement_and_stress_are_exact(l_shape):
    mesh, sm = l_shape
    op = LameBEM(mesh, 1000.0, 0.3)
    U = np.column_stack([op.V_space.interpolate(lambda x, c=c: navier(x)[:, c])
                         for c in (0, 1)]).ravel()
    out = interior_vtu(op, U, sampling=sm)
    x = out.points[:, :2]
    on = out.point_data["on_gamma"] > 0
    u = out.point_data["displacement"]
    assert u.shape == (len(x), 3) and np.all(u[:, 2] == 0)
    assert np.abs(u[:, :2] - navier(x)).max() < 1e-11
    S, Se = out.point_data["stress"], navier_stress(x, op.mu)
    assert np.abs(S[~on] - Se[~on]).max() < 1e-11 * np.abs(Se).max()
    # on Gamma: the formula 1e-4 of the way to a cell centroid
    assert np.abs(S[on] - Se[on]).max() < 1e-4 * np.abs(Se).max()


def test_user_meshes_skfem_and_meshio(tmp_path):
    """A scikit-fem mesh of the square (vertices on Gamma included) and the same mesh
    as a meshio.Mesh give the same field; the file has the usual mode."""
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=2)
    op = LaplaceBEM(mesh)
    U = op.V_space.interpolate(harmonic)
    fe = MeshTri.init_tensor(np.linspace(0, 1, 7), np.linspace(0, 1, 5))
    a = interior_vtu(op, U, sampling=fe)
    assert np.abs(a.point_data["potential"] - harmonic(fe.p.T)).max() < 1e-11
    as_meshio = meshio.Mesh(np.column_stack([fe.p.T, np.zeros(fe.p.shape[1])]),
                            [("triangle", fe.t.T)])
    b = interior_vtu(op, U, sampling=as_meshio)
    assert np.array_equal(a.point_data["potential"], b.point_data["potential"])
    path = write_interior_vtu(tmp_path / "inside.vtu", op, U, sampling=fe)
    back = meshio.read(path)
    assert np.allclose(back.point_data["potential"], a.point_data["potential"])
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask


def test_a_smooth_field_converges():
    """exp(x) sin(y) (not in the spaces): the sampled error falls with h at p = 2."""
    def u(x):
        return np.exp(x[:, 0]) * np.sin(x[:, 1])
    errs = []
    for n in (1, 2, 4):
        mesh = BoundaryMesh.polygon(L_SHAPE, n=n, p=2)
        op = LaplaceBEM(mesh)
        out = interior_vtu(op, op.V_space.interpolate(u), h=0.25)
        errs.append(np.abs(out.point_data["potential"] - u(out.points[:, :2])).max())
    assert errs[1] < errs[0] / 4 and errs[2] < errs[1] / 4, errs


def test_bad_input_refused(l_shape):
    mesh, sm = l_shape
    op = LaplaceBEM(mesh)
    U = op.V_space.interpolate(harmonic)
    outside = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(-1, 1, 3))  # notch
    outside = MeshTri(outside.p + np.array([[0.25], [0.0]]), outside.t)
    with pytest.raises(ValueError, match="outside"):
        interior_vtu(op, U, sampling=outside)
    with pytest.raises(ValueError, match="not both"):
        interior_vtu(op, U, sampling=sm, h=0.1)
    with pytest.raises(ValueError, match="U must have"):
        interior_vtu(op, U[:-1], sampling=sm)
    with pytest.raises(TypeError, match="sampling"):
        interior_vtu(op, U, sampling=np.zeros((3, 2)))
    with pytest.raises(TypeError, match="op"):
        interior_vtu(mesh, U, sampling=sm)
    with pytest.raises(ValueError, match="h must"):
        sampling_mesh(mesh, -1.0)
