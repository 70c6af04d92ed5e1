"""Issue 14 peer table: V + K + W assembly (p = 1, unit square, one thread) of hpfebe
against HILBERT's C++ port, minimum of interleaved runs, plus an agreement check.

    bash benchmarks/peers/build_hilbert.sh          # once (see README.md)
    NUMBA_NUM_THREADS=1 python benchmarks/peers/run_peers.py --driver /tmp/peers/build/hilbert_driver

Kernel conventions: HILBERT's V and W use G = -1/(2 pi) log|x - y| (length scale R = 1);
hpfebe's default R is the diameter, so the check assembles hpfebe with scale=1.0
(V changes by log(R)/(2 pi) h h^T otherwise; W and K do not depend on R).  HILBERT's
K is the double layer with the opposite sign convention of the normal derivative, so the
check would compare K_hpfebe with -K_hilbert if that agreed (the sign is printed; it is +:
both use d/dn_y G with the outward normal).  HILBERT with eta = 0 evaluates every pair by
its analytic formulas, which lose digits to cancellation on far pairs (K at N = 256:
2e-12 relative off an mpmath reference that hpfebe matches to 1e-16); with eta > 0 far
pairs are integrated by Gauss quadrature and the matrices agree to ~1e-14.  At p = 1 the
spaces coincide: V on the N elements (P0), K elements x vertices, W vertices x vertices,
and hpfebe's P1 dof k is mesh node k.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import time
from pathlib import Path

import numba
import numpy as np

from hpfebe import BoundaryMesh
from hpfebe.bem import LaplaceBEM

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def write_mesh(mesh: BoundaryMesh, prefix: Path) -> None:
    np.savetxt(f"{prefix}_coordinates.dat", mesh.nodes, fmt="%.17g")
    np.savetxt(f"{prefix}_elements.dat", mesh.elements + 1, fmt="%d")


def hilbert(driver: str, prefix: Path, eta: float, repeat: int, dump: bool = False) -> float:
    args = [driver, str(prefix), repr(eta), str(repeat)] + (["dump"] if dump else [])
    out = subprocess.run(args, check=True, capture_output=True, text=True)
    return float(out.stdout.split()[-1]) / 1e3


def vkw(mesh: BoundaryMesh, scale=None):
    op = LaplaceBEM(mesh, scale=scale)
    return op.V, op.K, op.W


def ours(mesh: BoundaryMesh, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        vkw(mesh)
        best = min(best, time.perf_counter() - t)
    return best


def agreement(driver: str, prefix: Path, mesh: BoundaryMesh, eta: float) -> dict:
    hilbert(driver, prefix, eta, 1, dump=True)
    n, nv = mesh.n_elements, len(mesh.nodes)
    H = {k: np.fromfile(f"{prefix}_{k}.bin").reshape(shape, order="F")
         for k, shape in (("V", (n, n)), ("K", (n, nv)), ("W", (nv, nv)))}
    mine = dict(zip("VKW", vkw(mesh, scale=1.0)))
    err = {}
    for k in "VKW":
        A = np.asarray(mine[k].toarray() if hasattr(mine[k], "toarray") else mine[k])
        scale = np.abs(H[k]).max()
        e_plus = np.abs(A - H[k]).max() / scale
        e_minus = np.abs(A + H[k]).max() / scale
        err[k] = (e_plus, "+") if e_plus <= e_minus else (e_minus, "-")
    return err


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--driver", default="/tmp/peers/build/hilbert_driver")
    ap.add_argument("--work", default="/tmp/peers/meshes")
    ap.add_argument("--sizes", default="16,64,256,1024,4096")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds (min taken)")
    ap.add_argument("--eta-default", type=float, default=0.5,
                    help="HILBERT's admissibility parameter of its examples")
    args = ap.parse_args(argv)
    if numba.get_num_threads() != 1:
        print(f"warning: numba uses {numba.get_num_threads()} threads "
              "(set NUMBA_NUM_THREADS=1 for the single-thread table)")
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    sizes = [int(s) for s in args.sizes.split(",")]
    meshes = {N: BoundaryMesh.polygon(SQUARE, n=N // 4, p=1) for N in sizes}
    prefixes = {N: work / f"square{N}" for N in sizes}
    for N in sizes:
        write_mesh(meshes[N], prefixes[N])
    vkw(meshes[sizes[0]])                      # compile / load the cache first
    print("agreement at p = 1 (max |diff| / max |entry|, sign of HILBERT's matrix used):")
    for N in [N for N in sizes if N <= 1024]:
        for eta in (args.eta_default, 0.0):
            err = agreement(args.driver, prefixes[N], meshes[N], eta)
            print(f"  N = {N}, eta = {eta:g}: "
                  + ", ".join(f"{k} {e:.1e} ({s})" for k, (e, s) in err.items()))
    best = {N: dict(h0=np.inf, hd=np.inf, us=np.inf) for N in sizes}
    for _ in range(args.rounds):
        for N in sizes:
            rep = max(1, 2048 // N)
            b = best[N]
            b["h0"] = min(b["h0"], hilbert(args.driver, prefixes[N], 0.0, rep))
            b["us"] = min(b["us"], ours(meshes[N], rep))
            b["hd"] = min(b["hd"], hilbert(args.driver, prefixes[N], args.eta_default, rep))
    print(f"\nload: {os.getloadavg()[0]:.2f} (1-min average at the end)")
    print(f"\n| N (p = 1) | HILBERT, eta = 0 | HILBERT, eta = {args.eta_default:g} | hpfebe "
          "| hpfebe / fastest |\n|---|---|---|---|---|")
    for N in sizes:
        b = best[N]
        fastest = min(b["h0"], b["hd"])
        print(f"| {N} | {1e3 * b['h0']:.3g} | {1e3 * b['hd']:.3g} | {1e3 * b['us']:.3g} "
              f"| {b['us'] / fastest:.2f} |")


if __name__ == "__main__":
    main()
