"""The fields of Figures 4.21 (mortar) and 4.22 (penalty), Section 4.4 (thesis line
~20715: "5-8 % in displacement, 2-3 % in stress"): both bodies' fields of either
solution (:func:`mortar_fields`, :func:`penalty_fields`), their colour-bar ranges beside
the published ones (:func:`colour_ranges`), the mortar-penalty differences on common
points and their split into variants (:func:`comparison_rows`, :data:`VARIANTS`: friction
law, penalty parameter, work piece formulation and mesh), the same per sensitivity
variant (:func:`variant_rows`), the bands of the thesis's statement (:data:`BANDS`,
:func:`beyond_bands`) and the readings of it (:func:`comparison_readings`), and the
ParaView exports of both solutions (:func:`penalty_exports`, :func:`mortar_exports`)."""

from __future__ import annotations

import logging
from dataclasses import replace

import meshio
import numpy as np

from ..io import contact_vtu, fe_vtu
from .mortar import mortar_contact_state
from .section44 import (PUB_DEV_MAX, PUB_MORTAR_DEV_MAX, PUB_MORTAR_UX, PUB_MORTAR_UY, PUB_UX,
                        PUB_UY, VARIANT_TEXT, Section44Scene, field_differences,
                        mortar_bodies)
from .section44_runs import run_penalty

log = logging.getLogger(__name__)

__all__ = ["BANDS", "MATCHED", "VARIANTS", "beyond_bands", "colour_ranges",
           "comparison_readings", "comparison_rows", "fixed_extremes", "matched_factor",
           "mortar_exports", "mortar_fields", "penalty_exports", "penalty_fields", "variant_rows"]


def mortar_fields(pr, sol) -> dict:
    """Both bodies' (points, cells, displacement) and the work piece's (mesh, element
    means of ||dev sigma||) of a mortar solution."""
    return dict(mortar_bodies(pr, sol),
                dev=(pr.work.mesh, sol.extra["fields"]["dev_sigma_norm_mean"]))


def penalty_fields(prm: Section44Scene, r) -> dict:
    """:func:`mortar_fields` of a penalty run ``r`` (a
    :class:`~hpfebe.scenes.section44_runs.PenaltyRun`; the BE stamp on its interior
    grid)."""
    return dict(r.bodies(prm.h_stamp), dev=(r.fe.mesh, r.peak.fields["dev_sigma_norm"]))


def colour_ranges(bodies: dict, dev: np.ndarray, mortar: bool = False) -> list[dict]:
    """Our colorbar ranges (nodal u_x, u_y of both bodies, ||dev sigma_m|| of the
    element values ``dev``) beside the published ones of Figure 4.22 (penalty) or, with
    ``mortar``, Figure 4.21: rows (body, field, ours_min, ours_max, published_min,
    published_max)."""
    pub_ux, pub_uy, pub_dev = ((PUB_MORTAR_UX, PUB_MORTAR_UY, PUB_MORTAR_DEV_MAX) if mortar
                               else (PUB_UX, PUB_UY, PUB_DEV_MAX))
    rows = []
    for b, (_, _, u) in bodies.items():
        for c, name, pub in ((0, "u_x", pub_ux), (1, "u_y", pub_uy)):
            rows.append(dict(body=b, field=name, ours_min=float(u[:, c].min()),
                             ours_max=float(u[:, c].max()), published_min=pub[b][0],
                             published_max=pub[b][1]))
    rows.append(dict(body="work", field="dev_sigma_norm", ours_min=float(dev.min()),
                     ours_max=float(dev.max()), published_min=float("nan"),
                     published_max=pub_dev))
    return rows


def fixed_extremes(prm: Section44Scene, body: str, field: str, lo: float, hi: float
                   ) -> tuple[str, ...]:
    """The colour-bar extremes that are Dirichlet values by construction (no evidence):
    the work piece's u_y maximum, its bottom's lift, and the stamp's u_y minimum, its
    fixed top's 0 - where ours is that value."""
    if field == "u_y" and body == "work" and np.isclose(hi, prm.lift, rtol=1e-9, atol=0):
        return ("max",)
    if field == "u_y" and body == "stamp" and lo == 0.0:
        return ("min",)
    return ()


