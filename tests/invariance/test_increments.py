"""Load increments and the yield stress of the elastic stamping scenes (issue 25): the
stamp of Section 4.2.7's Example 2 on a work piece that cannot yield (J2, sigma_Y =
1e30), FE/FE, FE/BE (:func:`hpfebe.scenes.stamping.touch`) and BE/BE (:func:`touch_be`).

* 1 vs 10 load increments (BE/BE: 1 vs 3, for time): frictionless elastic contact is
  path independent (the equilibrium of a convex energy), so one increment and ten give
  the same reaction.
* huge sigma_Y equals the elastic answer: the J2 work piece with sigma_Y = 1e30 against
  the same scene with a linear elastic work piece (ElasticBody on the same mesh, or the
  work piece's own LameBEM for BE/BE) solved by :class:`TwoBodyContact` on the same load
  path (Coulomb friction mu_f = 0.2, the thesis's penalty, two increments).

Bound.  Each run stops at a backward error ||R|| / (scale + F_ref) <= rtol = 1e-8 (the
rule of :mod:`hpfebe.solvers.info`); the reaction of two runs then differs by at most
cond(J) x 2 rtol ~ 1e2 x 2e-8 relative on these meshes: 1e-6 (= BACKWARD_TOL).
Measured (2026-12-02): 1 vs 10 increments 7e-16 (FE/FE), 1e-15 (FE/BE); sigma_Y = 1e30
vs elastic: reaction <= 2.5e-15, displacement <= 1.5e-15 (all three kinds).
"""

import numpy as np
import pytest

from hpfebe import TwoBodyContact
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


def _touch(kind: str, n_load: int, mu_f: float):
    stamp, work = _scene(kind)
    settings = StampContact(mu_f=mu_f)
    if kind == "BE/BE":
        tr = touch_be(stamp, work, U, n_load, X, settings)
    else:
        tr = touch(stamp, work, U, n_load, 0, X, settings)
    assert tr.converged, tr.reason
    return stamp, work, tr


@pytest.mark.parametrize("kind", KINDS)
def test_one_and_ten_increments_agree_frictionless(kind):
    # BE/BE: 1 vs 3 (an increment of the plastic BE work piece costs ~10 s on a loaded
    # 2-core machine, its cell-strain Newton runs even when nothing yields)
    n = 3 if kind == "BE/BE" else 10
    f1 = _touch(kind, 1, 0.0)[2].records[-1].force
    f10 = _touch(kind, n, 0.0)[2].records[-1].force
    assert abs(f10 - f1) <= BOUND * abs(f1), (f1, f10)


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
