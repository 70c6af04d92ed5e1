"""One Hertz contact run of :mod:`hpfebe.scenes.bem_hertz` at large N (issue 27's
showcase), outside the workflow: CPU seconds, peak RSS, Newton / GMRES iterations, the
backward error and a, p0 against Hertz.

    python tools/bem_hertz.py 4096 [16384 ...]
"""

from __future__ import annotations

import resource
import sys
import time

from hpfebe.scenes import bem_hertz as bh


def main(argv: list[str]) -> None:
    for arg in argv or ["4096"]:
        run = bh.HertzRun(int(arg))
        t0 = time.process_time()
        r = bh.solve(run)
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"N={r['N']} cpu={time.process_time() - t0:.1f}s peak_rss={rss:.0f}MB "
              f"newton={r['newton']} gmres={r['gmres_iterations']} "
              f"converged={r['converged']} backward_error={r['backward_error']:.1e} "
              f"a={r['a']:.6f} (Hertz {r['a_hertz']:.6f}, err {r['err_a']:.3e}) "
              f"p0={r['p0']:.2f} (Hertz {r['p0_hertz']:.2f}, err {r['err_p0']:.3e}) "
              f"F={r['F']:.4f}", flush=True)
        print("  gmres per Newton step:", r["gmres_per_step"], flush=True)
        print("  cpu split: " + ", ".join(f"{k}={v:.1f}" for k, v in r["times"].items()),
              flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
