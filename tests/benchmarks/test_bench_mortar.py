"""pytest-benchmark of the hp-mortar pieces (skipped by default, ``--benchmark-skip`` in
pyproject.toml; run with ``pytest tests/test_mortar_bench.py --benchmark-only``)."""

from hpfebe.contact.mortar import model_meshes, model_problem
from hpfebe.coupling.mortar import MortarProjection


def test_bench_mortar_assembly(benchmark):
    """D, B on the common refinement of the Table 4.1 contact meshes (16 : 12, p = 2)."""
    m1, m2, _ = model_meshes(64, 48, 2, 2)
    benchmark(lambda: MortarProjection(m1, m2))


def test_bench_dtn_solve(benchmark):
    """One DtN solve (Algorithm 4.3 with Uzawa and projected CG), S_hat and the Schur
    complements assembled once outside the timing."""
    pr = model_problem()
    benchmark(lambda: pr.dtn(0.7, 0.5))