# --------------------------------------------------------------------------- comparison
VARIANTS = {
    "main": "mortar (Tresca F) vs penalty (Coulomb mu_f, 1/eps_n = figure_factor E): the "
            "thesis's comparison, same work piece mesh and formulation",
    "eps_<f>": "the same with the penalty run 1/eps_n = f E of Table 4.3",
    "frictionless": "mortar F = 0 vs penalty mu_f = 0: the method alone (FE stamp + mortar "
                    "vs BE stamp + penalty)",
    "friction_mortar": "mortar frictionless (reference) vs mortar Tresca F",
    "friction_penalty": "penalty frictionless (reference) vs penalty Coulomb mu_f",
    "penalty_bbar": "mortar vs penalty with a B-bar work piece on the same mesh",
    "penalty_bbar_h_work": "mortar vs penalty with a B-bar work piece on the uniform h_work "
                           "mesh (the comparison before issue 13's follow-up)",
    "tresca_matched": "mortar vs penalty with the mortar's Tresca F in the penalty law "
                      "(1/eps_n = figure_factor E): the friction law matched, the method's "
                      "difference alone (FE stamp + mortar + DtN vs BE stamp + penalty)",
    "tresca_matched_eps_<f>": "the same at the stiffest penalty f of Table 4.3",
    "friction_law_penalty": "penalty Tresca F (reference) vs penalty Coulomb mu_f, both "
                            "1/eps_n = figure_factor E: the friction law's share",
}

MATCHED = "tresca_matched"

# the thesis's comparison (line ~20715): "5-8 % in displacement, 2-3 % in stress",
# checked as upper bounds on the relative discrete L2 differences
BANDS = {"displacement": 0.08, "stress": 0.03}


def matched_factor(prm: Section44Scene) -> float:
    """The penalty of the friction-matched comparison claim: the stiffest of Table 4.3,
    nearest to the mortar's exact non-penetration (penalty -> mortar as eps_n -> 0)."""
    return float(max(prm.eps_n_factors))


def _rows(variant: str, a: dict, b: dict) -> list[dict]:
    return [dict(r, variant=variant) for r in field_differences(a, b)]


def _matched_variants(prm: Section44Scene, mort: dict, pen: dict, rows: list, extra: dict,
                      solve) -> None:
    """The penalty runs with the mortar's Tresca F (:data:`VARIANTS` tresca_matched*,
    friction_law_penalty): at figure_factor and at :func:`matched_factor`."""
    q, ff = replace(prm, penalty_law="tresca"), prm.figure_factor
    for f in dict.fromkeys((ff, matched_factor(prm))):
        name = MATCHED if f == ff else f"{MATCHED}_eps_{f:g}"
        extra[name] = r = solve(q, f)
        if r.peak is None:
            log.warning("comparison variant %s: %s", name, r.result.reason)
            continue
        fields = penalty_fields(q, r)
        rows += _rows(name, mort, fields)
        if f == ff and ff in pen:
            rows += _rows("friction_law_penalty", fields, pen[ff])


def comparison_rows(prm: Section44Scene, pr, sol, free, runs: dict, solve=run_penalty
                    ) -> tuple[list[dict], dict]:
    """The mortar-penalty differences (variant "main", ``sol`` against the penalty run
    at figure_factor; "eps_<f>" the other runs of ``runs``) and, with
    ``compare_variants``, their split (:data:`VARIANTS`; ``free``: the frictionless
    mortar solution).  Returns (rows of :func:`~hpfebe.scenes.section44.field_differences`
    with their ``variant``, {variant: penalty run} of the extra penalty runs); ``solve``:
    :func:`~hpfebe.scenes.section44_runs.run_penalty` or its memo."""
    mort, ff = mortar_fields(pr, sol), prm.figure_factor
    rows, extra = [], {}
    pen = {f: penalty_fields(prm, r) for f, r in runs.items() if r.peak is not None}
    for f in sorted(pen, key=lambda f: f != ff):
        rows += _rows("main" if f == ff else f"eps_{f:g}", mort, pen[f])
    if not prm.compare_variants:
        return rows, extra
    for name, q in (("frictionless", prm.frictionless()),
                    ("penalty_bbar", replace(prm, penalty_formulation="bbar")),
                    ("penalty_bbar_h_work", replace(prm, penalty_formulation="bbar",
                                                    penalty_mesh="h_work"))):
        extra[name] = r = solve(q, ff)
        if r.peak is None:
            log.warning("comparison variant %s: %s", name, r.result.reason)
            continue
        fields = penalty_fields(q, r)
        if name == "frictionless":
            if free.info.converged:
                mfree = mortar_fields(pr, free)
                rows += _rows(name, mfree, fields) + _rows("friction_mortar", mfree, mort)
            if ff in pen:
                rows += _rows("friction_penalty", fields, pen[ff])
        else:
            rows += _rows(name, mort, fields)
    _matched_variants(prm, mort, pen, rows, extra, solve)
    return rows, extra


