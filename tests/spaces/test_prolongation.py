"""hpfebe.spaces.prolongate: exact embedding of V_hp / W_hp functions into the spaces of
a nested finer mesh (by parent maps or by geometry), and its errors."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh, ContinuousSpace, DiscontinuousSpace
from hpfebe.spaces import containing_elements, prolongate

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def coarse_mesh():
    return BoundaryMesh.polygon(SQUARE, n=[2, 1, 3, 2], labels=["D", "N", "N", "I"],
                                p=[1, 4, 5, 3])


def _samples(mesh, inner=False):
    t = np.linspace(-1, 1, 7) * (0.9 if inner else 1.0)
    elem = np.repeat(np.arange(mesh.n_elements), len(t))
    return elem, np.tile(t, mesh.n_elements)


def _fine_meshes(m):
    r = m.refine([0, 3, 4])
    yield r.with_degrees(np.maximum(r.degrees, 2)).refine([1, 7])        # parent maps
    # built independently: found by geometry
    yield BoundaryMesh.polygon(SQUARE, n=[4, 3, 6, 2], labels=["D", "N", "N", "I"],
                               p=[2, 4, 6, 3])


@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("Space", [ContinuousSpace, DiscontinuousSpace])
def test_prolongation_is_exact(Space, k):
    m = coarse_mesh()
    mf = list(_fine_meshes(m))[k]
    S, Sf = Space(m), Space(mf)
    rng = np.random.default_rng(1)
    c = rng.standard_normal(2 * S.ndof)
    cf = prolongate(S, c, Sf, components=2)
    elem, t = _samples(mf, inner=Space is DiscontinuousSpace)
    ec, tc = m.locate(mf.points(elem, t))
    assert np.allclose(Sf.evaluate(cf.reshape(-1, 2), elem, t),
                       S.evaluate(c.reshape(-1, 2), ec, tc), atol=1e-12)
    c1 = prolongate(S, c[0::2], Sf)
    assert np.allclose(c1, cf[0::2], atol=0)


def test_containing_elements_uses_parents_or_geometry():
    m = coarse_mesh()
    r = m.refine([2])
    assert np.array_equal(containing_elements(m, r), r.parent)
    fresh = BoundaryMesh(r.nodes, r.elements, r.labels, r.degrees)    # no parent map
    assert np.array_equal(containing_elements(m, fresh), r.parent)


def test_prolongation_errors():
    m = coarse_mesh()
    V = ContinuousSpace(m)
    c = np.zeros(V.ndof)
    with pytest.raises(ValueError, match="not nested"):
        prolongate(V, c, ContinuousSpace(BoundaryMesh.polygon(SQUARE, n=3, p=5)))
    with pytest.raises(ValueError, match="degree"):
        prolongate(V, c, ContinuousSpace(m.refine().with_degrees(1)))
    with pytest.raises(ValueError, match="same kind"):
        prolongate(V, c, DiscontinuousSpace(m.refine()))
    with pytest.raises(ValueError, match="U must"):
        prolongate(V, np.zeros(3), ContinuousSpace(m.refine()))
    with pytest.raises(ValueError, match="components"):
        prolongate(V, c, ContinuousSpace(m.refine()), components=3)
