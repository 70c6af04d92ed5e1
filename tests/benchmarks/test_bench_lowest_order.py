"""Issue 14, small N: V + K + W of the Laplace and of the Lame operators at p = 1 (unit
square, one thread) by the closed forms of hpfebe.bem.lowest_order against the general
quadrature path (``closed_form=False``), minima of interleaved runs.  Skipped by default;
run with

    NUMBA_NUM_THREADS=1 pytest tests/benchmarks/test_bench_lowest_order.py --benchmark-only

The peer comparison (HILBERT's C++ port) is benchmarks/peers/run_peers.py.
"""

from __future__ import annotations

import time

import numba
import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def _vkw(family, mesh, closed_form):
    op = (LaplaceBEM(mesh, closed_form=closed_form) if family == "laplace"
          else LameBEM(mesh, 1.0, 0.3, closed_form=closed_form))
    return op.V, op.K, op.W


@pytest.mark.parametrize("family", ["laplace", "lame"])
@pytest.mark.parametrize("N", [16, 64, 256, 1024])
def test_closed_form_vs_general(benchmark, N, family):
    """Closed form / general path time of V + K + W at p = 1 (recorded; asserted only
    that the closed form is faster).  For Lame the part of S_hat that depends on the
    assembly (S_hat adds the same dense factorisation either way); measured (one thread,
    load ~1.3): N = 16: 0.12 / 1.29 ms, 64: 0.59 / 7.4 ms, 256: 9.9 / 74 ms, 1024: 99 /
    781 ms."""
    old = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        mesh = BoundaryMesh.polygon(SQUARE, n=N // 4, p=1)
        small = BoundaryMesh.polygon(SQUARE, n=2, p=1)
        _vkw(family, small, True)
        _vkw(family, small, False)
        best = {True: np.inf, False: np.inf}
        for _ in range(max(3, 1024 // N)):
            for cf in (True, False):
                t = time.perf_counter()
                _vkw(family, mesh, cf)
                best[cf] = min(best[cf], time.perf_counter() - t)
    finally:
        numba.set_num_threads(old)
    benchmark.extra_info.update(N=N, closed_ms=1e3 * best[True], general_ms=1e3 * best[False],
                                ratio=best[True] / best[False])
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
    assert best[True] < best[False], best
