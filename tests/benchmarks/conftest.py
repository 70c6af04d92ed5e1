"""Shared fixtures for the benchmarks.

The default ``pytest`` run passes ``--benchmark-skip`` (pyproject.toml, addopts), so
benchmarks are skipped; ``pytest tests/benchmarks --benchmark-only`` overrides it.
Benchmarks measure single-threaded performance unless they say otherwise: set
NUMBA_NUM_THREADS=1 in the environment to compare with the Snakemake jobs.
"""

import pytest


@pytest.fixture(scope="session")
def square_mesh():
    """Factory: the unit square with ``n`` elements per side and degree ``p``."""
    from hpfebe import BoundaryMesh

    def make(n: int = 8, p: int = 1):
        return BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=n, p=p)

    return make
