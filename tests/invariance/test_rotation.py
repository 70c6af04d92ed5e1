"""Rigid rotation of a whole two-body penalty contact scene (FE/FE, FE/BE, BE/FE, BE/BE,
single and two passes, Coulomb friction; the scene of tests/invariance/conftest.py).

Rotating every point of the scene by R (and translating it) and the prescribed
displacements by R is the same continuous and discrete problem in other coordinates:
isotropic elasticity (the FE stiffness and the Lame BE operators are invariant under
isometries), the contact gap and slip along the rotated master normal and tangent, the
return map of the law on them.  So the displacement of the rotated scene at the rotated
dof points is R u, up to the forward bound of conftest.forward_bound:

    ||R u_ref - u_rot|| / ||u_ref|| <= cond_2(J_free) (2 rtol + C_ROUND eps_mach)

(rtol = 1e-12 the backward-error tolerance of both Newton runs, C_ROUND = 1e3 for the
rounding of the assembled data).  The contact pattern, the per-point pressure and the
total normal force (linear in U on that pattern: conftest.traction_bound, force_bound)
are checked alike.  Measured: ~1e-14 against bounds of ~1e-10 .. 1e-9.
"""

from __future__ import annotations

import numpy as np
import pytest

COMBOS = [("FE", "FE"), ("BE", "FE"), ("FE", "BE"), ("BE", "BE")]
ROTATIONS = [(0.7, (3.0, -2.0)), (np.pi / 2, (0.0, 0.0)), (-2.5, (-1.0, 10.0))]
PAIRS = [("slave", "slave"), ("master", "master")]


@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
@pytest.mark.parametrize("theta,shift", ROTATIONS, ids=["0.7", "pi/2", "-2.5"])
def test_rigid_rotation_of_the_scene(tb, kinds, theta, shift):
    T = tb.Isometry.rotation(theta, shift)
    ref, rot = tb.scene(kinds), tb.scene(kinds, T=T)
    beta = tb.forward_bound(ref[0], ref[1], ref[3])
    assert tb.mapped_discrepancy(ref, rot, T, PAIRS) <= beta
    a, b = ref[1], rot[1]
    # the same contact pattern (open / stick / slip) at the same (rotated) points
    assert np.array_equal(a.state, b.state)
    assert np.all(np.linalg.norm(T(a.points) - b.points, axis=1) <= 1e-12)
    assert len(set(a.state.tolist())) >= 2          # open and slip (and stick) present
    fa, fb = a.total_forces()[0], b.total_forces()[0]
    assert abs(fb / fa - 1) <= tb.force_bound(ref[0], a, beta)
    tb_ = tb.traction_bound(ref[0], a, beta)
    assert np.max(np.abs(b.p_n - a.p_n)) <= tb_
    assert np.max(np.abs(b.t_t - a.t_t)) <= tb_


@pytest.mark.parametrize("kinds", [("FE", "FE"), ("BE", "FE"), ("BE", "BE")],
                         ids="/".join)
def test_rigid_rotation_two_pass(tb, kinds):
    """The symmetric two-pass treatment, rotated by 1.1 rad: the same bound."""
    T = tb.Isometry.rotation(1.1, (0.5, 0.25))
    ref, rot = tb.scene(kinds, two_pass=True), tb.scene(kinds, T=T, two_pass=True)
    assert np.any(ref[1].passes == 1)
    beta = tb.forward_bound(ref[0], ref[1], ref[3])
    assert tb.mapped_discrepancy(ref, rot, T, PAIRS) <= beta
    assert np.array_equal(ref[1].state, rot[1].state)


@pytest.mark.parametrize("geometry", ["roof", "overhang"])
@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", [("FE", "FE"), ("BE", "FE"), ("BE", "BE")],
                         ids="/".join)
def test_rigid_rotation_kinked_and_overhanging(tb, kinds, two_pass, geometry):
    """A kinked interface (corner projections, Wriggers' nearest-segment rule) and an
    overhanging upper block (points outside the lower polyline, which carry no contact),
    rotated by 0.3 rad: the same bound (measured 3e-15 .. 1.4e-13)."""
    kw = dict(tb.GEOMETRIES[geometry], two_pass=two_pass)
    T = tb.Isometry.rotation(0.3)
    ref, rot = tb.scene(kinds, **kw), tb.scene(kinds, T=T, **kw)
    assert tb.mapped_discrepancy(ref, rot, T, PAIRS) <= tb.forward_bound(*ref[:2], ref[3])
    assert np.array_equal(ref[0].outside, rot[0].outside)
    assert np.any(ref[0].outside) == (geometry == "overhang")


