"""Load increments and the yield stress of the elastic stamping scenes (issue 25): the
stamp of Section 4.2.7's Example 2 on a work piece that cannot yield (J2, sigma_Y =
1e30), FE/FE, FE/BE (:func:`hpfebe.scenes.stamping.touch`) and BE/BE (:func:`touch_be`).

* 1 vs 10 load increments: frictionless elastic contact is path independent (the
  equilibrium of a convex energy), so one increment and ten give the same reaction
  (BE/BE included: 10 increments at h = 1 take 0.14 s, measured 2026-12-02 on this
  code and on HEAD 9888e20 alike, load 15; the 99 s of session 9's note were not
  reproduced, and the test had run 1 vs 3 for them).  With Coulomb friction the
  flat stamp is self-similar (the same contact pattern at every lift: no path
  dependence), while the BE/BE blocks on a curved interface are path dependent (the
  contact zone grows with the load), and the tests assert both.
* huge sigma_Y equals the elastic answer: the J2 work piece with sigma_Y = 1e30 against
  the same scene with a linear elastic work piece (ElasticBody on the same mesh, or the
  work piece's own LameBEM for BE/BE) solved by :class:`TwoBodyContact` on the same load
  path (Coulomb friction mu_f = 0.2, the thesis's penalty, two increments).

Bound.  Each run stops at a backward error ||R|| / (scale + F_ref) <= rtol = 1e-8 (the
rule of :mod:`hpfebe.solvers.info`); the reaction of two runs then differs by at most
cond(J) x 2 rtol ~ 1e2 x 2e-8 relative on these meshes: 1e-6 (= BACKWARD_TOL).
Measured (2026-12-02): 1 vs 10 increments 6.7e-16 (FE/FE), 1.0e-15 (FE/BE), 3.4e-16
(BE/BE); sigma_Y = 1e30 vs elastic: reaction <= 2.5e-15, displacement <= 1.5e-15 (all three kinds).
"""

import numpy as np
import pytest

from hpfebe import TwoBodyContact
from hpfebe.constitutive import SLIP
from hpfebe.constitutive.j2 import J2Material
from hpfebe.fem import ElasticBody
from hpfebe.scenes import (NU, STAMP_SOLVER, StampContact, be_work_piece, stamp_body, touch,
                           touch_be, work_piece)

WORK = (-2.0, 2.0, -3.0, -1.0)
STAMP = (-1.0, 1.0, -1.0, 0.0)
X = (1.0, -1.1)
E = 266926.0
U = 4.2e-3
BOUND = 1e-6
KINDS = ("FE/FE", "FE/BE", "BE/BE")


def _scene(kind: str):
    """(stamp, work piece); the FE work piece fully integrated Q1, the discretisation of
    ElasticBody (B-bar, the thesis runs' choice, is another elastic operator: 0.8 %
    stiffer here)."""
    mat = J2Material(E, NU, 1e30, 450.0, 1.0)
    if kind == "BE/BE":
        return stamp_body("BE", STAMP, 1.0, E, NU), be_work_piece(WORK, 1.0, mat)
    return stamp_body(kind[-2:], STAMP, 0.5, E, NU), work_piece(WORK, 0.5, mat, "full")


def _touch(kind: str, n_load: int, mu_f: float, u: float = U):
    stamp, work = _scene(kind)
    settings = StampContact(mu_f=mu_f)
    if kind == "BE/BE":
        tr = touch_be(stamp, work, u, n_load, X, settings)
    else:
        tr = touch(stamp, work, u, n_load, 0, X, settings)
    assert tr.converged, tr.reason
    return stamp, work, tr


@pytest.mark.parametrize("kind", KINDS)
def test_one_and_ten_increments_agree_frictionless(kind):
    f1 = _touch(kind, 1, 0.0)[2].records[-1].force
    f10 = _touch(kind, 10, 0.0)[2].records[-1].force
    assert abs(f10 - f1) <= BOUND * abs(f1), (f1, f10)


