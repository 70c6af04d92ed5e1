"""Assembly of the hp-Nitsche FE/BE system (Chapter 2), mid-size case.

Example 1, FE h^-1 = 11 (363 elements), BE h^-1 = 12 (48 elements), p1 = p2 = 3: FE
stiffness, S_hat, the interface terms on the common refinement and the right-hand side
(~3700 unknowns).  A warm-up builds once so that numba compilation is not timed.
"""

import pytest

from hpfebe.coupling import NitscheFEBE
from hpfebe.scenes.interface import SMOOTH


@pytest.fixture(scope="module")
def warm():
    NitscheFEBE(SMOOTH, 2, 3, 3)


def test_bench_nitsche_assembly(benchmark, warm):
    model = benchmark(NitscheFEBE, SMOOTH, 11, 12, 3)
    assert model.ndof > 3000


def test_bench_nitsche_solve(benchmark, warm):
    model = NitscheFEBE(SMOOTH, 11, 12, 3)
    sol = benchmark(model.solve, 10.0)
    assert sol.info["residual"] < 1e-10
