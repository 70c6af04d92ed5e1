"""Issue 25, class "wrong objects": a LaplaceBEM where a Lame body is expected, a gap
callable returning a scalar, densities of the wrong length and points on Gamma in the
representation formula, one body given as both contact bodies: each a ValueError (or
InputTypeError, also a ValueError) that names the parameter, what it got and what is
allowed."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem.lame import LameBEM
from hpfebe.bem.laplace import LaplaceBEM
from hpfebe.bem.potentials import PointOnBoundaryError
from hpfebe.bodies import BEBody, RigidObstacle, as_body
from hpfebe.checks import InputTypeError
from hpfebe.constitutive.j2 import J2Material
from hpfebe.contact import MortarContact
from hpfebe.contact.mortar_fe import FEMortarContact
from hpfebe.contact.two_body import TwoBodyContact
from hpfebe.fem import ElasticBody, ElastoPlasticFE, rectangle_mesh

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
MESH = BoundaryMesh.polygon(SQUARE, n=2, p=2, labels=["C", "N", "D", "N"])
LAP, LAME = LaplaceBEM(MESH), LameBEM(MESH, 1.0, 0.3)


@pytest.mark.parametrize("make", [lambda: BEBody(LAP), lambda: as_body(LAP, "bem"),
                                  lambda: TwoBodyContact(LAP, RigidObstacle(0.0), "C",
                                                         eps_n=1e-3)])
def test_laplace_operator_where_a_lame_body_is_expected(make):
    """BEBody(LaplaceBEM) used to fail with an IndexError in its traces."""
    with pytest.raises(InputTypeError, match=r"must be (a LameBEM|an ElasticBody).*"
                                             r"LaplaceBEM"):
        make()


@pytest.mark.parametrize("gap, text", [
    (lambda x: -1e-4, r"gap\(x\) must have shape \(\d+,\), got shape \(\)"),
    (lambda x: np.linalg.norm(x) - 1.0, r"gap\(x\) must have shape \(\d+,\), got shape \(\)"),
    (lambda x: x, r"gap\(x\) must have shape \(\d+,\), got shape \(\d+, 2\)"),
    (lambda x: np.full(len(x), np.nan), r"gap\(x\) must be finite, got nan"),
    ("0.1", r"gap \(a float or a callable of the points\) must be"),
])
def test_gap_must_give_one_value_per_point(gap, text):
    """The gap is evaluated at the contact points when the problem is built: a scalar
    (a constant, or ``norm(x) - 1`` of all points at once) is refused, not broadcast."""
    with pytest.raises(ValueError, match=text):
        TwoBodyContact(BEBody(LAME), RigidObstacle(gap), "C", eps_n=1e-3)
    ok = TwoBodyContact(BEBody(LAME), RigidObstacle(lambda x: np.full(len(x), -1e-4)),
                        "C", eps_n=1e-3)
    ref = TwoBodyContact(BEBody(LAME), RigidObstacle(-1e-4), "C", eps_n=1e-3)
    assert np.array_equal(ok.g0, ref.g0) and ok.g0.size > 0


@pytest.mark.parametrize("op", [LAP, LAME], ids=["laplace", "lame"])
def test_representation_with_a_density_of_the_wrong_length(op):
    d = op.d
    U, psi = np.zeros(d * op.V_space.ndof), np.zeros(d * op.W_space.ndof)
    nw, nv = d * op.W_space.ndof, d * op.V_space.ndof
    with pytest.raises(ValueError, match=rf"^psi must have {nw} entries .*got shape "
                                         rf"\({nw - 1},\)"):
        op.representation([[0.5, 0.5]], U, psi[:-1])
    with pytest.raises(ValueError, match=rf"^U must have {nv} entries .*got shape "
                                         rf"\({nv + 2},\)"):
        op.representation([[0.5, 0.5]], np.zeros(nv + 2), psi)
    with pytest.raises(InputTypeError, match="^psi must be an array of real numbers, "
                                             "got 'abc'"):
        op.representation([[0.5, 0.5]], U, "abc")


@pytest.mark.parametrize("op", [LAP, LAME], ids=["laplace", "lame"])
@pytest.mark.parametrize("point", [(0.0, 0.0), (0.5, 0.0), (1.0, 1.0)])
def test_representation_at_a_boundary_point_names_it(op, point):
    d = op.d
    U, psi = np.zeros(d * op.V_space.ndof), np.zeros(d * op.W_space.ndof)
    inside = op.representation([[0.5, 0.5]], U, psi)
    assert np.all(inside == 0.0)                       # zero data: u = 0 inside
    with pytest.raises(PointOnBoundaryError,
                       match=rf"points must lie off the boundary Gamma.*point 1 = "
                             rf"\({point[0]}, {point[1]}\) lies on Gamma"):
        op.representation([[0.5, 0.5], point], U, psi)
    # a ValueError for the hostile-input contract, a FloatingPointError as before
    assert issubclass(PointOnBoundaryError, ValueError)
    assert issubclass(PointOnBoundaryError, FloatingPointError)


def _fe_pair():
    work = ElastoPlasticFE(rectangle_mesh(-2, 2, -2, 0, 4, 2), J2Material(1.0, 0.3, 1.0, 1.0))
    return ElasticBody(rectangle_mesh(-0.5, 0.5, 0, 2, 1, 2), 1.0, 0.3), work


@pytest.mark.parametrize("make", [
    lambda: TwoBodyContact(LAME, LAME, "C", "C", eps_n=1e-3),
    lambda: TwoBodyContact(LAME, BEBody(LAME), "C", "C", eps_n=1e-3),
    lambda: MortarContact(LAME, LAME, ("D", (0.0, 0.0)), ("D", (0.0, 0.0)), 1.0),
    lambda: (lambda w: FEMortarContact(w.elastic, w, ("top", (0, 0)), ("bottom", (0, 0)),
                                       0.0))(_fe_pair()[1])],
    ids=["penalty", "penalty-wrapped", "mortar", "fe-mortar"])
def test_one_body_given_as_both_bodies(make):
    """The same body as slave and master (or bem1 and bem2, stamp and work piece) used
    to converge: two copies of one body overlapping by its whole height."""
    with pytest.raises(ValueError, match=r"must be two bodies, got the same body twice"):
        make()
