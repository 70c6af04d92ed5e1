"""Figures 4.1-4.12 (Section 4.2.7, thesis lines 14810-14920): an elastic stamp pressed
onto an elastoplastic work piece, frictional penalty contact, Algorithm 4.1 (incremental
loading, Newton), J2 flow theory with mixed hardening (4.21)-(4.22), radial return and
its algorithmic tangent (4.38)-(4.43).

Example 1 (figure_4_1 ... figure_4_5): the stamp (slave, elastic) at [0.2, 1.2] x [-1, 1]
for the first touch and at [-1.8, -0.8] x [-1, 1] for the second, its top fixed; work
piece (master, elastoplastic) [-2, 2] x [-3, -1], its bottom lifted by 4.3e-3 in
increments; FE/FE and FE/BE (stamp by the Galerkin BEM, S_hat); deformed meshes (x100),
||eps_p|| and ||dev sigma|| against the applied force at X = (-0.9, -1.1).
Example 2 (figure_4_6 ... figure_4_12): one touch of the stamp [-1, 1] x [-1, 0], lift
4.2e-3; ||dev sigma|| at X = (1, -1.1).  BE/BE (figure_4_10, figure_4_11 and the BE/BE
curve of figure_4_12): the plastic BE work piece of Section 4.2.4
(:mod:`hpfebe.bodies.plastic_be`: Newton potentials of a cell-wise constant plastic strain,
backward Euler update) under a BE stamp, every theta of 'thetas' (the figures show the
first), mesh bebe_h.

Scenes (:data:`SCENES`, one workflow job each): ``ex1`` (figures 4.1-4.5) and ``ex2``
(figures 4.6-4.12 with the locking study, BE/BE and its mesh study).

Core: :mod:`hpfebe.constitutive.j2` (return map), :mod:`hpfebe.fem.plastic_body` (B-bar
Q1 work piece), :mod:`hpfebe.scenes.plasticity` (the examples' geometry, data and runs)
on :mod:`hpfebe.scenes.stamping` (touches through :class:`hpfebe.contact.TwoBodyContact`,
one load path each).  The choices where the thesis is silent are :data:`CHOICES`.
Modules: :mod:`.scene` (CHOICES, Params, the runs and tables), :mod:`.claims`,
:mod:`.figures`.
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from hpfebe.suite import ArtefactResult, Claim, from_config, select_scenes, timed

from .claims import (bebe_curve_claim, bebe_field_claims, bebe_mesh_claim, coupling_claim,
                     dent_claim, mesh_claims, zone_claim)
from .figures import bebe_exports, bebe_figure, curve_figure, field_figure, vtu_exports
from .scene import (CHOICES, Params, all_runs, bebe_mesh_study, bebe_runs, bebe_table,
                    curve_table, summary_table)

ARTEFACTS = ("figure_4_1", "figure_4_2", "figure_4_3", "figure_4_4", "figure_4_5",
             "figure_4_6", "figure_4_7", "figure_4_8", "figure_4_9", "figure_4_10",
             "figure_4_11", "figure_4_12")
#: the two examples are independent computations, one workflow job each.  Example 2's
#: artefacts stay together: figure_4_6 ... figure_4_9 tabulate every Example 2 run (the
#: fully integrated Q1 ones included) and figure_4_12 needs them all, the BE/BE runs of
#: figures 4.10-4.11 and the BE/BE mesh study.  CPU time of the full config, one thread
#: (measured on a loaded machine): ex1 91 s, ex2 72 s (meta scene_s: the wall time).
SCENES = {"ex1": ("figure_4_1", "figure_4_2", "figure_4_3", "figure_4_4", "figure_4_5"),
          "ex2": ("figure_4_6", "figure_4_7", "figure_4_8", "figure_4_9", "figure_4_10",
                  "figure_4_11", "figure_4_12")}


# --------------------------------------------------------------------------- artefacts
def field_artefacts(prm, runs, example, ids, notes, meta) -> list[ArtefactResult]:
    """Deformed mesh and ||eps_p|| artefacts of FE/FE and FE/BE (ids in that order)."""
    th = prm.thetas[0]
    out = []
    summ = summary_table(prm, runs, example)
    for k, st in enumerate(("FE", "BE")):
        run = runs[(example, st, th, prm.h_figure, "bbar")]
        label = "FE/FE" if st == "FE" else "FE/BE"
        claims_mesh = [dent_claim(prm, run)]
        claims_eps = [zone_claim(prm, runs, example)] if st == "BE" else [Claim(
            "plastic deformation under every touch of the stamp", bool(
                all(t.peak is not None and t.peak.fields["eps_p_norm"].max() > prm.zone_tol
                    for t in run.touches)) if run.converged else None,
            "max ||eps_p|| at the peak of each touch: " + ", ".join(
                f"{t.peak.fields['eps_p_norm'].max():.3e}" for t in run.touches if t.peak)
            + ("" if run.converged else f"; not converged: {run.touches[-1].reason}"),
            id="plastic")]
        tab = summ[summ.coupling == label].reset_index(drop=True)
        out.append(ArtefactResult(ids[2 * k], tab, field_figure(prm, run, None,
                                  f"{label} deformed mesh"), claims=claims_mesh,
                                  notes=notes, meta=meta))
        out.append(ArtefactResult(ids[2 * k + 1], tab, field_figure(
            prm, run, "eps_p_norm", f"{label} ||eps_p||"), claims=claims_eps, notes=notes,
            meta=meta, exports=vtu_exports(prm, run, label.replace("/", ""))))
    return out


def _scene_notes(runs: dict, bb_runs: list) -> str:
    failed = [f"{k}: {t.reason}" for k, r in [*runs.items(), *bb_runs]
              for t in r.touches if not t.converged]
    return " ".join(CHOICES) + (" FAILED RUNS: " + "; ".join(failed) if failed else "")


def _scene_meta(runs: dict, bb_runs: list, t0: float) -> dict:
    """Timing and Newton statistics of one scene's runs (bb_runs: (label, Run) of BE/BE)."""
    its = [rec.iterations for r in runs.values() for rec in r.records]
    return dict(run_s=time.perf_counter() - t0, runs=len(runs),
                all_converged=all(r.converged for r in [*runs.values(),
                                                         *(r for _, r in bb_runs)]),
                newton_total=int(sum(its)), newton_max_per_increment=int(max(its)),
                newton_mean_per_increment=float(np.mean(its)))


