#!/usr/bin/env python
"""Issue 27's targets, measured by one command: dense against compressed hp-BEM.

    python tools/bem_scaling.py [--quick] [--parts check,matvec,tol,scaling]
                                [--cases laplace:1,laplace:4,lame:1,lame:2]
                                [--methods dense,hmatrix] [--n-range lo:hi]
                                [--preconditioner multilevel|jacobi]
                                [--csv /tmp/bem_scaling.csv] [--max-dense-gb 2.5]

Every measurement runs in a fresh subprocess (``--one``), one thread
(NUMBA/OMP/OPENBLAS/MKL_NUM_THREADS=1), after a warm-up solve on a 16-element mesh (numba
compiles or loads its cache there, not in the timing); its memory is the subprocess's
peak resident set (VmHWM) minus its resident set before the run (the interpreter,
numba and the warm-up), and the storage of V and K as held (dense arrays or H-matrices).
Beside the wall time (``total_s``) the subprocess's CPU time (``cpu_s``): on a loaded
machine the wall time measures the load, the CPU time (one thread) much less so.
The problem is :mod:`hpfebe.scenes.bem_scaling` (interior Dirichlet problem on the unit
square, exact Neumann data / traction known).

Parts:

* ``scaling``: time (assembly of V and B plus the solve for Psi) and memory against N,
  dense and compressed (tol 1e-8), Laplace p = 1 and 4, Lame p = 1 and 2; the fitted
  exponents over the target ranges (p = 1: N = 4096 ... 65536, p >= 2: 1024 ... 16384),
  the compression ratio, the CG iterations on V (``cg_iterations``, summed over the
  solves) and CG's Lanczos estimate of cond(C^{-1} V) (``cond_estimate``), the error
  against the exact data and, where dense ran, against the dense solution; the dense
  error extrapolated to the largest N (fit over its last three sizes) against the
  compressed error there.
* ``tol``: error against dense and against the exact data as the tolerance varies.
* ``matvec``: compressed V, K, W times a random vector against dense (relative 2-norm),
  Laplace and Lame, p = 1, 2, 4, at N = 4096, or the largest N whose dense matrix fits
  ``--max-dense-gb`` (the N used is printed).
* ``check``: the independent check of the compressed Laplace V at large N
  (:func:`hpfebe.scenes.bem_scaling.far_field_rows`: near pairs by the dense path's local
  blocks, all others by tensor Gauss; no H-matrix, no dense matrix).

Prints one table per part (and ``uptime`` beside the timings) and writes all rows to one
CSV (column ``part``).  ``--quick`` runs small sizes only (a smoke test, minutes).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

THREADS = {k: "1" for k in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                            "MKL_NUM_THREADS")}
os.environ.update(THREADS)          # before numpy's BLAS starts its threads (--one)

CASES = (("laplace", 1), ("laplace", 4), ("lame", 1), ("lame", 2))
FULL = {   # (pde, p) -> (dense N, compressed N)
    ("laplace", 1): ((512, 1024, 2048, 4096, 8192),
                     (1024, 2048, 4096, 8192, 16384, 32768, 65536)),
    ("laplace", 4): ((256, 512, 1024, 2048), (256, 512, 1024, 2048, 4096, 8192, 16384)),
    ("lame", 1): ((256, 512, 1024, 2048, 4096), (1024, 2048, 4096, 8192, 16384, 32768)),
    ("lame", 2): ((256, 512, 1024, 2048), (256, 512, 1024, 2048, 4096, 8192, 16384)),
}
QUICK = {case: ((64, 128, 256), (64, 128, 256, 512)) for case in CASES}
FIT_RANGE = {1: (4096, 65536), 2: (1024, 16384), 4: (1024, 16384)}
TOLS = (1e-4, 1e-6, 1e-8, 1e-10)
TOL_CASES = {("laplace", 1): 4096, ("lame", 1): 2048}
MATVEC_N = 4096


# --------------------------------------------------------------------- subprocess side
def _status(key: str) -> int:
    """kB of a /proc/self/status line (VmRSS, VmHWM)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1])
    raise KeyError(key)


def _warm_up(pde: str, p: int, compression) -> None:
    from hpfebe.scenes import bem_scaling as bs
    bs.solve(bs.ScalingRun(pde, 16, p, compression))
    if pde == "lame" or compression:      # W's kernels too (matvec part)
        op = bs.operators(bs.ScalingRun(pde, 16, p, compression))
        op.W