def variant_rows(prm: Section44Scene, mortar: dict, solve, variants: dict) -> dict:
    """Per sensitivity variant but the table: the rows of the mortar-penalty differences
    "main" (penalty Coulomb mu_f) and :data:`MATCHED` (penalty with the mortar's Tresca
    F), both at figure_factor, on that variant's meshes (None where a run failed);
    ``mortar``: variant -> (scene, solution) of
    :func:`~hpfebe.scenes.section44_runs.mortar_variants`."""
    out = {}
    for name, q in variants.items():
        sc, msol = mortar[name]
        if name == "table":
            continue
        runs = {v: (p, solve(p, prm.figure_factor)) for v, p in
                (("main", q), (MATCHED, replace(q, penalty_law="tresca")))}
        if msol is None or any(r.peak is None for _, r in runs.values()):
            out[name] = None
            continue
        mort = mortar_fields(sc, msol)
        out[name] = [row for v, (p, r) in runs.items()
                     for row in _rows(v, mort, penalty_fields(p, r))]
    return out


def beyond_bands(rows, variant: str) -> tuple[bool, list]:
    """(variant present, [(body, field, rel_l2) beyond :data:`BANDS`]) of one comparison
    variant of the difference ``rows`` (records with body, field, rel_l2, variant)."""
    t = [r for r in rows if r["variant"] == variant]
    band = [BANDS["stress" if r["field"] == "dev_sigma_norm" else "displacement"] for r in t]
    return len(t) > 0, [(r["body"], r["field"], r["rel_l2"]) for r, b in zip(t, band)
                        if not r["rel_l2"] <= b]


# --------------------------------------------------------------------------- exports
def _work_vtu(work, u, cell_fields: dict) -> meshio.Mesh:
    """The work piece (an ElastoPlasticFE) with its nodal displacement ``u`` (dofs) and
    element fields."""
    return fe_vtu(work.mesh, {"u": work.elastic.nodal_displacement(u).T},
                  {k: np.asarray(v, dtype=float) for k, v in cell_fields.items()})


def penalty_exports(prm: Section44Scene, r) -> dict:
    """ParaView meshes of a penalty run ``r`` at full lift: the work piece
    (displacement, element fields), the BE stamp's interior on its grid of cell size
    h_stamp / 2 (displacement by the representation formula) and the contact state along
    Gamma_C (pressure, tangential traction, gap, slip, stick/slip state; both passes'
    points)."""
    if r.peak is None:
        return {}
    s = r.peak
    pts, cells, u = r.bodies(prm.h_stamp)["stamp"]
    z = np.zeros((len(pts), 1))
    stamp = meshio.Mesh(np.hstack([pts, z]), [("quad", np.asarray(cells))],
                        point_data={"u": np.hstack([u, z])})
    return {"work": _work_vtu(r.fe, s.u_work, s.fields), "stamp": stamp,
            "contact": contact_vtu(s.result)}


def mortar_exports(pr, sol) -> dict:
    """ParaView meshes of a mortar solution of the Section 4.4 scene: both Q1 bodies
    with their displacement (the work piece with its element fields) and the contact
    state at the nodes of Gamma^1_C (:func:`~hpfebe.scenes.mortar.mortar_contact_state`)."""
    u1 = sol.extra["u1"]
    fields = {k: v for k, v in sol.extra["fields"].items() if k.endswith("_mean")}
    return {"work": _work_vtu(pr.work, sol.extra["u2"], fields),
            "stamp": fe_vtu(pr.stamp.mesh, {"u": pr.stamp.nodal_displacement(u1).T}),
            "contact": contact_vtu(mortar_contact_state(pr, sol))}


# --------------------------------------------------------------------------- readings
def _summary(rows: list, v: str) -> str:
    return f"{v}: " + ", ".join(f"{r['body']} {r['field']} {r['rel_l2']:.1%} (max "
                                f"{r['rel_max']:.1%})" for r in rows if r["variant"] == v)


def _rel(rows: list, variant: str) -> dict:
    return {(r["body"], r["field"]): r["rel_l2"] for r in rows if r["variant"] == variant}


def _fmt(xs) -> str:
    return ", ".join(f"{b} {f} {v:.2%}" for b, f, v in xs) or "none"


