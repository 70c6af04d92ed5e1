"""The claims of Figures 4.1-4.12: FE/FE and FE/BE close, similar plastic zones, the
dent, the mesh study and locking (Example 2), BE/BE against FE/FE and its mesh study."""

from __future__ import annotations

from hpfebe.scenes import plasticity, plasticity_fields as fields
from hpfebe.suite import Claim

difference = plasticity.run_difference


def _pct(v: float | None) -> str:
    return "not converged" if v is None else f"{v:.2%}"


def _pcts(values, hs=None) -> str:
    return ", ".join(map(_pct, values)) if hs is None else ", ".join(
        f"h={h:g}: {_pct(v)}" for h, v in zip(hs, values))


def _all_hold(parts: list) -> bool | None:
    """True when every part holds, None when one is undecided, else False."""
    return None if any(p is None for p in parts) else bool(all(parts))


def coupling_claim(prm, runs: dict, example: int) -> Claim:
    """FE/FE and FE/BE curves of ||dev sigma|| at X very close (at h_figure; every mesh
    and the FE/FE mesh differences beside)."""
    parts, ev, hs = [], [], prm.h_levels
    for th in prm.thetas:
        fe = [runs[(example, "FE", th, h, "bbar")] for h in hs]
        d = [difference(a, runs[(example, "BE", th, h, "bbar")]) for a, h in zip(fe, hs)]
        v = d[hs.index(prm.h_figure)]
        parts.append(None if v is None else v <= prm.close_tol)
        mesh = _pcts(plasticity.successive_differences(fe))
        ev.append(f"theta={th:g}: max rel. difference FE/FE vs FE/BE {_pcts(d, hs)}; FE/FE "
                  f"between successive meshes {mesh}")
    return Claim(f"FE/FE and FE/BE curves of ||dev sigma|| at X = "
                 f"{plasticity.POINT[example]} are very close (max relative difference "
                 f"<= {prm.close_tol:.0%} at h = {prm.h_figure:g})", _all_hold(parts),
                 "; ".join(ev), id="close")


def zone_claim(prm, runs: dict, example: int) -> Claim:
    """Similar plastic deformation in FE/FE and FE/BE after the last touch (L2
    difference of ||eps_p||, mismatch of the plastic zones; decided at h_figure)."""
    ok, ev = [], []
    for th in prm.thetas:
        for h in prm.h_levels:
            a, b = (runs[(example, st, th, h, "bbar")] for st in ("FE", "BE"))
            diff, mis = fields.zone_comparison(a, b, prm.zone_tol) if (
                a.converged and b.converged) else (None, None)
            if h == prm.h_figure:
                ok.append(None if diff is None else
                          diff <= prm.similar_tol and mis <= prm.similar_tol)
            ev.append(f"theta={th:g} h={h:g}: " + ("not converged" if diff is None else
                      f"||eps_p|| L2 difference {diff:.2%}, zone mismatch {mis:.2%}"))
    return Claim(f"similar plastic deformations in the work piece for FE and BE stamps "
                 f"(L2 difference of ||eps_p|| and plastic zone mismatch <= "
                 f"{prm.similar_tol:.0%} at h = {prm.h_figure:g})", _all_hold(ok),
                 "; ".join(ev), id="similar")


def dent_claim(prm, run: plasticity.Run) -> Claim:
    """A permanent dent under each stamp after unloading, relative to the lift."""
    lift, dents = prm.lift(run.example), fields.dent_depths(run)
    ev = [f"touch {k}: mean residual depth under the stamp {d:.3e} ({d / lift:.0%} of the "
          f"lift), deepest {deepest:.3e}" for k, d, deepest in dents]
    ev += [] if run.converged else [f"not converged: {run.touches[-1].reason}"]
    return Claim("the stamp leaves a permanent (plastic) dent in the work piece at each "
                 "touch (mean residual depth under the stamp > 50 % of the lift)",
                 bool(all(d > 0.5 * lift for _, d, _ in dents)) if run.converged else None,
                 "; ".join(ev), id="dent")


def plastic_claim(prm, run: plasticity.Run) -> Claim:
    """FE/FE: plastic deformation under every touch (max ||eps_p|| at each peak)."""
    peaks = [t.peak.fields["eps_p_norm"].max() if t.peak else None for t in run.touches]
    return Claim("plastic deformation under every touch of the stamp", bool(all(
        v is not None and v > prm.zone_tol for v in peaks)) if run.converged else None,
        "max ||eps_p|| at the peak of each touch: " + ", ".join(
            f"{v:.3e}" for v in peaks if v is not None)
        + ("" if run.converged else f"; not converged: {run.touches[-1].reason}"),
        id="plastic")