def one_solve(spec: dict) -> dict:
    """One ScalingRun: its measurements (and psi saved to spec["psi_file"])."""
    from hpfebe.scenes import bem_scaling as bs
    run = bs.ScalingRun(spec["pde"], spec["N"], spec["p"], spec["compression"], spec["tol"])
    if spec.get("preconditioner"):          # HMatrixSettings.preconditioner of the CG on V
        from dataclasses import replace
        make = bs.operators

        def operators(r, _make=make):
            op = _make(r)
            if op.hm is not None:
                op.hm.settings = replace(op.hm.settings,
                                         preconditioner=spec["preconditioner"])
            return op
        bs.operators = operators
    _warm_up(run.pde, run.p, run.compression)
    rss0 = _status("VmRSS")
    t0, c0 = time.perf_counter(), time.process_time()
    res = bs.solve(run)
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    peak = _status("VmHWM")
    np.save(spec["psi_file"], res.psi)
    out = dict(dof=res.dof, assembly_s=res.assembly_s, solve_s=res.solve_s,
               total_s=total, cpu_s=cpu, storage_mb=res.storage_bytes / 2**20,
               dense_mb=res.dense_bytes / 2**20, ratio=res.ratio, error_exact=res.error,
               peak_mb=peak / 1024, run_mb=(peak - rss0) / 1024)
    if res.info is not None:
        out["max_rank"] = max(res.info[k]["max_rank"] for k in ("V", "K"))
        out["sampled_error"] = max(res.info[k]["sampled_error"] for k in ("V", "K"))
        out["cg_iterations"] = int(sum(it for it, _ in res.info["solves"]))
        out["cond_estimate"] = float(np.nanmax(res.info["cond_estimates"] or [np.nan]))
    return out


def one_matvec(spec: dict) -> dict:
    """Compressed V, K, W against dense at one (pde, N, p): relative 2-norm errors."""
    from hpfebe.scenes import bem_scaling as bs
    _warm_up(spec["pde"], spec["p"], "hmatrix")
    dense = bs.operators(bs.ScalingRun(spec["pde"], spec["N"], spec["p"]))
    comp = bs.operators(bs.ScalingRun(spec["pde"], spec["N"], spec["p"], "hmatrix",
                                      spec["tol"]))
    rng = np.random.default_rng(0)
    out = {}
    for name in ("V", "K", "W"):
        A = getattr(dense, name)
        x = rng.standard_normal(A.shape[1])
        y = A @ x
        dense._cache.clear()                 # one dense matrix at a time
        del A
        out[f"err_{name}"] = bs.relative_difference(getattr(comp, name) @ x, y)
    return out


def one_check(spec: dict) -> dict:
    """Compressed Laplace V x against far_field_rows on ``n_rows`` spread elements."""
    from hpfebe.scenes import bem_scaling as bs
    _warm_up("laplace", spec["p"], "hmatrix")
    comp = bs.operators(bs.ScalingRun("laplace", spec["N"], spec["p"], "hmatrix",
                                      spec["tol"]))
    x = np.random.default_rng(1).standard_normal(comp.W_space.ndof)
    t0 = time.perf_counter()
    y = comp.V @ x
    t1 = time.perf_counter()
    els = np.linspace(0, spec["N"] - 1, spec["n_rows"]).round().astype(int)
    ref = bs.far_field_rows(comp, x, els)
    got = y[comp.W_space.elem_dofs[els, :spec["p"]]]
    return dict(build_and_matvec_s=t1 - t0, check_s=time.perf_counter() - t1,
                rows=int(ref.size), err_rows=bs.relative_difference(got, ref),
                max_abs_rel=float(np.abs(got - ref).max() / np.abs(ref).max()))


# --------------------------------------------------------------------- parent side
def _spawn(kind: str, spec: dict, timeout: float) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--one", kind, json.dumps(spec)]
    env = dict(os.environ, **THREADS)
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return dict(failed=f"timeout {timeout:.0f} s")
    if r.returncode != 0:
        return dict(failed=(r.stderr.strip().splitlines() or ["?"])[-1][:200])
    return json.loads(r.stdout.strip().splitlines()[-1])