def example1(prm: Params) -> list[ArtefactResult]:
    """Scene ex1: figures 4.1-4.5 (both touches, FE and BE stamps, every theta and h)."""
    t0 = time.perf_counter()
    runs = all_runs(prm, (1,))
    notes, meta = _scene_notes(runs, []), _scene_meta(runs, [], t0)
    fig5 = ArtefactResult("figure_4_5", curve_table(runs, 1), curve_figure(prm, runs, 1),
                          claims=[coupling_claim(prm, runs, 1)], notes=notes, meta=meta)
    return field_artefacts(prm, runs, 1, ARTEFACTS[0:4], notes, meta) + [fig5]


def example2(prm: Params) -> list[ArtefactResult]:
    """Scene ex2: figures 4.6-4.12 (FE/FE, FE/BE with the locking study, BE/BE and its
    mesh study)."""
    t0 = time.perf_counter()
    runs = all_runs(prm, (2,))
    bebe = bebe_runs(prm, runs)
    study, t_study = timed(bebe_mesh_study, prm, runs, bebe)
    bb_runs = [(f"BE/BE theta={th:g}", pair["BE/BE"]) for th, pair in bebe.items()]
    st_runs = [(f"BE/BE study h={h:g}", p["BE/BE"]) for h, p in study.items()
               if h != prm.bebe_h]
    notes = _scene_notes(runs, bb_runs + st_runs)
    meta = dict(_scene_meta(runs, bb_runs + st_runs, t0),
                bebe_s=sum(r.wall_s for _, r in bb_runs) if bebe else None,
                bebe_s_per_theta={f"{r.theta:g}": r.wall_s for _, r in bb_runs},
                bebe_newton_per_increment="; ".join(
                    f"theta={r.theta:g}: " + " ".join(str(x.iterations) for x in r.records)
                    for _, r in bb_runs) if bebe else None)
    meta12 = dict(meta, bebe_study_s=t_study if study else None,
                  bebe_study_s_per_h={f"{h:g}": p["BE/BE"].wall_s for h, p in study.items()},
                  bebe_study_newton_per_increment="; ".join(
                      f"h={h:g}: " + " ".join(str(x.iterations) for x in p["BE/BE"].records)
                      for h, p in study.items()) if study else None)
    ex2 = field_artefacts(prm, runs, 2, ARTEFACTS[5:9], notes, meta)
    tab = bebe_table(bebe) if bebe else pd.DataFrame({"coupling": ["BE/BE"],
                                                      "computed": [False]})
    first = bebe.get(prm.thetas[0], {})
    c_mesh, c_eps = bebe_field_claims(prm, bebe)
    bb = [ArtefactResult("figure_4_10", tab, bebe_figure(prm, first, None,
                                                         "BE/BE deformed mesh"),
                         claims=[c_mesh], notes=notes, meta=meta),
          ArtefactResult("figure_4_11", tab, bebe_figure(prm, first, "eps_p_norm",
                                                         "BE/BE ||eps_p||"),
                         claims=[c_eps], notes=notes, meta=meta,
                         exports=bebe_exports(bebe))]
    c2 = pd.concat([curve_table(runs, 2), bebe_table(bebe)]).drop_duplicates(
        ignore_index=True) if bebe else curve_table(runs, 2)     # FE/FE bebe_h may be in both
    c2 = pd.concat([c2, bebe_table(study)]).drop_duplicates(ignore_index=True) \
        if study else c2                                  # BE/BE mesh study: new meshes only
    fig12 = ArtefactResult("figure_4_12", c2, curve_figure(prm, runs, 2, bebe, study),
                           claims=[coupling_claim(prm, runs, 2),
                                   bebe_curve_claim(prm, runs, bebe),
                                   *mesh_claims(prm, runs),
                                   bebe_mesh_claim(prm, runs, study)],
                           notes=notes, meta=meta12)
    return ex2 + bb + [fig12]


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """Figures 4.1-4.12 (config/quick.yaml sets the sizes); scenes: names of
    :data:`SCENES` to compute (None: all)."""
    prm = from_config(Params, config, scene="ch4_plasticity")
    scenes = select_scenes(SCENES, scenes, "ch4_plasticity")
    out = []
    for name, scene in (("ex1", example1), ("ex2", example2)):
        if name in scenes:
            res, scene_s = timed(scene, prm)
            for r in res:
                r.meta["scene_s"] = scene_s
            out += res
    return out
