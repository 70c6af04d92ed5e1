"""Labelled FE meshes (hpfebe.fem.meshes): one cell diameter, refinement that keeps the
boundary labels, conformity, and where a refinement put its vertices."""

import math

import numpy as np
import pytest
from skfem import MeshQuad, MeshTri

from hpfebe.fem import (FEDomain, cell_diameter, distance_to_set, facet_containing,
                        is_conforming, local_mesh_size, new_vertices, refine_labelled,
                        refinement_concentration)
from hpfebe.fem.elasticity import rectangle_mesh

BOX = (-2.0, 2.0, -2.0, 0.0)


def _by_position(mesh, box):
    """The labels of rectangle_mesh recomputed by position (the reference)."""
    x0, x1, y0, y1 = box
    tol = 1e-10 * max(x1 - x0, y1 - y0)
    return mesh.with_boundaries({
        "left": lambda x: np.abs(x[0] - x0) < tol, "right": lambda x: np.abs(x[0] - x1) < tol,
        "bottom": lambda x: np.abs(x[1] - y0) < tol, "top": lambda x: np.abs(x[1] - y1) < tol,
    }).boundaries


# ----------------------------------------------------------------------------- diameter
def test_cell_diameter_triangles_and_rectangles():
    m = MeshTri(np.array([[0.0, 3.0, 0.0], [0.0, 0.0, 4.0]]), np.array([[0], [1], [2]]))
    assert cell_diameter(m).tolist() == [5.0]
    q = MeshQuad.init_tensor(np.array([0.0, 2.0, 3.0]), np.array([0.0, 1.0]))
    np.testing.assert_allclose(cell_diameter(q), [math.sqrt(5.0), math.sqrt(2.0)])
    np.testing.assert_array_equal(cell_diameter(q, [1]), cell_diameter(q)[[1]])
    # FEDomain uses the same function
    d = FEDomain(q, {}, 1.0)
    np.testing.assert_array_equal(d.cell_diameter(np.array([1, 0])), cell_diameter(q)[[1, 0]])


# ----------------------------------------------------------------------------- refinement
def test_refine_keeps_conformity_and_labels():
    m0 = rectangle_mesh(*BOX, 4, 2, kind="tri")
    marked = np.zeros(m0.t.shape[1], bool)
    marked[:3] = True
    m = m0
    for _ in range(4):
        m = refine_labelled(m, marked)
        assert is_conforming(m, m0)
        ref = _by_position(m, BOX)
        assert set(m.boundaries) == set(ref)
        for k in ref:
            np.testing.assert_array_equal(m.boundaries[k], ref[k])
        total = sum(len(v) for v in m.boundaries.values())
        assert total == m.boundary_facets().size
        marked = np.zeros(m.t.shape[1], bool)
        marked[np.argmin(cell_diameter(m))] = True       # keep refining one corner
    top = m.p[:, m.facets[:, m.boundaries["top"]].ravel()]
    assert np.allclose(top[1], 0.0)
    assert m.t.shape[1] > m0.t.shape[1]


def test_refine_uniform_and_all_marked_agree():
    m0 = rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2, kind="tri")
    a = refine_labelled(m0)
    b = refine_labelled(m0, np.ones(m0.t.shape[1], bool))
    np.testing.assert_array_equal(a.p, b.p)
    np.testing.assert_array_equal(a.t, b.t)
    assert a.t.shape[1] == 4 * m0.t.shape[1]
    for k in m0.boundaries:
        np.testing.assert_array_equal(a.boundaries[k], b.boundaries[k])


def test_refine_keeps_overlapping_and_partial_labels():
    """A facet may carry several labels; an unlabelled boundary facet stays unlabelled."""
    m0 = MeshTri.init_symmetric().with_boundaries({
        "C": lambda x: np.abs(x[1]) < 1e-12,                       # bottom
        "D": lambda x: (np.abs(x[1]) < 1e-12) & (x[0] < 0.5),       # part of the bottom
    })
    marked = np.zeros(m0.t.shape[1], bool)
    marked[0] = True
    m = refine_labelled(refine_labelled(m0, marked))
    mid = m.p[:, m.facets].mean(axis=1)
    np.testing.assert_array_equal(m.boundaries["C"],
                                  np.intersect1d(m.boundary_facets(),
                                                 np.flatnonzero(np.abs(mid[1]) < 1e-12)))
    d = m.boundaries["D"]
    assert np.all(np.abs(mid[1, d]) < 1e-12) and np.all(mid[0, d] < 0.5)
    assert np.isin(d, m.boundaries["C"]).all() and d.size < m.boundaries["C"].size


def test_refine_rejects_bad_mask():
    m = rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2, kind="tri")
    with pytest.raises(ValueError, match="marked"):
        refine_labelled(m, np.ones(3, bool))
    with pytest.raises(ValueError, match="marked"):
        refine_labelled(m, np.arange(m.t.shape[1]))