def comparison_readings(prm: Section44Scene, rows: list, sens: dict | None = None) -> dict:
    """The thesis's "5-8 % in displacement, 2-3 % in stress" (:data:`BANDS`) on the
    difference ``rows`` of :func:`comparison_rows`, keyed by claim id, each (verdict,
    evidence): ``bands`` - its own setup ("main": mortar Tresca F against penalty
    Coulomb mu_f); ``matched`` - the friction law matched (penalty with the mortar's
    Tresca F at :func:`matched_factor`: the method's difference alone); ``friction_law``
    - whether the friction law is the reason where the thesis's setup leaves the bands,
    on the table's meshes and on every sensitivity variant (``sens``: variant -> the
    rows of :func:`variant_rows`, None where a run failed)."""
    nx, ny = prm.penalty_cells
    sx, sy = prm.stamp_cells
    where = (f"relative discrete L2 (max-norm) of the penalty field against the mortar "
             f"field on the penalty's nodes / grid points / element centroids; work piece "
             f"{nx} x {ny} Q1 '{prm.penalty_formulation}' in both methods, stamp FE {sx} x "
             f"{sy} (mortar) against BE (penalty, grid h_stamp/2)")
    has, beyond = beyond_bands(rows, "main")
    ev = "; ".join(_summary(rows, v) for v in dict.fromkeys(r["variant"] for r in rows))
    fm = matched_factor(prm)
    mname = MATCHED if fm == prm.figure_factor else f"{MATCHED}_eps_{fm:g}"
    has_m, beyond_m = beyond_bands(rows, mname)
    has_s, beyond_s = beyond_bands(rows, MATCHED)       # same penalty as "main"
    same, stiff = _rel(rows, MATCHED), _rel(rows, mname)
    out = {"bands": (bool(not beyond) if has else None, (
        f"{where}. Beyond the bands: {_fmt(beyond)}"
        + (f"; the same fields with the friction law matched at the same penalty "
           f"({MATCHED}): " + _fmt((b, f, same[(b, f)]) for b, f, _ in beyond
                                   if (b, f) in same) if beyond and same else "")
        + f". {ev}. Reading: 'frictionless' and '{MATCHED}*' are the method's share alone "
        "(FE stamp + mortar against BE stamp + penalty eps); where 'main' exceeds them, the "
        "friction laws make the difference ('friction_*': how far each law moves its own "
        "solution, 'friction_law_penalty': Coulomb against Tresca in the penalty method); "
        "eps_<f>: the penalty parameter's share; 'penalty_bbar*': the work piece "
        "formulation's and mesh's (penalty_bbar_h_work is the comparison as it was "
        "before: B-bar on 44 x 22)"))}
    out["matched"] = (bool(not beyond_m) if has_m else None, (
        f"{where}. {_summary(rows, mname)}; beyond the bands: {_fmt(beyond_m)}. At "
        f"1/eps_n = {prm.figure_factor:g} E ({MATCHED}): beyond the bands: "
        f"{_fmt(beyond_s)}; the same fields at {fm:g} E: "
        + _fmt((b, f, stiff[(b, f)]) for b, f, _ in beyond_s if (b, f) in stiff)
        + " (the penalty parameter's share, cf. eps_<f>)"
        if has_m else f"variant {mname} not run (compare_variants off or run failed)"))

    def within(matched_rows: dict) -> bool:
        return all((b, f) in matched_rows and matched_rows[(b, f)] <= BANDS[
            "stress" if f == "dev_sigma_norm" else "displacement"] for b, f, _ in beyond)

    per = {k: None if d is None else (_rel(d, "main"), _rel(d, MATCHED))
           for k, d in ({} if sens is None else sens).items()}
    holds = None
    if beyond and has_s and all(v is not None for v in per.values()):
        holds = bool(within(same) and all(within(m) for _, m in per.values()))
    ev_sens = "; ".join(
        f"{k}: " + ("a run failed" if v is None else ", ".join(
            f"{b} {f} main {v[0].get((b, f), np.nan):.2%}, {MATCHED} "
            f"{v[1].get((b, f), np.nan):.2%}" for b, f, _ in beyond))
        for k, v in per.items())
    out["friction_law"] = (holds, (
        f"main beyond the bands: {_fmt(beyond)}; {MATCHED}: "
        + _fmt((b, f, same[(b, f)]) for b, f, _ in beyond if (b, f) in same)
        + (f"; {_summary(rows, 'friction_law_penalty')}" if
           any(r["variant"] == "friction_law_penalty" for r in rows) else "")
        + ("" if beyond else " (nothing to explain: 'main' lies within the bands)")
        + (f". Sensitivity variants (mortar by the monolithic Newton where the mortar "
           f"problem changes, penalty at 1/eps_n = {prm.figure_factor:g} E): {ev_sens}. "
           + "; ".join(f"{k}: {VARIANT_TEXT[k]}" for k in per) if per and beyond else "")))
    return out
