"""hpfebe.fem.skfem_entities: the edges of a mesh by integer keys, the same arrays as
scikit-fem's own build_entities."""

import numpy as np
import pytest
from skfem import MeshQuad, MeshTet, MeshTri
from skfem.mesh.mesh import Mesh

import hpfebe.fem  # noqa: F401  (installs the integer-key edges)
from hpfebe.fem import skfem_entities as se


def _meshes():
    tri = MeshTri.init_tensor(np.linspace(0, 1, 9), np.linspace(0, 2, 5))
    marked = tri.refined(np.array([0, 3, 7]))         # non-uniform, hanging-free
    rng = np.random.default_rng(0)
    perm = rng.permutation(tri.t.shape[1])              # cells in random order
    return [tri, marked, MeshTri(tri.p, tri.t[:, perm]), MeshTri().refined(5),
            MeshQuad().refined(4), MeshQuad.init_tensor(np.linspace(0, 3, 7),
                                                        np.linspace(0, 1, 4))]


def test_installed_on_import():
    assert Mesh.__dict__["build_entities"].__func__ is se.build_entities
    assert se.install()


def test_install_leaves_an_unknown_scikit_fem_alone(monkeypatch):
    """A scikit-fem whose build_entities is missing or has another signature is left as
    it is (install returns False, nothing replaced)."""
    monkeypatch.setattr(se, "_static", lambda name: None)
    monkeypatch.setattr(se, "_ORIGINAL", lambda t, indices: None)
    assert se.install() is False
    monkeypatch.setattr(se, "_ORIGINAL", None)
    assert se.install() is False


@pytest.mark.parametrize("mesh", _meshes(), ids=lambda m: f"{type(m).__name__}{m.t.shape}")
@pytest.mark.parametrize("sort", [True, False])
def test_same_arrays_as_scikit_fem(mesh, sort):
    ind = mesh.elem.refdom.facets
    ours = se.build_entities(mesh.t, ind, sort)
    theirs = se._ORIGINAL(mesh.t, ind, sort)
    for a, b in zip(ours, theirs):
        assert a.dtype == b.dtype and a.shape == b.shape
        np.testing.assert_array_equal(a, b)


def test_other_entities_left_to_scikit_fem(monkeypatch):
    """Faces of a tetrahedral mesh (three vertices) go to scikit-fem's method."""
    calls = []
    monkeypatch.setattr(se, "_ORIGINAL", lambda *a: calls.append(a) or ("orig", None))
    mesh = MeshTet()
    assert se.build_entities(mesh.t, mesh.elem.refdom.facets)[0] == "orig"
    assert se.build_entities(mesh.t, None) == (None, None)
    assert len(calls) == 1


def test_mesh_facets_unchanged():
    """A mesh's facets and t2f through the installed method equal scikit-fem's."""
    mesh = MeshTri().refined(3)
    facets, t2f = se._ORIGINAL(mesh.t, mesh.elem.refdom.facets)
    np.testing.assert_array_equal(mesh.facets, facets)
    np.testing.assert_array_equal(mesh.t2f, t2f)
