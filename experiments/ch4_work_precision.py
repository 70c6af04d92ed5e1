"""Beyond the thesis (issue 28): work-precision of Section 4.4's stamp contact force.

The normal contact force of the stamp on the work piece (Section 4.4, thesis lines
20355-20720) for the mortar treatment (FE/FE, DtN Algorithm 4.3, Table 4.2's set-up)
and the penalty treatment (FE/BE, Newton, Table 4.3's set-up) on meshes h = 1/k, each
against its own reference (Aitken extrapolation of its three finest meshes), against
the wall time of one solve.  Scene, reference, timings and fits:
:mod:`hpfebe.scenes.ch4_work_precision`.  Claims on the error only (rate in h, the
reference's change against the coarser extrapolation); the times are reported, no claim
is made on them.
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
from matplotlib.ticker import NullLocator

from hpfebe.scenes import ch4_work_precision as wp
from hpfebe.suite import ArtefactResult, Claim, from_config, new_figure, style_axes

ARTEFACTS = ("figure_ch4_work_precision",)
COLUMNS = ["treatment", "k", "h", "dof", "force", "reference", "error", "rel_error",
           "iterations", "converged", "wall_s", "wall_max_s", "cpu_s", "repeats"]


def _figure(t: pd.DataFrame, refs: dict, repeats: int, max_k: int):
    fig, axs = new_figure((10.0, 4.3), 1, 2, layout="constrained")
    for tr, mk in zip(wp.TREATMENTS, ("o-", "s--")):
        d, r = t[t.treatment == tr], refs[tr]
        axs[0].loglog(d.wall_s, d.rel_error, mk, ms=4,
                      label=f"{tr}: slope {r['slope_time']:.2f}")
        axs[1].loglog(d.h, d.rel_error, mk, ms=4, label=f"{tr}: rate {r['slope_h']:.2f}")
        for x, y, k in zip(d.wall_s, d.rel_error, d.k):
            axs[0].annotate(f"k={k}", (x, y), xytext=(3, 3), textcoords="offset points",
                            fontsize=6)
    ks = sorted(set(t.k))
    axs[1].xaxis.set_minor_locator(NullLocator())
    axs[1].set_xticks([1.0 / k for k in ks], [f"1/{k}" for k in ks])
    style_axes(axs[0], f"wall time of one solve [s] (min of {repeats} for k <= {max_k})",
               "relative error of the contact force", "error vs time", title_size=9,
               legend=dict(fontsize=7))
    style_axes(axs[1], "h = 1/k", "relative error of the contact force",
               "error vs mesh size (reference: Aitken of the 3 finest)", title_size=9,
               legend=dict(fontsize=7))
    return fig


def _claims(t: pd.DataFrame, refs: dict) -> list[Claim]:
    ev, mono = [], True
    for tr in wp.TREATMENTS:
        e = t[t.treatment == tr].error.to_numpy()
        mono &= bool(np.all(np.isfinite(e)) and np.all(np.diff(e) < 0))
        ev.append(f"{tr}: errors " + ", ".join(f"{x:.3g}" for x in e))
    ok_ref = [r["reference_change"] for r in refs.values()]
    finest = {tr: float(t[t.treatment == tr].rel_error.iloc[-1]) for tr in wp.TREATMENTS}
    holds = None if not np.all(np.isfinite(ok_ref)) else bool(
        all(refs[tr]["reference_change"] < finest[tr] for tr in wp.TREATMENTS))
    rates = {tr: refs[tr]["slope_h"] for tr in wp.TREATMENTS}
    return [
        Claim("beyond the thesis: the force error of both treatments decreases with every "
              "refinement", mono, "; ".join(ev), kind="beyond", id="monotone"),
        Claim("beyond the thesis: each reference is converged beyond the finest mesh (its "
              "relative change against the extrapolation of the three coarser meshes is "
              "below the finest mesh's relative error)", holds,
              "; ".join(f"{tr}: reference {refs[tr]['reference']:.5g}, coarser "
                        f"{refs[tr]['reference_coarse']:.5g}, change "
                        f"{refs[tr]['reference_change']:.3g} vs finest error "
                        f"{finest[tr]:.3g}; observed rates {refs[tr]['rate_coarse']:.2f}, "
                        f"{refs[tr]['rate_fine']:.2f}" for tr in wp.TREATMENTS),
              kind="beyond", id="reference"),
        Claim("beyond the thesis: both treatments' force errors converge at the same rate "
              "in h (fitted slopes within 0.3 of each other)",
              bool(np.all(np.isfinite(list(rates.values())))
                   and abs(rates["mortar"] - rates["penalty"]) <= 0.3),
              ", ".join(f"{tr} {v:.2f}" for tr, v in rates.items()), kind="beyond",
              id="same_rate")]


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    """The work-precision figure (``quick`` is unused: config/quick.yaml sets the
    meshes)."""
    prm = from_config(wp.WorkPrecisionScene, config, scene="ch4_work_precision")
    t0, c0 = time.perf_counter(), time.process_time()
    for tr in wp.TREATMENTS:              # numba compilation / cache load, untimed
        wp.solve(prm, tr, prm.ks[0])
    jit_s, jit_cpu = time.perf_counter() - t0, time.process_time() - c0
    rows, refs = wp.work_precision_rows(prm)
    t = pd.DataFrame(rows)[COLUMNS]
    ratio = (t[t.treatment == "mortar"].wall_s.to_numpy()
             / t[t.treatment == "penalty"].wall_s.to_numpy())
    spread = float((t.wall_max_s / t.wall_s).max())
    return [ArtefactResult(
        name="figure_ch4_work_precision", table=t, figure=_figure(t, refs, prm.timing_repeats,
                                                       prm.repeat_max_k),
        claims=_claims(t, refs),
        notes="Beyond the thesis. Normal contact force of the stamp at full lift; meshes "
              "h = 1/k: Q1 stamp (k, 2k) cells, Q1 work piece (4k, 2k) cells, BE stamp "
              f"h_stamp = 1/k. Mortar: Tresca F = 0.22, DtN omega_D = {prm.omega_D}, "
              f"omega_N = {prm.omega_N}; penalty: Coulomb mu_f = 0.2, 1/eps_n = "
              f"{prm.factor:g} E, {prm.n_load} load increments (the two treatments solve "
              "different discrete problems, each error is against its own reference). "
              "Reference: Aitken extrapolation of the three finest meshes. Times: one "
              "solve including its set-up, the minimum of "
              f"{prm.timing_repeats} repeats (k > {prm.repeat_max_k}: once; slowest/fastest "
              f"up to {spread:.2f}); the "
              f"untimed warm-up (numba) took {jit_s:.1f} s wall, {jit_cpu:.1f} s CPU. "
              "Mortar/penalty wall-time ratios per mesh: "
              + ", ".join(f"{x:.2f}" for x in ratio) + " (no claim on time is made).",
        meta=dict(jit_s=round(jit_s, 2), jit_cpu_s=round(jit_cpu, 2),
                  run_s=round(time.perf_counter() - t0, 2),
                  timing_repeats=prm.timing_repeats, timing_spread_max=round(spread, 3),
                  **{f"{tr}_{k}": (round(v, 6) if np.isfinite(v) else None)
                     for tr, r in refs.items() for k, v in r.items()}))]
