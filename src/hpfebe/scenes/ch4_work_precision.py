"""Beyond the thesis (issue 28): work-precision of Section 4.4's stamp contact force.

The stamp on the work piece of Section 4.4 (:mod:`hpfebe.scenes.section44`) on the mesh
family k: the Q1 stamp [-1/2, 1/2] x [0, 2] with (k, 2k) cells, the Q1 work piece
[-2, 2] x [-2, 0] with (4k, 2k) cells (h = 1/k in both), the BE stamp of the penalty
treatment with mesh size h_stamp = 1/k.

* mortar (Table 4.2's set-up): FE/FE, Tresca F, Algorithm 4.3 (DtN) at the damping
  (omega_D, omega_N) (:func:`~hpfebe.scenes.section44_runs.dtn_run`); the contact force
  is the vertical resultant of the transferred force on the work piece (``force2``).
* penalty (Table 4.3's set-up): FE/BE, Coulomb mu_f, 1/eps_n = ``factor`` E
  (:func:`~hpfebe.scenes.section44_runs.run_penalty`); the force int_Gamma_C p_n ds.

The quantity is the normal contact force at full lift.  Each treatment's reference is
the Aitken (Richardson with the observed rate) extrapolation of its three finest meshes,
F* = F3 - (F3 - F2)^2 / ((F3 - F2) - (F2 - F1)); with four or more meshes the reference
is checked against the extrapolation of the three next coarser meshes (its change,
reported).  Each run is timed ``timing_repeats`` times (wall and CPU of one solve,
including the set-up of the problem; the minimum is kept; meshes finer than
``repeat_max_k`` once), after one untimed warm-up
at the coarsest mesh that absorbs the numba compilation / cache load (reported apart).
Slopes: least-squares fits of log error against log h and against log wall time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..checks import integer, real
from .section44 import Section44Scene
from .section44_runs import dtn_run, mortar_scene, run_penalty

TREATMENTS = ("mortar", "penalty")


@dataclass(frozen=True)
class WorkPrecisionScene:
    """Parameters (config section ``ch4_work_precision``): the mesh family ``ks``
    (increasing, at least three), the penalty 1/eps_n = ``factor`` E, the DtN damping
    (``omega_D``, ``omega_N``), the timing repeats and the load increments of the
    penalty runs (``n_load``); the rest of the scene is :class:`Section44Scene`'s."""

    ks: tuple[int, ...] = (2, 4, 8, 16)
    factor: float = 10.0
    omega_D: float = 0.5
    omega_N: float = 0.7
    timing_repeats: int = 2
    n_load: int = 5
    repeat_max_k: int = 16      # meshes finer than this are timed once (the CPU budget)

    def __post_init__(self):
        ks = tuple(self.ks)
        if len(ks) < 3:
            raise ValueError(f"ch4_work_precision.ks needs at least three meshes, got {ks!r}")
        for k in ks:
            integer("ks", k, lo=1)
        if any(b <= a for a, b in zip(ks, ks[1:])):
            raise ValueError(f"ch4_work_precision.ks must increase, got {ks!r}")
        real("factor", self.factor, positive=True)
        for name in ("omega_D", "omega_N"):
            real(name, getattr(self, name), lo=0.0, hi=1.0, lo_open=True)
        integer("timing_repeats", self.timing_repeats, lo=1)
        integer("n_load", self.n_load, lo=1)
        integer("repeat_max_k", self.repeat_max_k, lo=1)

    def repeats(self, k: int) -> int:
        """Timed solves on mesh k: ``timing_repeats``, once above ``repeat_max_k``."""
        return self.timing_repeats if k <= self.repeat_max_k else 1

    def scene(self, k: int) -> Section44Scene:
        """Section 4.4's parameters on mesh k (h = 1/k in both bodies)."""
        return replace(Section44Scene(), stamp_cells=(k, 2 * k), work_cells=(4 * k, 2 * k),
                       h_stamp=1.0 / k, n_load=self.n_load, eps_n_factors=(self.factor,),
                       figure_factor=self.factor)


