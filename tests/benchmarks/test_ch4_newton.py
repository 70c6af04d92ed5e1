"""pytest-benchmark of one Newton step of each FE body type of Chapter 4 at the finest
stamping mesh, h = 0.05 (Q1 B-bar work piece [-2, 2] x [-3, -1]: 3321 nodes, 6642 dofs;
skipped by default, ``--benchmark-skip`` in pyproject.toml; run with
``NUMBA_NUM_THREADS=1 pytest tests/benchmarks/test_ch4_newton.py --benchmark-only``).

One step = the residual and tangent at a plastic iterate (return map, stress, forces,
the tangent on its fixed pattern) and the Newton update (the sparse LU:
PARDISO with its analysis reused when pypardiso is installed, else SuperLU):

* the plastic work piece alone under a prescribed punch (:class:`DisplacementSteps`);
* the plastic work piece under an elastic FE stamp (FE/FE, frictional penalty contact,
  the load steps of :func:`hpfebe.scenes.stamping.touch`);
* the same under a BE stamp (FE/BE, S_hat of the stamp).
"""

import numpy as np
import pytest

from hpfebe.bodies import PlasticFEBody
from hpfebe.constitutive.j2 import J2Material
from hpfebe.contact import ContactSettings, TwoBodyContact
from hpfebe.contact.loading import LoadSteps
from hpfebe.fem.plastic_body import DisplacementSteps
from hpfebe.scenes.materials import E, H, NU, SIGMA_Y
from hpfebe.scenes.stamping import stamp_body, work_piece

H_FINE = 0.05
WORK = (-2.0, 2.0, -3.0, -1.0)
LIFT = 4.3e-4                  # the first increment of Example 1 (4.3e-3 in 10)


def _work():
    return work_piece(WORK, H_FINE, J2Material(E, NU, SIGMA_Y, H, 1.0))


def _stepper(problem, x):
    """One Newton step, alternating between x and a copy moved at round-off level (the
    plastic body caches its state at the last u: every call computes it anew)."""
    xs, k = (x, x * (1.0 + 1e-13)), [0]

    def step():
        k[0] += 1
        return problem.step(problem.evaluate(xs[k[0] % 2]))

    return step


def predictor_iterate(stamp, work, lift: float = LIFT):
    """(problem, steps, x): the stamp on the plastic ``work`` body (frictional penalty
    contact of the stamping runs), the load steps of a first increment ``lift`` and its
    bonded predictor's iterate x."""
    pr = TwoBodyContact(stamp, work, "bottom", "top", eps_n=1 / (10 * E),
                        eps_t=1 / (5 * E), mu_f=0.2)
    fixed, is_y = pr.stamp_dofs()
    settings = ContactSettings(rtol=1e-8, max_iter=40, line_search=True, predictor=True,
                               lu_ordering="MMD_AT_PLUS_A")
    steps = LoadSteps(pr, None, fixed, np.where(is_y, lift, 0.0), settings)
    steps.problem(1.0)
    x = steps.start(np.zeros(pr.ndofs), 1.0)
    return pr, steps, steps.bonded_predictor(steps.evaluate(x))


def test_bench_newton_step_plastic_body(benchmark):
    """The work piece alone: bottom lifted by LIFT, the top centre third held (plastic
    under it)."""
    fe = _work()
    bottom = fe.elastic.dofs_on("bottom", 1)
    xy = fe.elastic.dof_coordinates()
    top = fe.elastic.dofs_on("top")
    top = top[np.abs(xy[top, 0]) < 0.7]
    fixed = np.concatenate([bottom, top])
    steps = DisplacementSteps(fe, fixed, np.where(np.isin(fixed, bottom), LIFT, 0.0))
    steps.problem(1.0)
    x = steps.start(np.zeros(fe.ndofs), 1.0)
    x = x + steps.step(steps.evaluate(x))      # after the first step: a plastic iterate
    assert fe.state_at(x)[1].plastic.any()
    benchmark(_stepper(steps, x))


@pytest.mark.parametrize("stamp_kind", ["FE", "BE"])
def test_bench_newton_step_stamping(benchmark, stamp_kind):
    """A Newton step of the first increment of Example 1 (stamp [0.2, 1.2] x [-1, 1])
    at the bonded predictor's iterate (about a third of the work piece's points
    plastic)."""
    fe = _work()
    stamp = stamp_body(stamp_kind, (0.2, 1.2, -1.0, 1.0), H_FINE, E, NU)
    pr, steps, x = predictor_iterate(stamp, PlasticFEBody(fe))
    assert fe.state_at(x[pr.offset:])[1].plastic.mean() > 0.1
    benchmark(_stepper(steps, x))
