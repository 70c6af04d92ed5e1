"""Swapping the bodies (slave <-> master) of the two-body penalty contact scenes
(FE/FE, FE/BE, BE/FE, BE/BE, Coulomb friction; the scene of tests/invariance/conftest.py).

1. Two passes (``two_pass=True``, Laursen / Wriggers): pass 0 integrates on the slave's
   pieces (split at the master vertices) against the master, pass 1 the roles swapped,
   with the same eps_n, eps_t and law.  Swapping the bodies exchanges the two passes:
   the same point sets, weights, gaps, slips and laws in another order, so the same
   discrete problem, on the curved interface (two different polylines) too.
2. One pass on a flat interface (c = 0): both bodies' pieces are the common refinement
   of the two interface meshes (the split), with the same Gauss points, weights, gaps
   and slips (n_s = -n_m, t_s = -t_m: the sign flips of the tangent and of the
   difference cancel): the same discrete problem again.
3. One pass on the curved interface is *not* symmetric: the gap is measured from the
   slave's points to the master's polyline, and the polylines differ by O(c h^2)
   (measured 1.3e-5 .. 2.2e-5 relative, 5e4 times the bound): this is what makes 1. and
   2. non-trivial checks.

Bound (conftest.forward_bound): both runs solve the same discrete problem to the backward
error rtol = 1e-12, with other rounding, so

    ||u_a - u_b|| / ||u_a|| <= cond_2(J_free) (2 rtol + C_ROUND eps_mach)

per body (upper with upper, lower with lower); the total forces by conftest.force_bound
and traction_bound.  Measured 1.5e-16 .. 1.3e-15 against bounds of ~1e-10 .. 5e-10.
"""

from __future__ import annotations

import pytest

COMBOS = [("FE", "FE"), ("BE", "FE"), ("FE", "BE"), ("BE", "BE")]


def swapped(tb, kinds, c, two_pass, p=1):
    a = tb.scene(kinds, c=c, two_pass=two_pass, p=p)
    b = tb.scene(kinds, c=c, two_pass=two_pass, p=p, upper_is_slave=False)
    pairs = [(a[2][k], b[2][k]) for k in ("upper", "lower")]
    beta = tb.forward_bound(a[0], a[1], a[3])
    return a, b, tb.mapped_discrepancy(a, b, tb.Isometry(), pairs), beta


def forces_agree(tb, a, b, beta) -> None:
    (fna, fta), (fnb, ftb) = a[1].total_forces(), b[1].total_forces()
    assert abs(fnb / fna - 1) <= tb.force_bound(a[0], a[1], beta)
    assert abs(ftb - fta) <= a[1].weights.sum() * tb.traction_bound(a[0], a[1], beta)


@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_two_pass_swap_on_a_curved_interface(tb, kinds):
    a, b, d, beta = swapped(tb, kinds, 0.005, True)
    assert d <= beta
    forces_agree(tb, a, b, beta)
    assert {0, 1, 2} <= set(a[1].state.tolist())            # open, stick and slip


@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_single_pass_swap_on_a_flat_interface(tb, kinds):
    a, b, d, beta = swapped(tb, kinds, 0.0, False)
    assert d <= beta
    forces_agree(tb, a, b, beta)


@pytest.mark.parametrize("geometry", ["roof", "overhang"])
@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_two_pass_swap_kinked_and_overhanging(tb, kinds, geometry):
    """Two passes on the kinked interface and with the overhanging upper block (its
    outside points in pass 0; in pass 1 the lower block's points all project inside):
    the same bound (measured 3e-16 .. 4e-15)."""
    kw = dict(tb.GEOMETRIES[geometry], two_pass=True)
    a, b = tb.scene(kinds, **kw), tb.scene(kinds, upper_is_slave=False, **kw)
    pairs = [(a[2][k], b[2][k]) for k in ("upper", "lower")]
    beta = tb.forward_bound(a[0], a[1], a[3])
    assert tb.mapped_discrepancy(a, b, tb.Isometry(), pairs) <= beta
    forces_agree(tb, a, b, beta)


@pytest.mark.parametrize("formulation", ["bbar", "full"])
@pytest.mark.parametrize("kinds", [("FE", "FE"), ("BE", "FE")], ids="/".join)
def test_two_pass_swap_elastoplastic(tb, kinds, formulation):
    """Two passes with an elastoplastic J2 lower block (slave or master): the same
    history along the same load path, so the same solution within the bound times
    E / H (conftest.plastic_factor); measured 1e-15 .. 3e-14."""
    kw = dict(two_pass=True, shear=4 * tb.D, fe_kw=dict(plastic=formulation))
    a, b = tb.scene(kinds, **kw), tb.scene(kinds, upper_is_slave=False, **kw)
    pairs = [(a[2][k], b[2][k]) for k in ("upper", "lower")]
    beta = tb.forward_bound(a[0], a[1], a[3]) * tb.plastic_factor(a[0])
    assert tb.mapped_discrepancy(a, b, tb.Isometry(), pairs) <= beta


@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_two_pass_swap_tresca(tb, kinds):
    """Two passes with Tresca friction (the bound conftest.TRESCA at both passes'
    points): the same bound."""
    kw = dict(two_pass=True, tresca=tb.TRESCA)
    a, b = tb.scene(kinds, **kw), tb.scene(kinds, upper_is_slave=False, **kw)
    pairs = [(a[2][k], b[2][k]) for k in ("upper", "lower")]
    beta = tb.forward_bound(a[0], a[1], a[3])
    assert tb.mapped_discrepancy(a, b, tb.Isometry(), pairs) <= beta
    forces_agree(tb, a, b, beta)


def test_two_pass_swap_p2_be(tb):
    """Degree-2 BE slave on an FE master, curved interface."""
    a, b, d, beta = swapped(tb, ("BE", "FE"), 0.005, True, p=2)
    assert d <= beta


@pytest.mark.parametrize("kinds", [("FE", "FE"), ("BE", "BE")], ids="/".join)
def test_single_pass_swap_on_a_curved_interface_is_not_symmetric(tb, kinds):
    _, _, d, beta = swapped(tb, kinds, 0.005, False)
    assert d > 1e3 * beta
