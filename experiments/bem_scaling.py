"""Dense against compressed hp-BEM: time, storage and error against N and tol (issue 27;
beyond the thesis).

The interior Dirichlet problem on the unit square (Laplace: u = log|x - x0|; Lame: Kelvin's
field of a point force outside) solved for its Neumann data, V psi_h = (K + M/2) g
(Section 1.4), by the dense operators and by the H-matrices of :mod:`hpfebe.bem.hmatrix`
(``compression="hmatrix"``, ACA+ far-field blocks to the tolerance tol); the scene and the
sweeps are :mod:`hpfebe.scenes.bem_scaling`.  Storage is that of V and K as held (the
dense arrays or the H-matrices' near blocks and low-rank factors); wall times are one
thread, after a warm-up.  The sizes here keep the job near a minute; the full study (N up
to 65536, peak memory per run in a subprocess) is ``python tools/bem_scaling.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from matplotlib.ticker import MaxNLocator

from hpfebe.analysis import fitted_rate
from hpfebe.scenes import bem_hertz as bh
from hpfebe.scenes import bem_scaling as bs
from hpfebe.suite import (ArtefactResult, Claim, from_config, joint_claim, new_figure,
                          progress, readable_log_ticks, select_scenes, style_axes, timed)

ARTEFACTS = ("figure_bem_scaling", "figure_bem_hertz")
#: independent computations: the scaling study; the Hertz contact showcase
SCENES = {"scaling": ("figure_bem_scaling",), "hertz": ("figure_bem_hertz",)}
CASES = (("laplace", 1), ("laplace", 4), ("lame", 1), ("lame", 2))
ERROR_MATCH = 0.01        # compressed error against the exact data = dense one's +- 1 %
FLOOR = 10.0              # dense errors below FLOOR x tol: the tolerance's floor shows


@dataclass(frozen=True)
class Params:
    sizes: tuple[int, ...] = (256, 512, 1024, 2048)   # N at p = 1 (N / p at degree p)
    dense_max_dof: int = 4096
    tol: float = 1e-8
    tols: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10)
    tol_n: int = 1024                                   # Laplace p = 1 tolerance sweep


@dataclass(frozen=True)
class HertzParams:
    sizes: tuple[int, ...] = (128, 256, 512)            # N of the half-disk, p = 1
    delta: float = 5e-3                                 # top displacement
    kappa: float = 1.0                                  # eps = kappa h / E*
    tol: float = 1e-6                                   # H-matrices and Newton
    dense_max_n: int = 256                              # dense check up to this N
    rate_min: float = 0.5                               # claimed: error rates >= this
    # the rates are fitted only where the contact zone is resolved, a / h >= this: at
    # N = 128 (a / h = 1.5) the errors of a and p0 are still pre-asymptotic (a: 0.29,
    # 0.22, 0.11 at N = 128, 256, 512: rate 0.35, then 1.02)
    resolved: float = 3.0


def _exponents(t: pd.DataFrame, key: str) -> dict:
    """(pde, p, method) -> fitted exponent of ``key`` against N (last three sizes)."""
    out = {}
    for (pde, p, m), g in t.groupby(["pde", "p", "method"], sort=False):
        if len(g) >= 2:
            out[(pde, int(p), m)] = fitted_rate(g.N, g[key], last=min(3, len(g)))
    return out


def _claims(scaling: pd.DataFrame, tols: pd.DataFrame, prm: Params) -> list[Claim]:
    both = scaling[scaling.method == "hmatrix"].merge(
        scaling[scaling.method == "dense"], on=["pde", "p", "N"], suffixes=("", "_d"))
    both = both.assign(dev=(both.error_exact / both.error_exact_d - 1).abs())
    low, high = both[both.p == 1], both[both.p == both.p.max()]
    match = Claim(f"At tol = {prm.tol:g} and p = 1 the compressed error against the exact "
                  f"data equals the dense one within {100 * ERROR_MATCH:g} %",
                  bool(len(low) and low.dev.max() <= ERROR_MATCH),
                  f"largest deviation {100 * low.dev.max():.3g} % over {len(low)} meshes",
                  kind="beyond")
    fine = high[high.error_exact_d < FLOOR * prm.tol]
    floor = Claim(f"The tolerance limits the error at high degree: where the dense error "
                  f"is below {FLOOR:g} tol (p = {int(both.p.max())}, tol = {prm.tol:g}), "
                  f"the compressed one exceeds it by more than {100 * ERROR_MATCH:g} %",
                  bool((fine.dev > ERROR_MATCH).all()) if len(fine) else None,
                  "; ".join(f"{r.pde} p={r.p} N={r.N}: {r.error_exact:.3e} against dense "
                            f"{r.error_exact_d:.3e} (difference to the dense psi_h "
                            f"{r.err_vs_dense:.2e})" for r in fine.itertuples())
                  or "no mesh of that degree has a dense error that small: not decidable",
                  kind="beyond")
    ex = _exponents(scaling, "storage_mb")
    hm = scaling[scaling.method == "hmatrix"]
    parts = [Claim("", bool(np.all(np.diff(g.ratio.to_numpy()) < 0)),
                   f"{pde} p={p}: ratio {g.ratio.iloc[0]:.3f} -> {g.ratio.iloc[-1]:.3f}, "
                   f"storage ~ N^{ex[(pde, p, 'hmatrix')]:.2f}")
             for (pde, p), g in hm.groupby(["pde", "p"], sort=False)]
    storage = joint_claim("The compression ratio (H-matrix / dense bytes of V and K) "
                          "falls as N grows, in every case (dense storage: N^2)", *parts)
    comp = tols[tols.method == "hmatrix"].sort_values("tol")
    mono = bool(np.all(np.diff(comp.err_vs_dense.to_numpy()) > 0))
    tol_claim = Claim("The difference to the dense solution falls with the tolerance",
                      mono, "err_vs_dense " + ", ".join(
                          f"{r.err_vs_dense:.2e} (tol {r.tol:g})" for r in comp.itertuples()),
                      kind="beyond")
    return [match, floor, replace(storage, kind="beyond"), tol_claim]


def _figure(scaling: pd.DataFrame, tols: pd.DataFrame):
    fig, axes = new_figure((13.0, 4.2), 1, 3, layout="constrained")
    tex, sex = _exponents(scaling, "wall_time_s"), _exponents(scaling, "storage_mb")
    for k, (pde, p) in enumerate(CASES):
        for m, fmt in (("dense", "--"), ("hmatrix", "-")):
            g = scaling[(scaling.pde == pde) & (scaling.p == p) & (scaling.method == m)]
            if len(g) < 2:
                continue
            lab = f"{pde} p={p} {m}"
            axes[0].loglog(g.dof, g.wall_time_s, fmt + "o", color=f"C{k}", ms=3,
                           label=f"{lab} (N^{tex[(pde, p, m)]:.2f})")
            axes[1].loglog(g.dof, g.storage_mb, fmt + "o", color=f"C{k}", ms=3,
                           label=f"{lab} (N^{sex[(pde, p, m)]:.2f})")
    comp = tols[tols.method == "hmatrix"].sort_values("tol")
    dense_err = tols[tols.method == "dense"].error_exact.iloc[0]
    axes[2].loglog(comp.tol, comp.err_vs_dense, "o-", label="against dense psi_h")
    axes[2].loglog(comp.tol, (comp.error_exact - dense_err).abs() / dense_err, "s-",
                   label="|error - dense error| / dense error (exact data)")
    axes[2].loglog(comp.tol, comp.tol, "k:", label="tol")
    for ax in axes[:2]:
        readable_log_ticks(ax.xaxis)
    style_axes(axes[0], "dof", "assembly + solve [s], one thread", "time",
               legend=dict(fontsize=6))
    style_axes(axes[1], "dof", "storage of V and K [MB]", "memory", legend=dict(fontsize=6))
    style_axes(axes[2], "tol", "relative difference",
               f"Laplace p=1, N={int(comp.N.iloc[0])}", legend=dict(fontsize=7))
    return fig


def _scaling(config: dict) -> list[ArtefactResult]:
    prm = from_config(Params, {k: v for k, v in (config or {}).items() if k != "hertz"},
                      scene="bem_scaling")
    jit_s = timed(lambda: [bs.solve(bs.ScalingRun(pde, 16, p, c)) for pde, p in CASES
                           for c in (None, "hmatrix")])[1]     # compile / load the cache
    rows = []
    for pde, p in progress(CASES, desc="cases"):
        rows += bs.scaling_rows(pde, p, [n // p for n in prm.sizes], prm.dense_max_dof,
                                prm.tol)
    scaling = pd.DataFrame(rows).assign(part="scaling")
    tols = pd.DataFrame(bs.tolerance_rows("laplace", 1, prm.tol_n, prm.tols)).assign(
        part="tol")
    table = pd.concat([scaling, tols], ignore_index=True)
    notes = ("Beyond the thesis (issue 27). " + __doc__.split("\n\n")[1].replace("\n", " ")
             + f" Sizes N = {list(prm.sizes)} at p = 1 (N / p at degree p), dense up to "
             f"{prm.dense_max_dof} dof; exponents fitted over the last three sizes.")
    return [ArtefactResult(name="figure_bem_scaling", table=table,
                           figure=_figure(scaling, tols), keys=("part", "pde", "p", "N",
                                                                "method", "tol"),
                           claims=_claims(scaling, tols, prm), notes=notes,
                           meta=dict(jit_s=round(jit_s, 3), max_dof=int(table.dof.max()),
                                     allow_nan_columns=["tol", "err_vs_dense"]))]


def _hertz(config: dict) -> list[ArtefactResult]:
    """Hertz contact of the half-disk (:mod:`hpfebe.scenes.bem_hertz`): a and p0 against
    Hertz's as N grows, the fitted rates in h, the compressed against the dense solve at
    small N and the pressure profile of the finest mesh against Hertz's ellipse."""
    prm = from_config(HertzParams, (config or {}).get("hertz"), scene="bem_scaling.hertz")
    small = bh.HertzRun(32, prm.delta, prm.kappa, prm.tol)
    jit_s = timed(lambda: [bh.solve(small, preconditioner=k)          # both paths of
                           for k in ("near_field", "multilevel")])[1]  # "auto"
    rows, last = [], None
    for n in progress(prm.sizes, desc="hertz N"):
        run = bh.HertzRun(n, prm.delta, prm.kappa, prm.tol)
        last = bh.solve(run)
        row = {k: v for k, v in last.items() if k not in ("U", "profile")}
        if n <= prm.dense_max_n:
            dense = bh.solve(run, compression=None)
            row["diff_dense"] = float(np.linalg.norm(last["U"] - dense["U"])
                                      / np.linalg.norm(dense["U"]))
        rows.append(row)
    t = pd.DataFrame(rows)
    t["a_over_h"] = t.a / t.h
    fit = t[t.a_over_h >= prm.resolved]
    ra, rp = ((fitted_rate(fit.h, fit[k], last=min(3, len(fit))) if len(fit) >= 2
               else float("nan")) for k in ("err_a", "err_p0"))
    fitted = (f"fitted over N = {list(fit.N)} (a / h >= {prm.resolved:g}, the last three)"
              if len(fit) >= 2 else f"not fitted: fewer than two N with a / h >= "
              f"{prm.resolved:g} (a / h = {', '.join(f'{v:.1f}' for v in t.a_over_h)})")
    checked = t.dropna(subset=["diff_dense"]) if "diff_dense" in t else t.iloc[:0]
    claims = [
        Claim("Every compressed Newton solve converged (backward errors of (U, psi) "
              f"<= tol = {prm.tol:g})", bool(t.converged.all()),
              f"largest backward error {t.backward_error.max():.2e}", kind="beyond"),
        Claim(f"At N <= {prm.dense_max_n} the compressed solution equals the dense "
              f"penalty solve to the tolerance {prm.tol:g}",
              bool(len(checked) and (checked.diff_dense <= prm.tol).all()) if len(checked)
              else None, "; ".join(f"N={int(r.N)}: {r.diff_dense:.2e}"
                                   for r in checked.itertuples()) or "no dense run",
              kind="beyond"),
        Claim(f"Where the contact zone is resolved (a / h >= {prm.resolved:g}) the errors "
              f"of a and p0 against Hertz fall with h at a rate >= {prm.rate_min:g}",
              bool(ra >= prm.rate_min and rp >= prm.rate_min) if len(fit) >= 2 else None,
              (f"rate of a {ra:.2f}, of p0 {rp:.2f}, " if len(fit) >= 2 else "") + fitted,
              kind="beyond")]
    fig, axes = new_figure((10.0, 4.0), 1, 2, layout="constrained")
    for key, mark, r in (("a", "o-", ra), ("p0", "s-", rp)):
        axes[0].loglog(t.N, t[f"err_{key}"], mark, label=f"{key} (rate in h {r:.2f})"
                       if np.isfinite(r) else key)
    axes[0].loglog(t.N, t.err_a.iloc[0] * t.N.iloc[0] / t.N, "k:", label="O(h)")
    readable_log_ticks(axes[0].xaxis)
    style_axes(axes[0], "N", "relative error against Hertz", "Hertz: a, p0",
               legend=dict(fontsize=7))
    x, p = last["profile"]
    o = np.argsort(x)
    aH, p0H = last["a_hertz"], last["p0_hertz"]
    xs = np.linspace(-aH, aH, 401)
    axes[1].plot(x[o], p[o], ".", ms=3, label=f"penalty BEM, N={int(last['N'])}")
    axes[1].plot(xs, p0H * np.sqrt(np.clip(1 - (xs / aH) ** 2, 0, None)), "k-",
                 label="Hertz")
    axes[1].set_xlim(-2 * aH, 2 * aH)
    axes[1].xaxis.set_major_locator(MaxNLocator(5))     # readable tick labels
    style_axes(axes[1], "x", "contact pressure", "pressure profile",
               legend=dict(fontsize=7))
    notes = ("Beyond the thesis (issue 27's showcase). " + bh.__doc__.split("\n\n")[1]
             .replace("\n", " ") + f" delta = {prm.delta:g}, kappa = {prm.kappa:g}, "
             f"tol = {prm.tol:g}, N = {list(prm.sizes)}; rates {fitted}. Larger N: python "
             "tools/bem_hertz.py N (README, Compressed BEM: the N = 16384 showcase, run "
             "apart from the workflow).")
    t = t.drop(columns=["reason"])
    return [ArtefactResult(name="figure_bem_hertz", table=t, figure=fig, keys=("N",),
                           claims=claims, notes=notes,
                           meta=dict(jit_s=round(jit_s, 3),
                                     allow_nan_columns=["diff_dense", "backward_error"]))]


SCENE_RUNS = {"scaling": _scaling, "hertz": _hertz}


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """The artefacts of the scenes asked for (None: all)."""
    names = select_scenes(SCENES, scenes, "bem_scaling")
    return [r for name in names for r in SCENE_RUNS[name](config)]