def mesh_claims(prm, runs: dict) -> list[Claim]:
    """Beyond the thesis, Example 2 FE/FE at thetas[0] on h_levels: the hypothesis that
    the B-bar curve at X converges (successive differences shrink; no rate, CHOICES)
    and the locking of fully integrated Q1 (its distance to B-bar grows with 1/h)."""
    th, hs = prm.thetas[0], prm.h_levels
    bb = [runs[(2, "FE", th, h, "bbar")] for h in hs]
    d = plasticity.successive_differences(bb)
    shrink = None if len(d) < 2 or None in d else all(b < a for a, b in zip(d, d[1:]))
    areas = [plasticity.plastic_area(r, prm.zone_tol) for r in bb]
    claims = [Claim(
        "the ||dev sigma|| curve at X converges under mesh refinement (differences "
        "between successive meshes of h_levels shrink; not a rate: a second mesh family, "
        "measured beside, does not contract, see the notes)", shrink,
        f"B-bar, successive meshes: {_pcts(d)}; plastic zone area "
        + ", ".join(f"h={h:g}: {a:.3f}" for h, a in zip(hs, areas)),
        kind="hypothesis", id="converges")]
    if prm.locking_study:
        full = [difference(r, runs[(2, "FE", th, h, "full")]) for r, h in zip(bb, hs)]
        grows = None if len(full) < 2 or None in full else all(
            b > a for a, b in zip(full, full[1:]))
        claims.append(Claim(
            "(beyond the thesis) fully integrated Q1 locks: its ||dev sigma|| curve at X "
            "departs further from the B-bar curve on the same mesh as h decreases", grows,
            f"fully integrated Q1 vs B-bar on the same mesh: {_pcts(full, hs)}; B-bar "
            f"between successive meshes: {_pcts(d)}", kind="beyond", id="locking"))
    return claims


def bebe_curve_claim(prm, runs: dict, bebe: dict) -> Claim:
    """BE/BE ||dev sigma|| at X and applied force along the load path against FE/FE on
    the same mesh (decides), FE/FE and FE/BE at h_figure, for every theta."""
    text = "the BE/BE curve shows qualitatively similar behaviour"
    if not bebe:
        return Claim(text, None, "BE/BE not run (bebe = false)", id="bebe")
    ok, ev = [], []
    for th, pair in bebe.items():
        bb = pair["BE/BE"]
        if not bb.converged:
            ok.append(None)                   # undecided: no converged BE/BE curve
            ev.append(f"theta={th:g}: BE/BE did not converge: {bb.touches[0].reason}")
            continue
        refs = {f"FE/FE h={bb.h:g}": pair["FE/FE"],
                f"FE/FE h={prm.h_figure:g}": runs[(2, "FE", th, prm.h_figure, "bbar")],
                f"FE/BE h={prm.h_figure:g}": runs[(2, "BE", th, prm.h_figure, "bbar")]}
        ds, df = ({k: difference(r, bb, c) for k, r in refs.items()} for c in (
            plasticity.Run.load_curve, lambda x: x.load_curve("force")))
        same = ds[f"FE/FE h={bb.h:g}"]
        ok.append(None if same is None else same <= prm.similar_tol)
        ev.append(f"theta={th:g}: max rel. difference of ||dev sigma|| at X, BE/BE vs " +
                  ", ".join(f"{k}: {_pct(v)}" for k, v in ds.items()) +
                  "; of the applied force: " + ", ".join(f"{k}: {_pct(v)}"
                                                         for k, v in df.items()))
    return Claim(f"{text} (max relative difference of ||dev sigma|| at X to FE/FE on the "
                 f"same mesh <= {prm.similar_tol:.0%}; theta = "
                 f"{', '.join(f'{t:g}' for t in bebe)}, h = {prm.bebe_h:g}; the finer FE "
                 f"curves show the mesh dependence of the value at X)", _all_hold(ok),
                 "; ".join(ev), id="bebe")