def _uptime() -> str:
    """The 1, 5, 15 minute load averages (beside every timing: a shared machine)."""
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def _fit(rows, key, lo, hi):
    from hpfebe.analysis import fitted_rate
    sel = [r for r in rows if lo <= r["N"] <= hi and np.isfinite(r.get(key, np.nan))]
    if len(sel) < 2:
        return float("nan"), 0
    return fitted_rate([r["N"] for r in sel], [r[key] for r in sel]), len(sel)


def part_scaling(sizes, tmp: Path, timeout: float, cases=CASES, methods=("dense", "hmatrix"),
                 n_range=(0, 10**9), preconditioner=None) -> tuple[list, list]:
    rows, fits = [], []
    for pde, p in cases:
        dense_n, comp_n = sizes[(pde, p)]
        psis = {}
        for method, ns in (("dense", dense_n), ("hmatrix", comp_n)):
            if method not in methods:
                continue
            for N in (n for n in ns if n_range[0] <= n <= n_range[1]):
                f = tmp / f"{pde}_{p}_{N}_{method}.npy"
                spec = dict(pde=pde, p=p, N=N, tol=1e-8, psi_file=str(f),
                            compression=None if method == "dense" else "hmatrix",
                            preconditioner=preconditioner)
                r = dict(part="scaling", pde=pde, p=p, N=N, method=method, tol=1e-8,
                         load=_uptime(), **_spawn("solve", spec, timeout))
                if "failed" not in r:
                    psis[(method, N)] = f
                    if method == "hmatrix" and ("dense", N) in psis:
                        r["err_vs_dense"] = _rel(f, psis[("dense", N)])
                rows.append(r)
                _print_row(r)
        ok = [r for r in rows if r["pde"] == pde and r["p"] == p and "failed" not in r]
        fits += _case_fits(pde, p, ok)
    return rows, fits


def _case_fits(pde, p, ok) -> list:
    """Exponents of time and memory, and the extrapolated dense error at the largest N."""
    from hpfebe.analysis import fitted_rate
    lo, hi = FIT_RANGE[p]
    out = []
    for method in ("dense", "hmatrix"):
        sub = [r for r in ok if r["method"] == method]
        if not sub:                     # not run (--methods)
            continue
        rng = (lo, hi) if method == "hmatrix" else (0, 10**9)
        keys = ("total_s", "cpu_s", "run_mb", "storage_mb")
        for key in keys + (("cg_iterations",) if method == "hmatrix" else ()):
            e, n = _fit(sub, key, *rng)
            out.append(dict(part="fit", pde=pde, p=p, method=method, quantity=key,
                            exponent=e, points=n, N_lo=rng[0], N_hi=min(rng[1], 10**6)))
    dense = sorted((r for r in ok if r["method"] == "dense"), key=lambda r: r["N"])[-3:]
    comp = sorted((r for r in ok if r["method"] == "hmatrix"), key=lambda r: r["N"])
    if len(dense) >= 2 and comp:
        N = [r["N"] for r in dense]
        rate = fitted_rate(N, [r["error_exact"] for r in dense])
        big = comp[-1]
        extrap = dense[-1]["error_exact"] * (big["N"] / N[-1]) ** rate
        out.append(dict(part="fit", pde=pde, p=p, method="hmatrix",
                        quantity="error_vs_extrapolated_dense", N_hi=big["N"],
                        exponent=rate, value=big["error_exact"] / extrap - 1.0))
    return out


def _rel(a: Path, b: Path) -> float:
    x, y = np.load(a), np.load(b)
    return float(np.linalg.norm(x - y) / np.linalg.norm(y))


def part_tol(cases, tmp: Path, timeout: float) -> list:
    rows = []
    for (pde, p), N in cases.items():
        ref = tmp / f"tol_{pde}_{p}_{N}_dense.npy"
        d = _spawn("solve", dict(pde=pde, p=p, N=N, tol=1e-8, compression=None,
                                 psi_file=str(ref)), timeout)
        rows.append(dict(part="tol", pde=pde, p=p, N=N, method="dense", load=_uptime(), **d))
        _print_row(rows[-1])
        for tol in TOLS:
            f = tmp / f"tol_{pde}_{p}_{N}_{tol:g}.npy"
            r = dict(part="tol", pde=pde, p=p, N=N, method="hmatrix", tol=tol,
                     load=_uptime(), **_spawn("solve", dict(pde=pde, p=p, N=N, tol=tol,
                                                            compression="hmatrix",
                                                            psi_file=str(f)), timeout))
            if "failed" not in r and "failed" not in d:
                r["err_vs_dense"] = _rel(f, ref)
            rows.append(r)
            _print_row(r)
    return rows


