"""Unit scaling of the elastic stamping scenes (issue 25): the stamp of Section 4.2.7's
Example 2 pressed onto a work piece that cannot yield (J2 with sigma_Y = 1e30), FE/FE,
FE/BE (:func:`hpfebe.scenes.stamping.touch`) and BE/BE (:func:`touch_be`), Coulomb
friction mu_f = 0.2, two load increments.  The problem is positively homogeneous of
degree one in the prescribed lift u (zero initial gap, penalty and Coulomb laws
homogeneous) and in E (1/eps = factor x E), so the reaction F(u, E) / (u E) must not
depend on u or E.

Bound.  Newton stops at ||R|| <= rtol (scale + F_ref) (the backward-error rule of
:mod:`hpfebe.solvers.info`, rtol = 1e-8, F_ref = :func:`reference_force`, a force of the
data that scales with u and E); the reaction is a linear functional of the displacement
error J^{-1} R, so its relative error is at most cond(J) x backward error ~ 1e2 x 1e-8
on these meshes: 1e-6 (= BACKWARD_TOL, the six digits the solvers promise).  Measured
(2026-12-02): at most 1e-15 over u in [4.2e-12, 4.2e-3] and E in [1, 1e12].  Before the
floor was scaled with the data (a yield force rtol sigma_Y width), the lift 4.2e-12 was
accepted at its start after 0 Newton iterations with a force 14.7 x the linear one.
"""

import pytest

from hpfebe.constitutive.j2 import J2Material
from hpfebe.scenes import NU, StampContact, be_work_piece, stamp_body, touch, touch_be, \
    work_piece

WORK = (-2.0, 2.0, -3.0, -1.0)
STAMP = (-1.0, 1.0, -1.0, 0.0)
X = (1.0, -1.1)
E0 = 266926.0
BOUND = 1e-6
KINDS = ("FE/FE", "FE/BE", "BE/BE")


def elastic_force(kind: str, u: float, E: float = E0, n_load: int = 2,
                  mu_f: float = 0.2) -> tuple[float, int]:
    """(reaction at full lift, Newton iterations of the first increment) of one elastic
    touch."""
    mat = J2Material(E, NU, 1e30, 450.0 * E / E0, 1.0)
    settings = StampContact(mu_f=mu_f)
    if kind == "BE/BE":
        tr = touch_be(stamp_body("BE", STAMP, 1.0, E, NU), be_work_piece(WORK, 1.0, mat),
                      u, n_load, X, settings)
    else:
        stamp = stamp_body(kind[-2:], STAMP, 0.5, E, NU)
        tr = touch(stamp, work_piece(WORK, 0.5, mat), u, n_load, 0, X, settings)
    assert tr.converged, tr.reason
    return tr.records[-1].force, tr.records[0].iterations


@pytest.mark.parametrize("kind", KINDS)
def test_force_is_linear_in_the_lift_down_to_1e_12(kind):
    ref, _ = elastic_force(kind, 4.2e-3)
    for u in (4.2e-6, 4.2e-9, 4.2e-12):
        f, its = elastic_force(kind, u)
        assert its >= 1                          # the start is never "converged"
        assert abs(f / u - ref / 4.2e-3) <= BOUND * abs(ref / 4.2e-3), (u, f / u)


@pytest.mark.parametrize("kind", KINDS)
def test_force_is_linear_in_E_up_to_1e12(kind):
    ref, _ = elastic_force(kind, 4.2e-3)
    for E in (1.0, 1e8, 1e12):
        f, _ = elastic_force(kind, 4.2e-3, E=E)
        assert abs(f * E0 / E - ref) <= BOUND * abs(ref), (E, f * E0 / E)


def test_tiny_lift_and_huge_modulus_together():
    """u -> s u with E -> E / s keeps the force: 4.2e-12 at E = 2.7e14 gives the force of
    4.2e-3 at E0."""
    ref, _ = elastic_force("FE/FE", 4.2e-3)
    f, _ = elastic_force("FE/FE", 4.2e-12, E=E0 * 1e9)
    assert abs(f - ref) <= BOUND * abs(ref)
