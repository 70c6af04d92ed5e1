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
import types

import numba
import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM, assembly, threads
from hpfebe.bem.kernels import LAPLACE_DL, LAPLACE_SL
from hpfebe.bem.laplace import NO_LOG, SINGLE_LAYER_LOGC

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def _square(N: int, p: int = 1) -> BoundaryMesh:
    return BoundaryMesh.polygon(SQUARE, n=N // 4, p=p)


def _vkw(mesh):
    op = LaplaceBEM(mesh)
    return op.V, op.K, op.W


def _vkw_quadrature(mesh):
    """V, K, W by the quadrature assembly of :mod:`hpfebe.bem.assembly` (what LaplaceBEM
    uses for p >= 2; at p = 1 it may take closed forms instead)."""
    op = LaplaceBEM(mesh)
    V = assembly.assemble(LAPLACE_SL, SINGLE_LAYER_LOGC, op.kp, op.W_space, op.W_space,
                          symmetric=True)
    K = assembly.assemble(LAPLACE_DL, NO_LOG, [0.0], op.W_space, op.V_space)
    return V, K, assembly.sandwich(op.T, V)


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
    """Speed-up of V + K + W (quadrature assembly, p = 1) with 2 threads over 1 (target
    >= 1.7 on an idle 2-core machine; recorded, not asserted: it measures the machine's
    load as much as ours)."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    mesh = _square(N)
    _vkw_quadrature(_square(64))

    cpu_per_wall = {}

    def run(nt):
        numba.set_num_threads(nt)
        c0, t0 = time.process_time(), time.perf_counter()
        _vkw_quadrature(mesh)
        cpu_per_wall[nt] = (time.process_time() - c0) / (time.perf_counter() - t0)

    old = numba.get_num_threads()
    try:
        best = _min_interleaved({1: lambda: run(1), 2: lambda: run(2)},
                                repeat=9 if N <= 1024 else 1)
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


_POOLS: list = []     # the _SerialPool instances of one run


class _SerialPool:
    """Stand-in for the pool of hpfebe.bem.threads: runs each task at once, on this
    thread, and records its CPU time (thread_time: what a busy machine hardly disturbs)."""

    def __init__(self, max_workers):
        self.workers, self.tasks = max_workers, []
        _POOLS.append(self)

    def submit(self, fn, *args):
        t = time.thread_time()
        value = fn(*args)
        self.tasks.append(time.thread_time() - t)
        return types.SimpleNamespace(result=lambda: value)

    def makespan(self) -> float:
        """Time of the tasks on ``workers`` threads, each taking the next task when free."""
        free = [0.0] * self.workers
        for t in self.tasks:
            free[int(np.argmin(free))] += t
        return max(free)


@pytest.mark.parametrize("N", [1024, 4096])
def test_two_thread_balance(benchmark, N, monkeypatch):
    """The speed-up 2 threads reach on an idle 2-core machine, predicted from one thread's
    CPU times: V + K + W run with numba.get_num_threads() = 2, but every thread-pool task
    runs at once on this thread, timed; 2 threads taking the tasks in order as they become
    free would need (time outside the tasks) + sum over pools of the makespan.  Recorded;
    the measured one is test_two_thread_speedup."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    old = numba.get_num_threads()
    monkeypatch.setattr(threads, "executor", _SerialPool)
    mesh = _square(N)
    best = None
    try:
        numba.set_num_threads(2)
        _vkw_quadrature(_square(64))
        for _ in range(3 if N <= 1024 else 1):
            _POOLS.clear()
            t = time.thread_time()
            _vkw_quadrature(mesh)
            total = time.thread_time() - t
            tasks = sum(sum(p.tasks) for p in _POOLS)
            t2 = total - tasks + sum(p.makespan() for p in _POOLS)
            if best is None or total < best[0]:
                best = (total, t2, total - tasks)
    finally:
        numba.set_num_threads(old)
    benchmark.extra_info.update(N=N, t1_cpu_s=best[0], t2_predicted_s=best[1],
                                serial_s=best[2], predicted_speedup=best[0] / best[1])
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
