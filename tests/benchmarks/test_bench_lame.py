"""pytest-benchmark of the Lame operators (skipped by default: run with
``pytest tests/benchmarks --benchmark-only``)."""

from __future__ import annotations

import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem.lame import LameBEM


def _bem(n, p):
    mesh = BoundaryMesh.polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)], n=n, p=p,
                                labels=["C", "N", "D", "N"])
    return LameBEM(mesh, 266926.0, 0.29)


@pytest.mark.parametrize("n,p", [(32, 1), (16, 3)])
def test_bench_S_hat(benchmark, n, p):
    """V, K, Vt assembly and S_hat (the Table 3.1 cost per mesh)."""
    _bem(2, p).S_hat                      # compile / load the numba cache
    benchmark(lambda: _bem(n, p).S_hat)
