"""Figures 4.1-4.12 (Section 4.2.7, thesis lines 14810-14920): an elastic stamp pressed
onto an elastoplastic work piece, frictional penalty contact, Algorithm 4.1 (incremental
loading, Newton), J2 flow theory with mixed hardening (4.21)-(4.22), radial return and
its algorithmic tangent (4.38)-(4.43).

Example 1 (figure_4_1 ... figure_4_5): the stamp (slave, elastic, top fixed) at
[0.2, 1.2] x [-1, 1] for the first touch and at [-1.8, -0.8] x [-1, 1] for the second on
the work piece (master, elastoplastic) [-2, 2] x [-3, -1], its bottom lifted by 4.3e-3 in
increments; FE/FE and FE/BE (stamp by the Galerkin BEM, S_hat); deformed meshes (x100),
||eps_p|| and ||dev sigma|| against the applied force at X = (-0.9, -1.1).  Example 2
(figure_4_6 ... figure_4_12): one touch of the stamp [-1, 1] x [-1, 0], lift 4.2e-3, X =
(1, -1.1); BE/BE (figures 4.10, 4.11, 4.12): the plastic BE work piece of Section 4.2.4
(Newton potentials of a cell-wise constant plastic strain) under a BE stamp.

Scenes (:data:`SCENES`, one workflow job each): ``ex1`` (figures 4.1-4.5) and ``ex2``
(figures 4.6-4.12 with the locking study, BE/BE and its mesh study).  The examples'
geometry, data, runs and tables and the choices where the thesis is silent (``CHOICES``):
:mod:`hpfebe.scenes.plasticity`; the fields compared and drawn:
:mod:`hpfebe.scenes.plasticity_fields`.  Here: :mod:`.claims`, :mod:`.figures`.
"""

from __future__ import annotations

import pandas as pd

from hpfebe.scenes import plasticity, plasticity_fields
from hpfebe.suite import ArtefactResult, from_config, progress, select_scenes, timed

from . import claims
from .figures import bebe_figure, curve_figure, field_figure

ARTEFACTS = ("figure_4_1", "figure_4_2", "figure_4_3", "figure_4_4", "figure_4_5",
             "figure_4_6", "figure_4_7", "figure_4_8", "figure_4_9", "figure_4_10",
             "figure_4_11", "figure_4_12")
#: the two examples are independent computations, one workflow job each (full config, one
#: thread, measured on a loaded machine: ex1 91 s, ex2 72 s; meta scene_s: the wall time)
SCENES = {"ex1": ("figure_4_1", "figure_4_2", "figure_4_3", "figure_4_4", "figure_4_5"),
          "ex2": ("figure_4_6", "figure_4_7", "figure_4_8", "figure_4_9", "figure_4_10",
                  "figure_4_11", "figure_4_12")}


def field_artefacts(prm, runs, example, ids, notes, meta) -> list[ArtefactResult]:
    """Deformed mesh and ||eps_p|| artefacts of FE/FE and FE/BE (ids in that order)."""
    summ, out = pd.DataFrame(plasticity.summary_rows(prm, runs, example)), []
    for k, (st, label) in enumerate((("FE", "FE/FE"), ("BE", "FE/BE"))):
        run = runs[(example, st, prm.thetas[0], prm.h_figure, "bbar")]
        eps = (claims.zone_claim(prm, runs, example) if st == "BE" else
               claims.plastic_claim(prm, run))
        tab, kw = summ[summ.coupling == label].reset_index(drop=True), dict(notes=notes,
                                                                            meta=meta)
        out += [ArtefactResult(ids[2 * k], tab, field_figure(
                    prm, run, None, f"{label} deformed mesh"),
                    claims=[claims.dent_claim(prm, run)], **kw),
                ArtefactResult(ids[2 * k + 1], tab, field_figure(
                    prm, run, "eps_p_norm", f"{label} ||eps_p||"), claims=[eps], **kw,
                    exports=plasticity_fields.touch_exports(run, label.replace("/", ""),
                                                            prm.h_figure))]
    return out


def example1(prm: plasticity.StampingStudy) -> list[ArtefactResult]:
    """Scene ex1: figures 4.1-4.5 (both touches, FE and BE stamps, every theta and h)."""
    ex = plasticity.example_runs(prm, 1, progress)
    fig5 = ArtefactResult("figure_4_5", pd.DataFrame(plasticity.curve_rows(ex.runs, 1)),
                          curve_figure(prm, ex.runs, 1),
                          claims=[claims.coupling_claim(prm, ex.runs, 1)], notes=ex.notes,
                          meta=ex.meta)
    return field_artefacts(prm, ex.runs, 1, ARTEFACTS[0:4], ex.notes, ex.meta) + [fig5]


def example2(prm: plasticity.StampingStudy) -> list[ArtefactResult]:
    """Scene ex2: figures 4.6-4.12 (FE/FE, FE/BE with the locking study, BE/BE and its
    mesh study)."""
    ex = plasticity.example_runs(prm, 2, progress)
    runs, bebe, study, notes, meta = ex.runs, ex.bebe, ex.study, ex.notes, ex.meta
    bebe_tab = pd.DataFrame(plasticity.bebe_rows(bebe)) if bebe else pd.DataFrame(
        {"coupling": ["BE/BE"], "computed": [False]})
    first = bebe.get(prm.thetas[0], {})
    c_mesh, c_eps = claims.bebe_field_claims(prm, bebe)
    c12 = pd.DataFrame(plasticity.curve_rows(runs, 2))
    for part in (p for p in (bebe, study) if p):     # FE/FE at bebe_h may be in both
        c12 = pd.concat([c12, pd.DataFrame(plasticity.bebe_rows(part))]).drop_duplicates(
            ignore_index=True)
    return field_artefacts(prm, runs, 2, ARTEFACTS[5:9], notes, meta) + [
        ArtefactResult("figure_4_10", bebe_tab, bebe_figure(prm, first, None,
                                                            "BE/BE deformed mesh"),
                       claims=[c_mesh], notes=notes, meta=meta),
        ArtefactResult("figure_4_11", bebe_tab, bebe_figure(prm, first, "eps_p_norm",
                                                            "BE/BE ||eps_p||"),
                       claims=[c_eps], notes=notes, meta=meta,
                       exports=plasticity_fields.bebe_exports(bebe)),
        ArtefactResult("figure_4_12", c12, curve_figure(prm, runs, 2, bebe, study),
                       claims=[claims.coupling_claim(prm, runs, 2),
                               claims.bebe_curve_claim(prm, runs, bebe),
                               *claims.mesh_claims(prm, runs),
                               claims.bebe_mesh_claim(prm, runs, study)],
                       notes=notes, meta=ex.meta_study)]


def run(config: dict, quick: bool = False, scenes=None) -> list[ArtefactResult]:
    """Figures 4.1-4.12 (config/quick.yaml sets the sizes); scenes: names of
    :data:`SCENES` to compute (None: all)."""
    prm = from_config(plasticity.StampingStudy, config, scene="ch4_plasticity")
    out = []
    for name in select_scenes(SCENES, scenes, "ch4_plasticity"):
        res, scene_s = timed({"ex1": example1, "ex2": example2}[name], prm)
        for r in res:
            r.meta["scene_s"] = scene_s
        out += res
    return out