@pytest.mark.parametrize("kind", KINDS)
def test_flat_stamp_with_friction_is_self_similar(kind):
    """Coulomb friction (mu_f = 0.2) is path dependent in general (the curved scene
    below), but not here: the flat stamp on linear bodies under a proportional lift has
    the same contact pattern (open / stick / slip) at every lift, so the solution is
    homogeneous of degree 1 in the lift and 1 and 10 increments agree.  Asserted: the
    pattern at a tenth of the lift is the final one (some points slip; BE/BE at h = 1:
    all four), and the reactions agree (measured: 4.4e-16 to 6.6e-16)."""
    _, _, tenth = _touch(kind, 1, 0.2, U / 10)
    _, _, one = _touch(kind, 1, 0.2)
    _, _, ten = _touch(kind, 10, 0.2)
    states = [tr.peak.result.state for tr in (tenth, one, ten)]
    assert np.array_equal(states[0], states[1]) and np.array_equal(states[1], states[2])
    assert np.any(states[1] == SLIP)                # friction carries load
    assert np.abs(one.peak.result.t_t).max() > 0
    f1, f10 = one.records[-1].force, ten.records[-1].force
    assert abs(f10 - f1) <= BOUND * abs(f1), (f1, f10)
    assert abs(10 * tenth.records[-1].force - f1) <= BOUND * abs(f1)


@pytest.mark.parametrize("path", ["increments", "press_then_shear"])
def test_be_be_curved_interface_friction_is_path_dependent(tb, path):
    """BE/BE on the curved interface of tests/invariance/conftest.py (pressed by D and
    sheared by 2 D): frictionless, 10 increments (or pressing first, then shearing)
    give the one-increment answer to the forward bound cond_2(J) (2 rtol + C eps);
    with Coulomb friction (mu_f = 0.3) the contact zone grows with the load and the
    slip depends on the path: the answers differ by more than 1000 times that bound.
    Measured: frictionless 2.7e-16 / 4.7e-16, Coulomb 4.0e-3 (10 increments) and
    4.1e-5 (press then shear), bounds 1.3e-10 to 2.3e-10."""
    for mu in (0.0, tb.MU):
        pr, _, names, fixed = tb.scene(("BE", "BE"), mu_f=mu)
        n0 = pr.dofs_on(names["upper"], "top", 0).size
        n1 = pr.dofs_on(names["upper"], "top", 1).size

        def top(s, d):
            return np.concatenate([np.full(n0, s), np.full(n1, -d),
                                   np.zeros(fixed.size - n0 - n1)])

        one = pr.solve(None, fixed, top(tb.SHEAR, tb.D), settings=tb.SETTINGS)
        if path == "increments":
            other = pr.solve(None, fixed, top(tb.SHEAR, tb.D), settings=tb.SETTINGS,
                             load_factors=np.linspace(0.1, 1.0, 10))
        else:       # press (0 < lam <= 1), then shear (1 < lam <= 2)
            other = pr.solve(None, fixed, lambda lam: top(tb.SHEAR * max(lam - 1, 0),
                                                          tb.D * min(lam, 1)),
                             settings=tb.SETTINGS, load_factors=np.linspace(0.2, 2.0, 10))
        assert one.converged and other.converged, (one.reason, other.reason)
        d = np.linalg.norm(other.U - one.U) / np.linalg.norm(one.U)
        bound = tb.forward_bound(pr, one, fixed)
        if mu == 0:
            assert d <= bound, (d, bound)
        else:
            assert d > 1e3 * bound, (d, bound)


@pytest.mark.parametrize("kind", KINDS)
def test_huge_yield_stress_is_the_elastic_answer(kind):
    stamp, work, tr = _touch(kind, 2, 0.2)
    assert tr.peak.fields["eps_p_norm"].max() == 0
    elastic = work.bem if kind == "BE/BE" else ElasticBody(work.mesh, E, NU)
    pr = TwoBodyContact(stamp, elastic, "bottom", "top", eps_n=1.0 / (10.0 * E),
                        eps_t=1.0 / (5.0 * E), mu_f=0.2)
    fixed, is_y = pr.stamp_dofs()
    res = pr.solve(None, fixed, U * is_y, load_factors=[0.5, 1.0], settings=STAMP_SOLVER)
    assert res.converged, res.reason
    K = pr.bodies["master"]
    f_int = K.internal_force(res.u_master)[0]
    force = float(f_int[K.dofs_on("bottom", 1)].sum())
    ref = tr.records[-1].force
    assert abs(force - ref) <= BOUND * abs(ref), (force, ref)
    du = np.abs(res.u_master - tr.u_work).max()
    assert du <= BOUND * np.abs(tr.u_work).max()
