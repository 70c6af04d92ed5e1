"""Reversed node order and element orientation of the meshes of the two-body penalty
contact scenes (BE/FE, FE/BE, BE/BE, FE/FE; single and two passes, Coulomb friction,
degrees 1 and 2; the scene of tests/invariance/conftest.py).

A BE body's boundary mesh given with its segments clockwise (every element reversed),
with its nodes numbered from another start, or with its elements listed in another
order describes the same body: BoundaryMesh.from_segments orients every curve (outer
curves counter-clockwise: outward normals n = (t_y, -t_x)), and the contact code takes
normals, tangents, the segment splits and the traces from the oriented elements.  A Q1
body with its vertices numbered in reverse and its cells listed clockwise is the same FE
body (the stiffness uses |det J|, the outward facet normals are found from the cell
centroids).  So the solutions agree at the same dof points, and so do the contact
states at the same contact points.  The plain constructor BoundaryMesh(nodes, elements,
...) refuses a wrongly oriented curve (a ValueError naming it): an inward normal cannot
reach the contact code.

Bound (conftest.forward_bound): both runs solve the same discrete problem (another
numbering, other rounding) to the backward error rtol = 1e-12:

    ||u_a - u_b|| / ||u_a|| <= cond_2(J_free) (2 rtol + C_ROUND eps_mach);

the tractions at the matched contact points by conftest.traction_bound; with an
elastoplastic body times E / H (conftest.plastic_factor).  Measured 1.8e-16 .. 2.9e-15
against bounds of 1.3e-10 .. 7.6e-10 (elastic), 1.3e-14 .. 2.5e-14 against 3e-7 .. 4e-7
(elastoplastic).
"""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe import BoundaryMesh

PAIRS = [("slave", "slave"), ("master", "master")]
NUMBERINGS = [dict(reverse=True), dict(start=3), dict(shuffle=1),
              dict(reverse=True, start=5, shuffle=2)]
NUMBERING_IDS = ["reversed", "shifted", "shuffled", "all"]


def agree(tb, a, b) -> None:
    """The solutions (per body, at the same dof points) and the contact states and
    tractions (at the same contact points) of two runs agree within the bounds."""
    beta = tb.forward_bound(a[0], a[1], a[3])
    assert tb.mapped_discrepancy(a, b, tb.Isometry(), PAIRS) <= beta
    ra, rb = a[1], b[1]
    j = tb.match(tb.point_keys(ra), tb.point_keys(rb))
    assert np.array_equal(ra.state, rb.state[j]) and np.array_equal(ra.passes,
                                                                    rb.passes[j])
    tt = tb.traction_bound(a[0], ra, beta)
    assert np.max(np.abs(rb.p_n[j] - ra.p_n)) <= tt
    assert np.max(np.abs(rb.t_t[j] - ra.t_t)) <= tt


@pytest.mark.parametrize("p", [1, 2])
@pytest.mark.parametrize("kinds", [("BE", "FE"), ("FE", "BE"), ("BE", "BE")],
                         ids="/".join)
@pytest.mark.parametrize("numbering", NUMBERINGS, ids=NUMBERING_IDS)
def test_be_mesh_numbering_and_orientation(tb, kinds, p, numbering):
    agree(tb, tb.scene(kinds, p=p), tb.scene(kinds, p=p, be_kw=numbering))


@pytest.mark.parametrize("kinds", [("BE", "FE"), ("BE", "BE")], ids="/".join)
def test_be_mesh_orientation_two_pass(tb, kinds):
    agree(tb, tb.scene(kinds, two_pass=True),
          tb.scene(kinds, two_pass=True, be_kw=dict(reverse=True, start=5, shuffle=2)))


@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", [("FE", "FE"), ("FE", "BE"), ("BE", "FE")],
                         ids="/".join)
def test_fe_mesh_reversed_numbering_and_clockwise_cells(tb, kinds, two_pass):
    agree(tb, tb.scene(kinds, two_pass=two_pass),
          tb.scene(kinds, two_pass=two_pass, fe_kw=dict(renumber=True)))


@pytest.mark.parametrize("geometry", ["roof", "overhang"])
@pytest.mark.parametrize("kinds", [("BE", "FE"), ("FE", "BE"), ("BE", "BE")],
                         ids="/".join)
def test_numbering_kinked_and_overhanging(tb, kinds, geometry):
    """Every BE mesh reversed, shifted and shuffled and every FE mesh renumbered with
    clockwise cells, on the kinked interface (ties at the corner) and with the
    overhanging upper block (outside points), two passes: the same bound."""
    kw = dict(tb.GEOMETRIES[geometry], two_pass=True)
    agree(tb, tb.scene(kinds, **kw),
          tb.scene(kinds, be_kw=dict(reverse=True, start=5, shuffle=2),
                   fe_kw=dict(renumber=True), **kw))


@pytest.mark.parametrize("formulation", ["bbar", "full"])
def test_numbering_elastoplastic_master(tb, formulation):
    """A BE slave (reversed, shifted, shuffled) on an elastoplastic J2 Q1 master
    (renumbered, clockwise cells: the B-bar / full strain operators and the return map
    per quadrature point do not depend on the numbering): the bound times E / H."""
    kw = dict(shear=4 * tb.D, two_pass=True)
    a = tb.scene(("BE", "FE"), fe_kw=dict(plastic=formulation), **kw)
    b = tb.scene(("BE", "FE"), be_kw=dict(reverse=True, start=5, shuffle=2),
                 fe_kw=dict(plastic=formulation, renumber=True), **kw)
    beta = tb.forward_bound(a[0], a[1], a[3]) * tb.plastic_factor(a[0])
    assert tb.mapped_discrepancy(a, b, tb.Isometry(), PAIRS) <= beta


def test_clockwise_polygon_is_the_counter_clockwise_mesh():
    """BoundaryMesh.polygon with the corners clockwise: the same elements (reversed to
    counter-clockwise), labels and degrees per side, outward normals."""
    V = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)]
    ccw = BoundaryMesh.polygon(V, n=[3, 2, 3, 2], labels=list("CNDN"), p=[2, 1, 3, 1])
    # V[::-1]: side k joins (0, 1)-(2, 1) (top), (2, 1)-(2, 0), (2, 0)-(0, 0) (bottom), ...
    cw = BoundaryMesh.polygon(V[::-1], n=[3, 2, 3, 2], labels=list("DNCN"),
                              p=[3, 1, 2, 1])

    def key(m):
        return sorted(zip(map(tuple, np.round(m.a, 12)), map(tuple, np.round(m.b, 12)),
                          m.labels.tolist(), m.degrees.tolist()))
    assert key(ccw) == key(cw)
    mid = 0.5 * (cw.a + cw.b)
    assert np.all(np.sum(cw.normals * (mid - [1.0, 0.5]), axis=1) > 0)   # outward


@pytest.mark.parametrize("elements", [
    [[0, 3], [3, 2], [2, 1], [1, 0]],                   # outer curve clockwise
    [[1, 0], [1, 2], [2, 3], [3, 0]],                   # one element reversed
], ids=["clockwise", "one_reversed"])
def test_plain_constructor_refuses_a_wrongly_oriented_curve(elements):
    nodes = np.array([(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)])
    with pytest.raises(ValueError, match="orient|curve"):
        BoundaryMesh(nodes, np.array(elements), list("CNDN"), [1] * 4)
