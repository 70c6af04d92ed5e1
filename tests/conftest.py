"""Test-suite set-up: one thread for the BLAS and OpenMP pools, as in the Snakemake jobs.
On a shared 2-core machine OpenBLAS's default pool made a 128 x 128 Cholesky
factorisation 1000x slower under load (76 ms against 0.07 ms).  numpy is already loaded
when pytest reads this file (its warning filters import numba), so the pools of this
process are limited through threadpoolctl and the environment carries the setting to
the `python -m hpfebe run` subprocesses of the tests.  numba's pool is left alone (the
BEM assembly benchmarks set it themselves); a value the user set wins."""

import os

from threadpoolctl import threadpool_limits

_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
if not any(v in os.environ for v in _VARS):
    for _var in _VARS:
        os.environ[_var] = "1"
    threadpool_limits(limits=1, user_api="blas")

# The experiments package lives in the repository root, not in the installed package:
# tests that import it find it as `hpfebe run` does (cli.find_root), in any order.
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

_ROOT = str(Path(__file__).resolve().parents[2])
if _ROOT not in sys.path:
    sys.path.insert(0, _ROOT)
