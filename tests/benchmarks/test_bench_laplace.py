"""Assembly of the Laplace matrices V, K and W (issue 2 benchmarks).

Run: ``pytest tests/benchmarks/test_bench_laplace.py --benchmark-only``.  Timings are
single-threaded (numba.set_num_threads(1)), after compilation; the compile (JIT) time is
measured on its own in a fresh process with an empty numba cache.

Targets (issue 2): V, K and W for N = 1024, p = 1 in under 0.5 s; time growing like N^2
(log-log slope 2 +- 0.2 from 256 to 4096); peak memory below three times the output
matrices (no N^2 x q^2 temporaries).
"""

import json
import os
import subprocess
import sys
import textwrap
import time

import numba
import numpy as np
import pytest

from hpfebe.bem import LaplaceBEM


def assemble_all(mesh):
    op = LaplaceBEM(mesh)
    return op.V, op.K, op.W


@pytest.fixture(autouse=True)
def one_thread():
    old = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(old)


@pytest.mark.parametrize("N, p", [(256, 1), (1024, 1), (4096, 1), (256, 4), (256, 8)])
def test_assembly_V_K_W(benchmark, square_mesh, N, p):
    mesh = square_mesh(N // 4, p)
    assemble_all(square_mesh(4, p))  # compile outside the timing
    rounds = 1 if N >= 4096 else 3
    V, K, W = benchmark.pedantic(assemble_all, args=(mesh,), rounds=rounds, iterations=1)
    benchmark.extra_info.update(N=N, p=p, ndof_W=V.shape[0], ndof_V=W.shape[0])
    if N == 1024 and p == 1:
        assert benchmark.stats.stats.min < 0.5, "target: V, K, W for N=1024, p=1 in < 0.5 s"


def test_assembly_scales_like_N_squared(benchmark, square_mesh):
    """log-log slope of the assembly time from N = 256 to 4096 (p = 1), in CPU time of
    this (single-threaded) process, which other load on the machine disturbs less."""
    assemble_all(square_mesh(4, 1))
    Ns = np.array([256, 512, 1024, 2048, 4096])
    times = []
    for N in Ns:
        mesh = square_mesh(N // 4, 1)
        best = np.inf
        for _ in range(2 if N <= 1024 else 1):
            t = time.process_time()
            assemble_all(mesh)
            best = min(best, time.process_time() - t)
        times.append(best)
    slope = np.polyfit(np.log(Ns), np.log(times), 1)[0]
    benchmark.extra_info.update(N=Ns.tolist(), seconds=times, slope=float(slope))
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
    assert abs(slope - 2.0) <= 0.2, (slope, times)


SCRIPT = textwrap.dedent("""
    import json, resource, sys, time
    t0 = time.perf_counter()
    import numba
    numba.set_num_threads(1)
    from hpfebe import BoundaryMesh
    from hpfebe.bem import LaplaceBEM
    t_import = time.perf_counter() - t0
    def rss():
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    mesh = lambda n, p: BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=n, p=p)
    t = time.perf_counter()
    op = LaplaceBEM(mesh(2, 1)); op.V, op.K, op.W
    first = time.perf_counter() - t
    t = time.perf_counter()
    op = LaplaceBEM(mesh(2, 1)); op.V, op.K, op.W
    second = time.perf_counter() - t
    N = int(sys.argv[1])
    base = rss()
    op = LaplaceBEM(mesh(N // 4, 1))
    mats = (op.V, op.K, op.W)
    out = sum(m.nbytes for m in mats)
    print(json.dumps(dict(import_s=t_import, first_call_s=first, warm_call_s=second,
                          peak_increase_bytes=rss() - base, output_bytes=out)))
""")


def _fresh(tmp_path, N, cache_dir):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir), NUMBA_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(N)], env=env, check=True,
                         capture_output=True, text=True, cwd=tmp_path)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_jit_compile_time_and_peak_memory(benchmark, tmp_path):
    """Compile time (first call with an empty cache minus the warm call), the first call
    with a warm on-disk cache, and the peak memory of assembling N = 4096 at p = 1."""
    cold = _fresh(tmp_path, 4096, tmp_path / "numba_cache")
    warm = _fresh(tmp_path, 256, tmp_path / "numba_cache")
    info = dict(jit_compile_s=cold["first_call_s"] - cold["warm_call_s"],
                first_call_cached_s=warm["first_call_s"],
                peak_increase_MB=cold["peak_increase_bytes"] / 2**20,
                output_MB=cold["output_bytes"] / 2**20)
    benchmark.extra_info.update(info)
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
    assert cold["peak_increase_bytes"] < 3 * cold["output_bytes"], info
