"""pytest-benchmark of the pieces of one refinement step of the adaptive FE/FE contact
scene (Figures 4.13-4.16; skipped by default, run with ``pytest
tests/benchmarks/test_bench_adaptive_fefe.py --benchmark-only``): the indicator (3.100)
by the closed-form P1 path and by scikit-fem's facet quadrature, the P1 stiffness in
closed form and by quadrature, one Woodbury Newton solve.  The meshes: the initial
meshes refined uniformly twice (5412 dofs, uniform step 2 of the scene)."""

import numpy as np
import pytest

from hpfebe.adaptivity import hooke_stress, fe_indicators, two_body_indicators
from hpfebe.contact.woodbury import WoodburySolver
from hpfebe.fem import ElasticBody, refine_labelled
from hpfebe.scenes import adaptive_fefe as scene


@pytest.fixture(scope="module")
def solved():
    prm = scene.AdaptiveStudy()
    meshes = [refine_labelled(refine_labelled(m)) for m in prm.initial_meshes()]
    pr, res = prm.solve(meshes, prm.load_steps, prm.settings)
    assert res.converged
    return prm, meshes, pr, res


@pytest.mark.parametrize("method", ["cellwise", "quadrature"])
def test_bench_fe_indicators(benchmark, solved, method):
    _, _, pr, res = solved
    b = pr.master
    tractions = {"left": lambda x, y, nx, ny: np.zeros((2,) + np.shape(x))}
    benchmark(lambda: fe_indicators(b.basis, res.u_master, tractions=tractions,
                                    stress=hooke_stress(b.lam, b.mu), method=method))


def test_bench_two_body_indicators(benchmark, solved):
    _, _, pr, res = solved
    benchmark(lambda: two_body_indicators(pr, res, contact=scene.CONTACT, free=scene.OPEN))


@pytest.mark.parametrize("assembly", ["closed_form", "quadrature"])
def test_bench_p1_stiffness(benchmark, solved, assembly):
    prm, meshes, _, _ = solved
    benchmark(lambda: ElasticBody(meshes[1], prm.E, prm.nu, prm.plane, assembly=assembly))


def test_bench_woodbury_solve(benchmark, solved):
    """One Newton system (K + C) d = r with every contact point active (K factorised
    once, outside the timing)."""
    _, _, pr, res = solved
    fixed, _ = pr.stamp_dofs()
    free = np.setdiff1d(np.arange(pr.ndofs), fixed)
    K = pr._blocks(pr.slave.K, pr.master.K)
    wb = WoodburySolver(K, free, pr.offset, pr.Gn, pr.Gt)
    w = np.asarray(res.weights)
    wn, wt, wtn = w * 1e6, w * 5e5, w * 1e4
    r = np.random.default_rng(0).standard_normal(free.size)
    d = wb.solve(wn, wt, wtn, r)
    assert np.linalg.norm(wb.matvec(wn, wt, wtn, d) - r) <= 1e-8 * np.linalg.norm(r)
    benchmark(lambda: wb.solve(wn, wt, wtn, r))