def bebe_mesh_claim(prm, runs: dict, study: dict) -> Claim:
    """Beyond the thesis: BE/BE converges under mesh refinement (bebe_h_levels,
    thetas[0]): successive differences per halving of h shrink; FE/FE beside."""
    hs = list(study) or list(prm.bebe_h_levels)
    text = ("(beyond the thesis) BE/BE converges under mesh refinement, h = "
            + ", ".join(f"{h:g}" for h in hs) + f", theta = {prm.thetas[0]:g}: the "
            "successive differences of ||dev sigma|| at X along the load path, of the "
            "applied force and of the plastic zone area, per halving of h (difference / "
            "log2(h_i / h_i+1)), shrink")
    bad = [f"{k} h={h:g}: {r.touches[-1].reason}" for h, p in study.items()
           for k, r in p.items() if not r.converged or r.touches[0].peak is None]
    if not study or bad:
        return Claim(text, None, "did not converge: " + "; ".join(bad) if bad else
                     "BE/BE mesh study not run (bebe = false or fewer than two "
                     "bebe_h_levels)", kind="beyond", id="bebe_study")
    bb, ff = (fields.mesh_study_differences(study, k, prm.zone_tol)
              for k in ("BE/BE", "FE/FE"))
    fmt = lambda x, spec=".2%": ", ".join(format(v, spec) for v in x)    # noqa: E731
    parts = ("||dev sigma|| at X", "dev"), ("force", "force"), ("plastic zone area", "zone")
    ev = [f"{name}: successive differences (raw / per halving) " + ", ".join(
        f"{q} {fmt(r['raw'][k])} / {fmt(r['scaled'][k])}" for q, k in parts) +
        f"; at full lift ||dev sigma||_X {fmt(r['peak_dev'], '.4g')}, force "
        f"{fmt(r['peak_force'], '.4g')}, zone area {fmt(r['area'], '.4g')}"
        for name, r in (("BE/BE", bb), ("FE/FE same meshes", ff))]
    ev.append("BE/BE vs FE/FE on the same mesh (||dev sigma|| / force): " + ", ".join(
        f"h={h:g}: {a:.2%} / {b:.2%}"
        for h, (a, b) in zip(hs, fields.same_mesh_differences(study))))
    fe = [runs[(2, "FE", prm.thetas[0], h, "bbar")] for h in prm.h_levels]
    ev.append("FE/FE on h_levels " + ", ".join(f"{h:g}" for h in prm.h_levels) +
              f": successive ||dev sigma|| differences "
              f"{_pcts(plasticity.successive_differences(fe))}")
    shrinks = lambda x: all(b < a or b == 0 for a, b in zip(x, x[1:]))   # noqa: E731
    holds = None if len(hs) < 3 else bool(all(shrinks(bb["scaled"][k])
                                              for k in ("dev", "force", "zone")))
    return Claim(text, holds, "; ".join(ev), kind="beyond", id="bebe_study")


def bebe_field_claims(prm, bebe: dict) -> tuple[Claim, Claim]:
    """Deformed top surface and plastic strain of BE/BE against FE/FE on the same grid
    at full lift, for every theta."""
    t_mesh = (f"BE/BE deformed mesh qualitatively as FE/FE (top surface u_y at full lift "
              f"within {prm.similar_tol:.0%} of FE/FE on the same mesh)")
    t_eps = (f"BE/BE ||eps_p|| qualitatively as FE/FE (L2 difference and plastic zone "
             f"mismatch <= {prm.similar_tol:.0%} against FE/FE on the same mesh)")
    if not bebe:
        return (Claim(t_mesh, None, "BE/BE not run", id="bebe_mesh"),
                Claim(t_eps, None, "BE/BE not run", id="bebe_eps"))
    ok_u, ok_e, ev_u, ev_e, tol = [], [], [], [], prm.similar_tol
    for th, pair in bebe.items():
        if not all(r.converged for r in pair.values()):   # undecided: nothing to compare
            why = "; ".join(f"theta={th:g}: {k} failed: {r.touches[-1].reason}"
                            for k, r in pair.items() if not r.converged)
            ok_u.append(None), ok_e.append(None), ev_u.append(why), ev_e.append(why)
            continue
        d, h = fields.bebe_field_differences(pair, prm.zone_tol), pair["BE/BE"].h
        ok_u.append(d.u_top <= tol)
        ok_e.append(d.eps_l2 <= tol and d.zone_mismatch <= tol)
        ev_u.append(f"theta={th:g}, h = {h:g}: max |u_y(BE/BE) - u_y(FE/FE)| / "
                    f"max |u_y(FE/FE)| on the top surface = {d.u_top:.2%}")
        ev_e.append(f"theta={th:g}, h = {h:g}, element means: ||eps_p|| L2 difference "
                    f"{d.eps_l2:.2%}, zone mismatch {d.zone_mismatch:.2%}, max ||eps_p|| "
                    f"BE/BE {d.eps_max_bebe:.3e} vs FE/FE {d.eps_max_fe:.3e}")
    return (Claim(t_mesh, _all_hold(ok_u), "; ".join(ev_u), id="bebe_mesh"),
            Claim(t_eps, _all_hold(ok_e), "; ".join(ev_e), id="bebe_eps"))