def test_hanging_node_is_not_conforming():
    # the square split in two triangles, the lower one bisected once more (hanging node
    # at the middle of the diagonal)
    p = np.array([[0.0, 1.0, 1.0, 0.0, 0.5], [0.0, 0.0, 1.0, 1.0, 0.5]])
    ref = MeshTri(p[:, :4], np.array([[0, 1, 2], [0, 2, 3]]).T)
    hanging = MeshTri(p, np.array([[0, 1, 4], [1, 2, 4], [0, 2, 3]]).T)
    assert is_conforming(ref, ref)
    assert not is_conforming(hanging, ref)
    unused = MeshTri(p, np.array([[0, 1, 2], [0, 2, 3]]).T)      # vertex 4 in no cell
    assert not is_conforming(unused, ref)


def test_facet_containing():
    m = rectangle_mesh(0.0, 2.0, 0.0, 1.0, 2, 1, kind="tri")
    bottom = m.boundaries["bottom"]
    j = facet_containing(m, bottom, np.array([[0.5, 1.5, 0.5, 3.0], [0.0, 0.0, 0.1, 0.0]]))
    assert j[2] == -1 and j[3] == -1
    for i, x in ((0, 0.5), (1, 1.5)):
        a, b = m.p[0, m.facets[:, bottom[j[i]]]]
        assert min(a, b) <= x <= max(a, b)
    with pytest.raises(ValueError, match="points"):
        facet_containing(m, bottom, np.zeros((3, 2)))


# ----------------------------------------------------------------------------- statistics
def test_new_vertices_and_concentration():
    m0 = rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2, kind="tri")
    marked = np.zeros(m0.t.shape[1], bool)
    marked[0] = True
    m = refine_labelled(m0, marked)
    new = new_vertices(m0, m)
    assert new.sum() == m.p.shape[1] - m0.p.shape[1]
    assert not new_vertices(m0, m0).any()
    seg = [((0.0, 0.0), (1.0, 0.0))]
    c = refinement_concentration(m0, m, lambda p: distance_to_set(p, seg), 0.3, n_sample=101)
    d = distance_to_set(m.p[:, new], seg)
    assert c.n_new == new.sum() and c.share == pytest.approx(np.mean(d <= 0.3))
    assert c.area_share == pytest.approx(31 / 101)        # grid rows with y <= 0.3
    assert c.enrichment == pytest.approx(c.share / c.area_share)
    with pytest.raises(ValueError, match="radius"):
        refinement_concentration(m0, m, lambda p: distance_to_set(p, seg), 0.0)


def test_distance_to_set():
    p = np.array([[0.0, 2.0, -1.0, 0.5], [1.0, 0.0, 0.0, 3.0]])
    d = distance_to_set(p, [((-0.5, 0.0), (0.5, 0.0))], [(0.5, 2.0)])
    np.testing.assert_allclose(d, [1.0, 1.5, 0.5, 1.0])
    assert np.all(np.isinf(distance_to_set(p)))


def test_local_mesh_size():
    m = rectangle_mesh(0.0, 1.0, 0.0, 1.0, 4, 4, kind="tri")
    h = local_mesh_size(m, [(0.0, 0.0), (0.5, 0.5), (9.0, 9.0)])
    np.testing.assert_allclose(h[:2], math.sqrt(2) / 4)
    assert math.isnan(h[2])


# ----------------------------------------------------------------------------- one world
def test_fe_domain_labels_are_the_mesh_boundaries():
    from hpfebe.scenes.interface import SMOOTH

    d = SMOOTH.fe_domain(2)
    assert d.facets is d.mesh.boundaries and set(d.facets) == {"D", "I", "N"}
    r = refine_labelled(d.mesh)                  # labels survive refinement
    mid = r.p[:, r.facets[:, r.boundaries["D"]]].mean(axis=1)
    assert np.allclose(mid[0], -1.0) and r.boundaries["D"].size == 2 * d.facets["D"].size
    bare = FEDomain(MeshQuad.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3)))
    assert bare.facets == {} and math.isnan(bare.h_inv)
    with pytest.raises(ValueError, match="mesh"):
        FEDomain("not a mesh", {})


def test_fe_bodies_share_labelled_meshes_and_the_stiffness_name():
    from hpfebe.fem import PoissonFE
    from hpfebe.fem.elasticity import ElasticBody

    q = rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2, kind="quad")
    fe = PoissonFE(q, 1, dirichlet=("left",))
    assert fe.mesh.boundaries is fe.domain.facets
    assert not hasattr(fe, "A") and fe.K.shape == (9, 9)
    left = np.flatnonzero(np.abs(fe.basis.doflocs[0]) < 1e-12).tolist()
    assert fe.fixed.tolist() == PoissonFE(FEDomain(q), 1, ("left",)).fixed.tolist() == left
    assert len(left) == 3
    body = ElasticBody(FEDomain(q), 1.0, 0.3)
    np.testing.assert_array_equal(body.boundary_facets("left"), q.boundaries["left"])
    assert body.K.shape == (18, 18)