def solve(prm: WorkPrecisionScene, treatment: str, k: int) -> dict:
    """One solve of ``treatment`` on mesh k: force, dofs, iterations, convergence."""
    q = prm.scene(k)
    if treatment == "mortar":
        pr = mortar_scene(q)
        sol = dtn_run(pr, q, prm.omega_D, prm.omega_N)
        ok = bool(sol.info.converged)
        force = float(np.sum(sol.extra["force2"][1::2])) if ok else np.nan
        return dict(force=force, converged=ok, iterations=int(sol.info.iterations),
                    dof=int(sol.extra["u1"].size + sol.extra["u2"].size))
    if treatment == "penalty":
        r = run_penalty(q, prm.factor)
        ok = bool(r.result.converged and r.peak is not None)
        force = float(r.peak.result.total_forces()[0]) if ok else np.nan
        its = sum(rec.iterations for rec in r.result.records)
        return dict(force=force, converged=ok, iterations=int(its),
                    dof=int(r.fe.ndofs + (r.peak.u_stamp.size if ok else 0)))
    raise ValueError(f"treatment must be one of {TREATMENTS}, got {treatment!r}")


def timed_solve(prm: WorkPrecisionScene, treatment: str, k: int) -> dict:
    """:func:`solve` ``prm.repeats(k)`` times: the row with the minimum wall and CPU
    time (``wall_s``, ``cpu_s``), the slowest wall time (``wall_max_s``) and the number
    of repeats."""
    walls, cpus, row = [], [], None
    for _ in range(prm.repeats(k)):
        w0, c0 = time.perf_counter(), time.process_time()
        row = solve(prm, treatment, k)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return dict(row, wall_s=min(walls), wall_max_s=max(walls), cpu_s=min(cpus),
                repeats=len(walls))


def aitken(f) -> float:
    """The Aitken extrapolation of three values of a sequence on h, h/2, h/4 (NaN when
    the differences do not contract, i.e. the sequence is not in its asymptotic range)."""
    f1, f2, f3 = map(float, f)
    d1, d2 = f2 - f1, f3 - f2
    if not (np.isfinite(d1) and np.isfinite(d2)) or d1 == d2 or abs(d2) >= abs(d1):
        return float("nan")
    return f3 - d2 * d2 / (d2 - d1)


def observed_rate(f) -> float:
    """log2 of the contraction of the differences of three values on h, h/2, h/4."""
    f1, f2, f3 = map(float, f)
    return float(np.log2(abs(f2 - f1) / abs(f3 - f2))) if f3 != f2 else float("nan")


def fit_slope(x, y) -> float:
    """Least-squares slope of log y against log x over the finite positive pairs (NaN
    with fewer than two)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0]) if ok.sum() >= 2 \
        else float("nan")


def references(forces) -> dict:
    """The reference of one treatment's forces on ``ks`` (halving meshes): Aitken of the
    three finest, that of the three next coarser (NaN with three meshes), the relative
    change between them and the observed rates of both triples."""
    f = np.asarray(forces, float)
    ref = aitken(f[-3:])
    coarse = aitken(f[-4:-1]) if f.size >= 4 else float("nan")
    return dict(reference=ref, reference_coarse=coarse,
                reference_change=abs(ref - coarse) / abs(ref) if np.isfinite(coarse)
                else float("nan"),
                rate_fine=observed_rate(f[-3:]),
                rate_coarse=observed_rate(f[-4:-1]) if f.size >= 4 else float("nan"))


def work_precision_rows(prm: WorkPrecisionScene, timed=timed_solve) -> tuple[list, dict]:
    """The table rows (treatment, k, h, dof, force, error against the treatment's
    reference, timings) and per treatment :func:`references` plus the fitted slopes."""
    rows, refs = [], {}
    for tr in TREATMENTS:
        rs = [dict(treatment=tr, k=k, h=1.0 / k, **timed(prm, tr, k)) for k in prm.ks]
        ref = references([r["force"] for r in rs])
        for r in rs:
            r["reference"] = ref["reference"]
            r["error"] = abs(r["force"] - ref["reference"])
            r["rel_error"] = r["error"] / abs(ref["reference"])
        # the finest mesh's error is the extrapolation's own correction: fit all meshes
        ref["slope_h"] = fit_slope([r["h"] for r in rs], [r["error"] for r in rs])
        ref["slope_time"] = fit_slope([r["wall_s"] for r in rs], [r["error"] for r in rs])
        refs[tr] = ref
        rows += rs
    return rows, refs
