"""Mesh validation cost (issue 10): the crossing test of BoundaryMesh was O(N^2)
(32k elements 8-14 s, 4e5 over 60 s); the uniform-grid test is near-linear.

Run: ``pytest tests/benchmarks/test_bench_geometry.py --benchmark-only``.
Measured (2 shared cores): 32k elements 0.05 s, 128k 0.16-0.30 s, 4e5 0.6-1.0 s;
2000 elements: validation 2 ms against 0.5 s for assembling V (p = 1).
"""

import numpy as np
import pytest

from hpfebe import BoundaryMesh


def _circle(n: int):
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    nodes = np.column_stack([np.cos(th), np.sin(th)])
    return nodes, np.column_stack([np.arange(n), (np.arange(n) + 1) % n])


@pytest.mark.parametrize("n", [32_000, 128_000, 400_000])
def test_validation_circle(benchmark, n):
    nodes, seg = _circle(n)
    BoundaryMesh.from_segments(*_circle(16))                     # compile
    m = benchmark(BoundaryMesh.from_segments, nodes, seg)
    assert m.n_elements == n


@pytest.mark.parametrize("n", [8_000, 100_000])
def test_validation_square(benchmark, n):
    BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2)  # compile
    m = benchmark(BoundaryMesh.polygon, [(0, 0), (1, 0), (1, 1), (0, 1)], n=n)
    assert m.n_elements == 4 * n
