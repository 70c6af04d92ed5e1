"""Issue 14 benchmarks: cold/warm start, small-N assembly, 2-thread speed-up, and the
near-touching slit of issue 10.  Skipped by default; run with

    pytest tests/benchmarks/test_bench_issue14.py --benchmark-only

Timings are minima of interleaved runs (a shared machine disturbs them all alike).
Per-function compile times: ``python tools/compile_time.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time

import numba
import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def _square(N: int, p: int = 1) -> BoundaryMesh:
    return BoundaryMesh.polygon(SQUARE, n=N // 4, p=p)


def _vkw(mesh):
    op = LaplaceBEM(mesh)
    return op.V, op.K, op.W


def _min_interleaved(fs: dict, repeat: int) -> dict:
    best = dict.fromkeys(fs, np.inf)
    for _ in range(repeat):
        for key, f in fs.items():
            t = time.perf_counter()
            f()
            best[key] = min(best[key], time.perf_counter() - t)
    return best


START = textwrap.dedent("""
    import json, time
    t0 = time.perf_counter()
    from hpfebe import BoundaryMesh
    from hpfebe.bem import LameBEM, LaplaceBEM
    t_import = time.perf_counter() - t0
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=1)
    t = time.perf_counter(); LaplaceBEM(mesh).V; t_lap = time.perf_counter() - t
    t = time.perf_counter(); LameBEM(mesh, 1.0, 0.3).S_hat; t_lame = time.perf_counter() - t
    print(json.dumps(dict(import_s=t_import, laplace_V_s=t_lap, lame_S_hat_s=t_lame)))
""")


def test_cold_and_warm_start(benchmark, tmp_path):
    """First LaplaceBEM(mesh).V and LameBEM(...).S_hat in a fresh process: with an empty
    numba cache (target < 10 s) and with the cache it left (target < 0.5 s)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), NUMBA_NUM_THREADS="1")
    runs = []
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", START], env=env, check=True,
                             capture_output=True, text=True, cwd=tmp_path)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    cold, warm = runs
    info = dict(cold_s=cold["laplace_V_s"] + cold["lame_S_hat_s"],
                warm_s=warm["laplace_V_s"] + warm["lame_S_hat_s"],
                cold=cold, warm=warm)
    benchmark.extra_info.update(info)
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
    assert info["warm_s"] < 1.0, info        # target 0.5 s on an idle machine


@pytest.mark.parametrize("N", [16, 64, 256])
def test_small_n_assembly(benchmark, N):
    """V + K + W (p = 1, unit square), one thread: the per-call overheads."""
    old = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        mesh = _square(N)
        _vkw(_square(8))
        benchmark.pedantic(_vkw, args=(mesh,), rounds=max(3, 2000 // N), iterations=1)
        benchmark.extra_info.update(N=N)
    finally:
        numba.set_num_threads(old)


@pytest.mark.parametrize("N", [1024, 4096])
def test_two_thread_speedup(benchmark, N):
    """Speed-up of V + K + W with 2 threads over 1 (target >= 1.7 on an idle 2-core
    machine; recorded, not asserted: it measures the machine's load as much as ours)."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    mesh = _square(N)
    _vkw(_square(8))

    cpu_per_wall = {}

    def run(nt):
        numba.set_num_threads(nt)
        c0, t0 = time.process_time(), time.perf_counter()
        _vkw(mesh)
        cpu_per_wall[nt] = (time.process_time() - c0) / (time.perf_counter() - t0)

    old = numba.get_num_threads()
    try:
        best = _min_interleaved({1: lambda: run(1), 2: lambda: run(2)},
                                repeat=3 if N <= 1024 else 1)
    finally:
        numba.set_num_threads(old)
    # cpu/wall of the 2-thread run below ~1.8: the machine did not give this process two
    # cores (other busy sessions; with sched_autogroup the cores are shared per session,
    # not per thread), and the speed-up says nothing about the code: see
    # test_two_thread_balance for the load-free figure
    benchmark.extra_info.update(N=N, t1_s=best[1], t2_s=best[2], speedup=best[1] / best[2],
                                cpu_per_wall_1=cpu_per_wall[1],
                                cpu_per_wall_2=cpu_per_wall[2])
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


@pytest.mark.parametrize("N", [1024, 4096])
def test_two_thread_balance(benchmark, N, monkeypatch):
    """Load balance of the parallel row loop, measured on one thread (so that a busy
    machine does not decide it): the row chunks that 2 threads get under numba's static
    schedule (4 per thread) are timed one by one, and total / max(per-thread sum) is the
    speed-up 2 threads reach on an idle machine if nothing else were serial (the
    remaining serial work - Python around the kernels, T, the finiteness check - is under
    1 % at these sizes).  Recorded; the measured one is test_two_thread_speedup."""
    from hpfebe.bem import assembly

    old = numba.get_num_threads()
    numba.set_num_threads(1)
    calls = []
    orig = assembly._assemble_rows            # the parfor that 2 threads run
    serial = assembly._assemble_rows_serial   # what one thread runs (the same arguments)

    def capture(*args):
        calls.append(args)
        return serial(*args)

    try:
        monkeypatch.setattr(assembly, "_assemble_rows_serial", capture)
        _vkw(_square(N))
        monkeypatch.setattr(assembly, "_assemble_rows_serial", serial)
        info = {}
        for name, args in zip(("V", "K"), calls):
            rows = assembly._interleaved(len(args[-2]))     # the parfor's row order
            starts = np.linspace(0, len(rows), 9).round().astype(np.int64)
            fs = {c: (lambda c=c: orig(*args[:-2], rows[starts[c]:starts[c + 1]],
                                       np.array([0, starts[c + 1] - starts[c]])))
                  for c in range(8)}
            best = _min_interleaved(fs, repeat=3 if N <= 1024 else 2)
            t = np.array([best[c] for c in range(8)])
            info[f"{name}_predicted_speedup"] = t.sum() / max(t[:4].sum(), t[4:].sum())
    finally:
        numba.set_num_threads(old)
    benchmark.extra_info.update(N=N, **info)
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


def _slit(d: float) -> BoundaryMesh:
    return BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1 + d, 1), (1 + d, 0.2),
                                 (1, 0.2), (1, 1), (0, 1)], h=0.25, p=2)


def test_near_touching_slit(benchmark):
    """Issue 10: V of the slit polygon (h = 0.25, p = 2) for d = 1e-2 ... 1e-8; the
    time at 1e-8 within 3x of 1e-2 (was 0.9 s at 1e-4, 56 s at 1e-6, > 90 s at 1e-8)."""
    ds = (1e-2, 1e-4, 1e-6, 1e-8)
    meshes = {d: _slit(d) for d in ds}
    LaplaceBEM(meshes[1e-2]).V
    best = _min_interleaved({d: (lambda m=m: LaplaceBEM(m).V) for d, m in meshes.items()},
                            repeat=15)
    benchmark.extra_info.update({f"d={d:g}_ms": 1e3 * t for d, t in best.items()})
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
    assert best[1e-8] < 3.0 * best[1e-2], best


def test_lame_S_hat_small(benchmark):
    """S_hat of the Lame operators, N = 64, p = 1 (the contact sweeps' unit of work)."""
    mesh = _square(64)
    LameBEM(_square(8), 1.0, 0.3).S_hat
    benchmark(lambda: LameBEM(mesh, 1.0, 0.3).S_hat)
