"""pytest-benchmark of one Newton step of the BE/BE pair of Example 2 (Chapter 4,
thesis Section 4.2.4 with the plastic BE work piece of Algorithm 4.2, backward Euler
cells): the BE stamp [-1, 1] x [-1, 0] (degree 1) on the BE work piece [-2, 2] x [-3, -1]
with crossed cells of size bebe_h = 0.4 (10 x 5 squares, 200 triangles, 600 cell
strains), frictional penalty contact, at the first increment's bonded predictor iterate
(skipped by default, ``--benchmark-skip`` in pyproject.toml; run with
``NUMBA_NUM_THREADS=1 pytest tests/benchmarks/test_ch4_be_newton.py --benchmark-only``).

One step = the residual at an iterate (the inner backward Euler solve of the cell
strains, :meth:`ElastoPlasticBE.implicit_response_lazy`: I - M_pp D_p per inner
iteration solved by a single-precision LU refined in double, its factors reused while they
converge, :mod:`hpfebe.bodies.refined_lu`) and the Newton update (the consistent tangent
S_hat - G_p D_p (I - M_pp D_p)^-1 B_p by one double solve at the inner solution, the
dense contact system).
"""

import numpy as np

from hpfebe.bodies.plastic_be import PlasticBEBody
from hpfebe.constitutive.j2 import J2Material
from hpfebe.scenes.materials import E, H, NU, SIGMA_Y
from hpfebe.scenes.stamping import be_work_piece, stamp_body

# one Newton step (the cached state moved away) at the bonded predictor's iterate
from .test_ch4_newton import _stepper, predictor_iterate

H_BEBE = 0.4
WORK = (-2.0, 2.0, -3.0, -1.0)
STAMP = (-1.0, 1.0, -1.0, 0.0)
LIFT = 4.2e-4                  # the first increment of Example 2 (4.2e-3 in 10)


def test_bench_newton_step_bebe(benchmark):
    """A Newton step of the first increment of Example 2's BE/BE run (theta = 1) at the
    bonded predictor's iterate (a plastic zone under the stamp)."""
    be = be_work_piece(WORK, H_BEBE, J2Material(E, NU, SIGMA_Y, H, 1.0), "crossed")
    stamp = stamp_body("BE", STAMP, H_BEBE, E, NU, p=1)
    pr, steps, x = predictor_iterate(stamp, PlasticBEBody(be), LIFT)
    plastic = be.implicit_response(x[pr.offset:])[1].plastic
    assert plastic.mean() > 0.1
    dx = steps.step(steps.evaluate(x))
    assert np.all(np.isfinite(dx)) and np.abs(dx).max() > 0
    step = _stepper(steps, x)

    def fresh_step():
        be._icache = None     # its recent inner solutions would hold both points of step
        return step()

    benchmark(fresh_step)