def part_matvec(max_dense_gb: float, n_target: int, timeout: float) -> list:
    rows = []
    for pde in ("laplace", "lame"):
        for p in (1, 2, 4):
            d = 1 if pde == "laplace" else 2
            N = n_target
            while (d * p * N) ** 2 * 8 / 2**30 > max_dense_gb and N > 64:
                N //= 2                       # the dense W_hp x W_hp matrix must fit
            r = dict(part="matvec", pde=pde, p=p, N=N, method="hmatrix", tol=1e-8,
                     load=_uptime(), **_spawn("matvec", dict(pde=pde, p=p, N=N, tol=1e-8),
                                              timeout))
            rows.append(r)
            _print_row(r)
    return rows


def part_check(Ns, timeout: float) -> list:
    rows = []
    for N in Ns:
        r = dict(part="check", pde="laplace", p=1, N=N, method="hmatrix", tol=1e-8,
                 load=_uptime(), **_spawn("check", dict(p=1, N=N, tol=1e-8, n_rows=16),
                                          timeout))
        rows.append(r)
        _print_row(r)
    return rows


SHOW = ("part", "pde", "p", "N", "method", "tol", "dof", "total_s", "cpu_s", "run_mb", "storage_mb",
        "ratio", "cg_iterations", "cond_estimate", "error_exact", "err_vs_dense", "err_V",
        "err_K", "err_W", "err_rows",
        "quantity", "exponent", "value", "failed", "load")


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


ROWS: list = []              # every row so far, rewritten to CSV_PATH after each one
CSV_PATH = ["/tmp/bem_scaling.csv"]


def _print_row(r: dict) -> None:
    """Print a row and rewrite the CSV with it (a long run leaves its rows so far)."""
    import pandas as pd
    print("  ".join(f"{k}={_fmt(r[k])}" for k in SHOW if k in r), flush=True)
    ROWS.append(r)
    pd.DataFrame(ROWS).to_csv(CSV_PATH[0], index=False)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--parts", default="check,matvec,tol,scaling")
    ap.add_argument("--csv", default="/tmp/bem_scaling.csv")
    ap.add_argument("--max-dense-gb", type=float, default=2.5)
    ap.add_argument("--cases", default=",".join(f"{c}:{p}" for c, p in CASES),
                    help="scaling part: pde:p pairs, e.g. laplace:1,lame:2")
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--methods", default="dense,hmatrix",
                    help="scaling part: dense, hmatrix or both")
    ap.add_argument("--n-range", default="0:1000000000",
                    help="scaling part: only the sizes N in lo:hi")
    ap.add_argument("--preconditioner", default=None, choices=("multilevel", "jacobi"),
                    help="of the CG on the compressed V (default: HMatrixSettings')")
    ap.add_argument("--one", nargs=2, metavar=("KIND", "SPEC"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.one:
        fn = {"solve": one_solve, "matvec": one_matvec, "check": one_check}[a.one[0]]
        print(json.dumps(fn(json.loads(a.one[1]))))
        return 0
    parts = a.parts.split(",")
    CSV_PATH[0] = a.csv
    with tempfile.TemporaryDirectory(prefix="bem_scaling_") as tmp:
        tmp = Path(tmp)
        print(f"load average {_uptime()} (2-core machine; timings beside it)", flush=True)
        if "check" in parts:
            part_check((1024,) if a.quick else (16384, 65536), a.timeout)
        if "matvec" in parts:
            part_matvec(a.max_dense_gb, 256 if a.quick else MATVEC_N, a.timeout)
        if "tol" in parts:
            part_tol({("laplace", 1): 256, ("lame", 1): 128} if a.quick else TOL_CASES,
                     tmp, a.timeout)
        if "scaling" in parts:
            cases = [(c, int(p)) for c, p in (x.split(":") for x in a.cases.split(","))]
            lo, hi = (int(v) for v in a.n_range.split(":"))
            _, fits = part_scaling(QUICK if a.quick else FULL, tmp, a.timeout, cases,
                                   a.methods.split(","), (lo, hi), a.preconditioner)
            print("\nfitted exponents (least squares in log-log):")
            for f in fits:
                _print_row(f)
    print(f"\nwrote {a.csv} ({len(ROWS)} rows); load average now {_uptime()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
