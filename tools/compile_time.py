"""Cold-cache numba compile times of the BEM kernels, per function and specialisation.

Runs the scene in a fresh Python process with an empty, temporary NUMBA_CACHE_DIR and
records numba's "numba:compile" events (numba.core.event): one line per compiled
(function, signature), its own time (nested compiles subtracted), split into LLVM
(numba's "numba:llvm_lock" events: optimisation and machine code of the function's
library, which holds a copy of every jitted callee it calls) and the rest (numba's Python
front end: bytecode analysis, type inference, lowering to LLVM IR), and the wall and CPU
time of each step of the scene.  A second process with the same (now warm) cache gives
the warm-start times.  Run-to-run noise on a shared machine is +-10 % or more: compare
CPU totals of interleaved runs.

    python tools/compile_time.py            # first LaplaceBEM(mesh).V, LameBEM(...).S_hat
                                            # (p = 1), then a p = 2 LameBEM(...).S_hat
    python tools/compile_time.py --no-quadrature   # the p = 1 steps only
    python tools/compile_time.py --top 40   # more lines
    python tools/compile_time.py --threads 2
    python tools/compile_time.py --sigs     # signatures of functions compiled twice or more

Issue 14 targets: cold (empty cache) under 10 s, warm first call under 0.5 s, for the
p = 1 steps (the closed forms of hpfebe.bem.lowest_order); the third step reports the
general quadrature path's cold start separately (per-function lines: their step).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap

SCENE = textwrap.dedent("""
    import json, sys, time
    t0, c0 = time.perf_counter(), time.process_time()
    import numba.core.event as ev
    records = []
    stack = []      # per open compile: [start, nested compile time, own LLVM time]
    llvm = []

    class L(ev.Listener):
        def on_start(self, event):
            stack.append([time.perf_counter(), 0.0, 0.0])
        def on_end(self, event):
            t_start, child, own_llvm = stack.pop()
            total = time.perf_counter() - t_start
            if stack:
                stack[-1][1] += total
            d = event.data["dispatcher"]
            f = getattr(d, "py_func", None)
            records.append(dict(name=(f.__module__ + "." + f.__qualname__) if f else str(d),
                                sig=str(event.data["args"]), self_s=total - child,
                                llvm_s=own_llvm, total_s=total))

    class LL(ev.Listener):
        def on_start(self, event):
            llvm.append(time.perf_counter())
        def on_end(self, event):
            t = time.perf_counter() - llvm.pop()
            if stack:
                stack[-1][2] += t

    ev.register("numba:compile", L())
    ev.register("numba:llvm_lock", LL())
    from hpfebe import BoundaryMesh
    from hpfebe.bem import LameBEM, LaplaceBEM
    steps = {"import": time.perf_counter() - t0}
    cpu = {"import": time.process_time() - c0}
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=1)
    scene = [("LaplaceBEM.V", lambda: LaplaceBEM(mesh).V),
             ("LameBEM.S_hat", lambda: LameBEM(mesh, 1.0, 0.3).S_hat)]
    if QUADRATURE:
        mesh2 = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=2)
        scene.append(("LameBEM.S_hat p=2", lambda: LameBEM(mesh2, 1.0, 0.3).S_hat))
    for name, f in scene:
        t, c = time.perf_counter(), time.process_time()
        n0 = len(records)
        f()
        steps[name], cpu[name] = time.perf_counter() - t, time.process_time() - c
        for r in records[n0:]:
            r["step"] = name
    print(json.dumps(dict(steps=steps, cpu=cpu, records=records)))
""")


def run(cache_dir: str, threads: int, quadrature: bool = True) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, NUMBA_NUM_THREADS=str(threads))
    scene = f"QUADRATURE = {bool(quadrature)}\n" + SCENE
    out = subprocess.run([sys.executable, "-c", scene], env=env, capture_output=True,
                         check=False,
                         text=True)
    if out.returncode != 0:
        sys.exit(f"the scene failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=25, help="lines of the per-function table")
    ap.add_argument("--threads", type=int, default=1, help="NUMBA_NUM_THREADS")
    ap.add_argument("--sigs", action="store_true",
                    help="list the signatures of the functions compiled more than once "
                         "(a Literal[int] argument, a non-contiguous array ...)")
    ap.add_argument("--no-quadrature", action="store_true",
                    help="leave out the third step (a p = 2 LameBEM.S_hat: the general "
                         "quadrature path's cold start)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="numba_cache_") as cache:
        cold = run(cache, args.threads, not args.no_quadrature)
        warm = run(cache, args.threads, not args.no_quadrature)
    p1 = ("import", "LaplaceBEM.V", "LameBEM.S_hat")
    for label, res in (("cold (empty cache)", cold), ("warm (cached)", warm)):
        s, c = res["steps"], res["cpu"]
        print(f"{label}: " + ", ".join(f"{k} {v:.2f} s" for k, v in s.items())
              + f"; total p = 1 (import, LaplaceBEM.V, LameBEM.S_hat) "
              f"{sum(s[k] for k in p1):.2f} s (CPU {sum(c[k] for k in p1):.2f} s)"
              + (f", with p = 2 {sum(s.values()):.2f} s (CPU {sum(c.values()):.2f} s)"
                 if len(s) > len(p1) else ""))
    recs = sorted(cold["records"], key=lambda r: -r["self_s"])
    per_fn: dict[str, list] = {}
    for r in recs:
        per_fn.setdefault(r["name"], []).append(r)
    tot, tot_llvm = sum(r["self_s"] for r in recs), sum(r["llvm_s"] for r in recs)
    print(f"\n{len(recs)} compilations of {len(per_fn)} functions, {tot:.2f} s in all "
          f"(self time; LLVM {tot_llvm:.2f} s, front end {tot - tot_llvm:.2f} s)")
    by_step: dict[str, float] = {}
    for r in recs:
        by_step[r.get("step", "import")] = by_step.get(r.get("step", "import"), 0.0) + r["self_s"]
    print("compile self time per step: "
          + ", ".join(f"{k} {v:.2f} s" for k, v in by_step.items()))
    print(f"{'self s':>7} {'LLVM s':>7} {'front s':>7} {'#sig':>4}  {'step':<18} function")
    rows = sorted(per_fn.items(), key=lambda kv: -sum(r["self_s"] for r in kv[1]))
    for name, rs in rows[:args.top]:
        s_, l_ = sum(r["self_s"] for r in rs), sum(r["llvm_s"] for r in rs)
        step = rs[0].get("step", "import")
        print(f"{s_:7.2f} {l_:7.2f} {s_ - l_:7.2f} {len(rs):4d}  {step:<18} {name}")
    if args.sigs:
        for name, rs in rows:
            if len(rs) > 1 and name.startswith("hpfebe"):
                print(f"\n{name}:")
                for r in rs:
                    print(f"  {r['self_s']:6.2f} s  {r['sig']}")
    if warm["records"]:
        print(f"\nwarm run still compiled {len(warm['records'])} specialisations: "
              + ", ".join(sorted({r['name'].rsplit('.', 1)[-1] for r in warm['records']})))


if __name__ == "__main__":
    main()