@pytest.mark.parametrize("formulation", ["bbar", "full"])
@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", [("FE", "FE"), ("BE", "FE")], ids="/".join)
def test_rigid_rotation_elastoplastic_master(tb, kinds, two_pass, formulation):
    """An elastoplastic J2 lower block (ElastoPlasticFE, B-bar or full integration;
    isotropic return map) sheared by 4 D: the bound times E / H (conftest.plastic_factor,
    the least modulus of the algorithmic tangent).  Measured 3e-13 .. 7e-13 (the return
    map's iterates; 1e-14 elastic) against ~4e-7."""
    kw = dict(two_pass=two_pass, shear=4 * tb.D, fe_kw=dict(plastic=formulation))
    T = tb.Isometry.rotation(0.8, (1.0, 2.0))
    ref, rot = tb.scene(kinds, **kw), tb.scene(kinds, T=T, **kw)
    fields = ref[0].bodies["master"].plastic.fields()
    assert fields["eps_p_norm"].max() > 0                  # the block yields
    beta = tb.forward_bound(*ref[:2], ref[3]) * tb.plastic_factor(ref[0])
    assert tb.mapped_discrepancy(ref, rot, T, PAIRS) <= beta


@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_rigid_rotation_tresca(tb, kinds, two_pass):
    """Tresca friction with a bound F(x) varying along Gamma_C (conftest.TRESCA, given as
    F(T^{-1} y) in the rotated frame: a scalar of the scene): the same bound
    (measured 4e-13 .. 5e-13: Newton stops after 1-2 iterations, nearer rtol)."""
    T = tb.Isometry.rotation(0.8, (1.0, 2.0))
    kw = dict(two_pass=two_pass, tresca=tb.TRESCA)
    ref, rot = tb.scene(kinds, **kw), tb.scene(kinds, T=T, **kw)
    assert ref[1].friction == "tresca"
    assert tb.mapped_discrepancy(ref, rot, T, PAIRS) <= tb.forward_bound(*ref[:2], ref[3])
    assert np.array_equal(ref[1].state, rot[1].state)


def test_rigid_rotation_p2_be(tb):
    """BE bodies of degree 2 (GLL interior nodes on the contact elements) on an FE
    master: the same bound."""
    T = tb.Isometry.rotation(-0.4, (2.0, 1.0))
    ref, rot = tb.scene(("BE", "FE"), p=2), tb.scene(("BE", "FE"), T=T, p=2)
    assert tb.mapped_discrepancy(ref, rot, T, PAIRS) <= tb.forward_bound(*ref[:2], ref[3])


SQUARE = np.array(((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)))


def against_obstacle(tb, T, quadrature: str, mu_f: float):
    """The Section 3.2.5 body (BE, [-1, 1]^2, 4 elements of degree 2 per side, Gamma_C
    the bottom, top held) against the rigid tilted obstacle g = -2e-4 + 2e-4 (x + 1) of
    the reference frame (x = T^{-1} of the point: the gap along the body's normal is a
    scalar of the scene), moving tangentially by 1e-4 with Coulomb friction."""
    from hpfebe import BoundaryMesh, LameBEM, RigidObstacle, TwoBodyContact

    mesh = BoundaryMesh.polygon(T(SQUARE), n=4, p=2, labels=["C", "N", "D", "N"])
    bem = LameBEM(mesh, tb.E, tb.NU, "strain")

    def gap(x):
        return -2e-4 + 2e-4 * ((np.asarray(x) - T.b) @ T.A[:, 0] + 1.0)

    motion = (lambda x: np.full(len(x), 1e-4)) if mu_f else None
    pr = TwoBodyContact(bem, RigidObstacle(gap, motion), "C", eps_n=1e-7, eps_t=1e-7,
                        mu_f=mu_f, nq=None, quadrature=quadrature)
    fixed = pr.dofs_on("slave", "D")
    res = pr.solve(None, fixed, None, load_factors=list(tb.STEPS), settings=tb.SETTINGS)
    assert res.converged, res.reason
    return pr, res, None, fixed


@pytest.mark.parametrize("quadrature,mu_f", [("exact", 0.0), ("gauss", 0.0),
                                             ("gauss", 0.3)])
def test_rigid_rotation_be_against_rigid_obstacle(tb, quadrature, mu_f):
    """One BE body against a rigid obstacle (Sections 3.2-3.3; the exact positive part
    of Section 3.2 or Gauss points with Coulomb friction), rotated by 0.9 rad and
    moved: the same bound (measured 1e-15 .. 3e-15 against 7e-10 .. 2e-9)."""
    T = tb.Isometry.rotation(0.9, (5.0, -3.0))
    ref, rot = against_obstacle(tb, tb.Isometry(), quadrature, mu_f), \
        against_obstacle(tb, T, quadrature, mu_f)
    assert np.any(ref[1].p_n > 0) and np.any(ref[1].p_n == 0) != (quadrature == "exact")
    beta = tb.forward_bound(ref[0], ref[1], ref[3])
    assert tb.mapped_discrepancy(ref, rot, T, [("slave", "slave")]) <= beta
