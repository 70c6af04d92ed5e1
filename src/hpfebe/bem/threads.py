"""The Python threads of the BEM kernels (issue 14).

The assembly, closed-form and potential kernels are compiled ``nogil`` and write disjoint
rows, so chunks of rows run on Python threads: no parallel (parfor) compilation, the same
bits as one thread.  ``numba.get_num_threads()`` (NUMBA_NUM_THREADS, or
``numba.set_num_threads``) sets how many; below a per-module amount of work per thread one
direct call is faster.

One pool per process, kept between calls: creating and joining the threads of a pool
cost ~0.3 ms a call, and V + K + W of one mesh made seven pools (3 % of a 2-thread
assembly at N = 1024).  A forked child (another pid) makes its own.

The large output matrices start on a huge-page boundary (:func:`zeros_aligned`): first-touch
page faults are what threads writing a fresh matrix cannot share.
"""

from __future__ import annotations

import math
import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

_LOCK = threading.Lock()
_POOLS: dict = {}        # workers -> pool of this process (pid in "pid")


def n_threads(work: float, min_per_thread: float) -> int:
    """numba.get_num_threads(), or 1 when ``work`` (element pairs, points x elements ...)
    is below ``min_per_thread`` per thread."""
    nt = numba.get_num_threads()
    return 1 if nt <= 1 or work < min_per_thread * nt else nt


def interleaved(n: int) -> np.ndarray:
    """0, n-1, 1, n-2, ...: short and long rows of a triangle alternate (load balance)."""
    idx = np.arange(n)
    return np.where(idx % 2 == 0, idx // 2, n - 1 - idx // 2)


def executor(workers: int) -> ThreadPoolExecutor:
    """The process's pool of ``workers`` threads (made on first use, then kept)."""
    with _LOCK:
        if _POOLS.get("pid") != os.getpid():       # first use, or a forked child
            _POOLS.clear()
            _POOLS["pid"] = os.getpid()
        if workers not in _POOLS:
            _POOLS[workers] = ThreadPoolExecutor(max_workers=workers,
                                                 thread_name_prefix="hpfebe-bem")
        return _POOLS[workers]


def run_chunks(fn, chunks, workers: int) -> list:
    """[fn(c) for c in chunks] on ``workers`` threads, each taking the next chunk when
    free (dynamic: chunks of uneven cost balance); the results in the order of
    ``chunks``, the first exception raised.  ``fn`` must not call run_chunks itself
    (the pool's threads would wait for themselves)."""
    pool = executor(workers)
    futures = [pool.submit(fn, c) for c in chunks]
    return [f.result() for f in futures]


HUGE_PAGE = 2 << 20        # bytes of a transparent huge page (x86-64, aarch64 4k)


def zeros_aligned(shape, dtype=float) -> np.ndarray:
    """np.zeros(shape) whose data start on a huge-page boundary when it is larger than
    one: numpy asks the kernel for transparent huge pages (madvise) on large arrays, but
    only the aligned 2 MB blocks inside get them.  An 8 MB matrix at a random 4 kB
    offset took ~500 extra first-touch page faults, which the threads of the
    assembly serialise on (N = 1024, V + K + W: 2300 faults per call; without huge
    pages 10000 and a 2-thread speed-up of 1.22 instead of 1.55)."""
    n, size = math.prod(shape), np.dtype(dtype).itemsize   # (np.prod: 2 us a call)
    if n * size < 2 * HUGE_PAGE:
        return np.zeros(shape, dtype)
    buf = np.zeros(n + HUGE_PAGE // size, dtype)
    off = (-buf.ctypes.data % HUGE_PAGE) // size
    return buf[off:off + n].reshape(shape)


MIN_ENTRIES_PER_THREAD = 1 << 18   # all_finite: below this many entries per thread, one


def _rows_finite(A: np.ndarray, lo: int, hi: int) -> bool:
    """Whether the rows lo <= r < hi of A are all finite (numpy releases the GIL): by
    their min and max (NaN propagates), which allocate nothing - np.isfinite's boolean
    temporary cost page faults that two threads could not share."""
    B = A[lo:hi]
    return bool(B.size == 0 or (np.isfinite(B.min()) and np.isfinite(B.max())))


def all_finite(A: np.ndarray) -> bool:
    """np.all(np.isfinite(A)) for a dense matrix (real or complex), in row blocks on the
    threads (as a serial step it was 3 % of V + K + W at N = 4096 on 2 threads)."""
    if np.iscomplexobj(A):
        return all_finite(A.real) and all_finite(A.imag)
    nt = n_threads(A.size, MIN_ENTRIES_PER_THREAD)
    n = A.shape[0]
    if nt <= 1:
        return _rows_finite(A, 0, n)
    cuts = np.linspace(0, n, nt + 1).round().astype(np.int64)
    return all(run_chunks(lambda k: _rows_finite(A, cuts[k], cuts[k + 1]), range(nt), nt))
