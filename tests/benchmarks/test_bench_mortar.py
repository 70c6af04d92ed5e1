"""pytest-benchmark of the hp-mortar pieces (skipped by default, ``--benchmark-skip`` in
pyproject.toml; run with ``pytest tests/benchmarks/test_bench_mortar.py
--benchmark-only``)."""

import numpy as np

from hpfebe.scenes import model_meshes, model_problem
from hpfebe.solvers import DtNSettings, projected_cg
from hpfebe.coupling.mortar import MortarProjection


def test_bench_mortar_assembly(benchmark):
    """D, B on the common refinement of the finest Figure 4.18 contact meshes
    (64 : 48, p = 2)."""
    m1, m2, _ = model_meshes(64, 48, 2, 2)
    benchmark(lambda: MortarProjection(m1, m2))


def test_bench_dtn_solve(benchmark):
    """One DtN solve (Algorithm 4.3 with Uzawa and projected CG, Tresca F = 0.1) on the
    Table 4.1 meshes; S_hat and the Schur complements assembled once outside the
    timing."""
    pr = model_problem()
    benchmark(lambda: pr.dtn(DtNSettings(0.7, 0.5)))


def test_bench_dtn_table_reading(benchmark):
    """One Table 4.1 cell in the reading reported there (Coulomb bound from the previous
    DtN pressure, function transfer): (omega_D, omega_N) = (0.5, 0.5), 23 DtN and
    ~11700 Uzawa iterations."""
    pr = model_problem()
    settings = DtNSettings(0.5, 0.5, transfer="function")
    benchmark.pedantic(lambda: pr.dtn(settings, friction="coulomb"), rounds=3, iterations=1)


def test_bench_projected_cg(benchmark):
    """Polyak's projected CG (compiled kernel) on the condensed contact QP of the Table
    4.1 meshes from a cold start."""
    pr = model_problem()
    upper = np.concatenate([pr.gap, np.full(pr.nc, np.inf)])
    benchmark(lambda: projected_cg(pr.A, pr.b, upper, tol=1e-11))
