"""Boundary meshes: construction, refinement, and clear errors for bad input (issue 2,
test 4)."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def test_polygon_counts_labels_degrees_and_orientation():
    m = BoundaryMesh.polygon(SQUARE[::-1], n=[1, 2, 3, 4], labels=list("ABCD"), p=[1, 2, 3, 4])
    assert m.n_elements == 10
    # given clockwise: reversed to counter-clockwise, so normals point outward
    centre = np.array([0.5, 0.5])
    mid = 0.5 * (m.a + m.b)
    assert np.all(np.sum((mid - centre) * m.normals, axis=1) > 0)
    # side k of the reversed input keeps its label, count and degree
    assert sorted(zip(m.labels, m.degrees)) == sorted(
        [("A", 1)] * 1 + [("B", 2)] * 2 + [("C", 3)] * 3 + [("D", 4)] * 4)
    assert np.isclose(m.lengths.sum(), 4.0)


def test_polygon_by_size():
    m = BoundaryMesh.polygon(SQUARE, h=0.3)
    assert m.n_elements == 16 and m.h_max <= 0.3


def test_refine_keeps_labels_degrees_and_order():
    m = BoundaryMesh.polygon(SQUARE, n=1, labels=["D", "N", "I", "C"], p=[1, 2, 3, 4])
    r = m.refine([0, 2])
    assert r.n_elements == 6
    assert list(r.labels) == ["D", "D", "N", "I", "I", "C"]
    assert list(r.degrees) == [1, 1, 2, 3, 3, 4]
    # consecutive elements still share nodes: the curve stays closed and ordered
    assert np.all(r.elements[1:, 0] == r.elements[:-1, 1])
    assert np.isclose(r.lengths.sum(), 4.0)
    u = m.refine().refine()
    assert u.n_elements == 16 and np.allclose(u.lengths, 0.25)


def test_degrees_raise_and_set():
    m = BoundaryMesh.polygon(SQUARE, n=2, p=1)
    assert list(m.raise_degree([1, 3], by=2).degrees) == [1, 3, 1, 3, 1, 1, 1, 1]
    assert np.all(m.with_degrees(12).degrees == 12)


def test_join_outer_and_hole():
    outer = BoundaryMesh.polygon([(-2, -2), (2, -2), (2, 2), (-2, 2)], n=2)
    hole = BoundaryMesh.polygon(SQUARE, n=1)
    hole = BoundaryMesh.from_segments(hole.nodes, hole.elements[:, ::-1])  # clockwise
    m = BoundaryMesh.join(outer, hole)
    assert m.n_elements == 12 and m.n_curves == 2


@pytest.mark.parametrize("kwargs, match", [
    (dict(vertices=SQUARE, n=2, p=0), "degree"),
    (dict(vertices=SQUARE, n=-1), "n"),
    (dict(vertices=SQUARE, n=0), "n"),
    (dict(vertices=SQUARE, h=-0.5), "h"),
    (dict(vertices=SQUARE, h=0.0), "h"),
    (dict(vertices=[(0, 0), (1, 0), (1, 0), (0, 1)], n=1), "zero-length|repeated"),
    (dict(vertices=[(0, 0), (1, 0), (0.5, 0.5), (1, 1), (0, 1), (0.5, 0.5)], n=1),
     "repeated point"),
    (dict(vertices=[(0, 0), (1, 1), (1, 0), (0, 1)], n=1), "self-intersecting"),
    (dict(vertices=[(0, 0), (1, 0)], n=1), "vertices"),
])
def test_polygon_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        BoundaryMesh.polygon(**kwargs)


def test_unclosed_curve():
    nodes = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], dtype=float)
    with pytest.raises(ValueError, match="not closed"):
        BoundaryMesh.from_segments(nodes, [[0, 1], [1, 2], [2, 3]])  # open chain


def test_zero_length_element():
    nodes = np.array([(0, 0), (1, 0), (1, 1e-16), (1, 1), (0, 1)], dtype=float)
    with pytest.raises(ValueError, match="zero-length"):
        BoundaryMesh.from_segments(nodes, [[0, 1], [1, 2], [2, 3], [3, 4], [4, 0]])


@pytest.mark.parametrize("scale", [1e160, 1e-170])
def test_coordinates_whose_squares_overflow_or_underflow(scale):
    # a 1e-170 square used to fail as "zero-length element" (squared lengths underflow),
    # a 1e160 one with "cannot convert float NaN to integer"
    nodes = np.array(SQUARE, dtype=float) * scale
    with pytest.raises(ValueError, match=r"nodes: .*rescale the geometry"):
        BoundaryMesh.from_segments(nodes, [[0, 1], [1, 2], [2, 3], [3, 0]])
    assert BoundaryMesh.from_segments(nodes / scale * 1e99, [[0, 1], [1, 2], [2, 3], [3, 0]])


def test_self_intersection_of_nonadjacent_collinear_overlap():
    # a spike folding back over itself: collinear overlapping segments
    nodes = np.array([(0, 0), (2, 0), (1, 0), (1, 1)], dtype=float)
    with pytest.raises(ValueError, match="self-intersecting|cross"):
        BoundaryMesh.from_segments(nodes, [[0, 1], [1, 2], [2, 3], [3, 0]])


def test_bad_degrees_and_marks():
    m = BoundaryMesh.polygon(SQUARE, n=1)
    with pytest.raises(ValueError, match="degree"):
        m.with_degrees(0)
    with pytest.raises(ValueError, match="marked"):
        m.refine([7])
    with pytest.raises(ValueError, match="p"):
        BoundaryMesh.polygon(SQUARE, n=1, p=1.5)
    with pytest.raises(ValueError, match="labels"):
        BoundaryMesh.polygon(SQUARE, n=1, labels=["D", "N"])


def test_refine_records_parent_and_ancestor_map():
    m = BoundaryMesh.polygon(SQUARE, n=2, labels=["D", "N", "I", "C"])
    r = m.refine([1, 6])
    assert r.parent_mesh is m and m.parent is None
    assert list(r.parent) == [0, 1, 1, 2, 3, 4, 5, 6, 6, 7]
    # every element lies in its parent
    mid = 0.5 * (r.a + r.b)
    assert np.array_equal(m.locate(mid)[0], r.parent)
    rr = r.refine([0]).with_degrees(3)
    assert np.array_equal(rr.ancestor_map(m), [0, 0, 1, 1, 2, 3, 4, 5, 6, 6, 7])
    assert rr.ancestor_map(BoundaryMesh.polygon(SQUARE, n=2)) is None
    assert np.array_equal(m.ancestor_map(m), np.arange(8))


def test_locate_points_on_the_boundary():
    m = BoundaryMesh.polygon(SQUARE, n=2)
    e, t = m.locate(np.array([[0.25, 0.0], [1.0, 0.75], [0.5, 0.5], [0.0, 0.0]]))
    assert list(e[:2]) == [0, 3] and np.allclose(t[:2], [0.0, 0.0])
    assert e[2] == -1 and np.isnan(t[2])
    assert e[3] == 0 and t[3] == -1.0          # a vertex: the first element containing it
    with pytest.raises(ValueError, match="points"):
        m.locate(np.zeros(3))


def test_common_refinement_of_nested_meshes():
    from hpfebe.geometry import common_refinement

    labels = ["C", "C", "D", "C"]
    sq = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    base = BoundaryMesh.polygon(sq, n=8, labels=labels)
    adaptive = BoundaryMesh.polygon(sq, n=4, labels=labels).refine([0, 5]).refine([0])
    c = common_refinement(base, adaptive)
    assert c.n_elements == 33                          # one extra node at x = -0.875
    assert np.allclose(c.nodes[:3], [[-1, -1], [-0.875, -1], [-0.75, -1]])
    assert np.all(c.elements[1:, 0] == c.elements[:-1, 1])
    assert np.array_equal(c.labels, base.labels[base.locate(0.5 * (c.a + c.b))[0]])
    # the same mesh: nothing changes; degrees: the largest of the containing elements
    assert common_refinement(base, base).n_elements == 32
    assert np.all(common_refinement(base, base.with_degrees(3)).degrees == 3)
    with pytest.raises(ValueError, match="same boundary"):
        common_refinement(base, BoundaryMesh.polygon(SQUARE, n=2))
    with pytest.raises(ValueError, match="labels"):
        common_refinement(base, BoundaryMesh.polygon(sq, n=4, labels="C"))


def test_a_copied_mesh_stays_read_only():
    """A mesh is immutable: copy and deepcopy give the mesh itself, never writable arrays
    (writable ones would be a second argument type for every numba kernel)."""
    import copy

    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=1)
    scene = copy.deepcopy({"mesh": mesh, "state": np.zeros(3)})
    assert scene["mesh"] is mesh and copy.copy(mesh) is mesh
    assert not scene["mesh"].nodes.flags.writeable
