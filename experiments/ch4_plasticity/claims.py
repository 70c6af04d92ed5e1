"""The claims of Figures 4.1-4.12: FE/FE and FE/BE close, similar plastic zones, the
dent, the mesh study and locking (Example 2), BE/BE against FE/FE and its mesh study."""

from __future__ import annotations

import numpy as np

from hpfebe.scenes import curve_difference, element_areas, field_difference, plastic_zone, \
    zone_mismatch
from hpfebe.scenes import plasticity
from hpfebe.suite import Claim

from .scene import Params


def _pct(v: float | None) -> str:
    return "not converged" if v is None else f"{v:.2%}"


def coupling_claim(prm: Params, runs: dict, example: int) -> Claim:
    """FE/FE and FE/BE curves of ||dev sigma|| at X very close (max relative difference
    along the load path, at h_figure and on every mesh), beside the mesh differences."""
    parts, ev = [], []
    for th in prm.thetas:
        d = {h: plasticity.run_difference(runs[(example, "FE", th, h, "bbar")],
                                  runs[(example, "BE", th, h, "bbar")])
             for h in prm.h_levels}
        hs = prm.h_levels
        mesh = [plasticity.run_difference(runs[(example, "FE", th, hs[i + 1], "bbar")],
                                  runs[(example, "FE", th, hs[i], "bbar")])
                for i in range(len(hs) - 1)]
        v = d[prm.h_figure]
        parts.append(None if v is None else v <= prm.close_tol)
        ev.append(f"theta={th:g}: max rel. difference FE/FE vs FE/BE "
                  + ", ".join(f"h={h:g}: {_pct(v)}" for h, v in d.items())
                  + "; FE/FE between successive meshes "
                  + ", ".join(_pct(v) for v in mesh))
    return Claim(f"FE/FE and FE/BE curves of ||dev sigma|| at X = "
                 f"{plasticity.POINT[example]} are very "
                 f"close (max relative difference <= {prm.close_tol:.0%} at h = "
                 f"{prm.h_figure:g})", _all_hold(parts), "; ".join(ev), id="close")


def zone_claim(prm: Params, runs: dict, example: int) -> Claim:
    """Similar plastic deformation in FE/FE and FE/BE: L2 difference of ||eps_p|| and
    mismatch of the plastic zones (same work piece mesh) after the last touch."""
    ok, ev = [], []
    for th in prm.thetas:
        for h in prm.h_levels:
            a, b = runs[(example, "FE", th, h, "bbar")], runs[(example, "BE", th, h, "bbar")]
            if not (a.converged and b.converged):
                if h == prm.h_figure:
                    ok.append(None)
                ev.append(f"theta={th:g} h={h:g}: not converged")
                continue
            fa = a.fe.fields()["eps_p_norm_mean"]
            fb = b.fe.fields()["eps_p_norm_mean"]
            diff = field_difference(a.fe, fa, fb)
            mis = zone_mismatch(a.fe, plastic_zone(a.fe, fa, prm.zone_tol),
                                plastic_zone(b.fe, fb, prm.zone_tol))
            if h == prm.h_figure:
                ok.append(diff <= prm.similar_tol and mis <= prm.similar_tol)
            ev.append(f"theta={th:g} h={h:g}: ||eps_p|| L2 difference {diff:.2%}, zone "
                      f"mismatch {mis:.2%}")
    return Claim(f"similar plastic deformations in the work piece for FE and BE stamps "
                 f"(L2 difference of ||eps_p|| and plastic zone mismatch <= "
                 f"{prm.similar_tol:.0%} at h = {prm.h_figure:g})", _all_hold(ok),
                 "; ".join(ev), id="similar")


def dent_claim(prm: Params, run: plasticity.Run) -> Claim:
    """The stamp leaves a permanent dent: residual top displacement under each stamp
    after unloading, relative to the lift."""
    fe, ev, ok = run.fe, [], []
    u_total = prm.ex1_u if run.example == 1 else prm.ex2_u
    top = fe.elastic.boundary_vertices("top")
    x = fe.mesh.p[0, top]
    for tr, box in zip(run.touches, plasticity.STAMPS[run.example]):
        uy = fe.elastic.nodal_displacement(tr.u_work)[1, top]
        under = (x >= box[0]) & (x <= box[1])
        dent = float(-uy[under].mean())
        ok.append(dent > 0.5 * u_total)
        ev.append(f"touch {tr.records[0].touch}: mean residual depth under the stamp "
                  f"{dent:.3e} ({dent / u_total:.0%} of the lift), deepest "
                  f"{-uy[under].min():.3e}")
    if not run.converged:
        ev.append(f"not converged: {run.touches[-1].reason}")
    return Claim("the stamp leaves a permanent (plastic) dent in the work piece at each "
                 "touch (mean residual depth under the stamp > 50 % of the lift)",
                 bool(all(ok)) if run.converged else None, "; ".join(ev), id="dent")


def mesh_claims(prm: Params, runs: dict) -> list[Claim]:
    """Beyond the thesis, Example 2 FE/FE at thetas[0] on h_levels: the hypothesis that
    the B-bar curve of ||dev sigma|| at X converges (its successive differences shrink;
    two differences are no rate and a second mesh family does not contract, CHOICES),
    and the locking of fully integrated Q1 (its distance to the B-bar curve on the same
    mesh grows under refinement instead of shrinking)."""
    th, hs = prm.thetas[0], prm.h_levels
    bb = [runs[(2, "FE", th, h, "bbar")] for h in hs]
    d = [plasticity.run_difference(bb[i + 1], bb[i]) for i in range(len(hs) - 1)]
    shrink = (None if len(d) < 2 or None in d else
              all(d[i + 1] < d[i] for i in range(len(d) - 1)))
    areas = [float(element_areas(r.fe)[plastic_zone(r.fe, r.fe.fields()["eps_p_norm_mean"],
                                                     prm.zone_tol)].sum()) for r in bb]
    claims = [Claim(
        "the ||dev sigma|| curve at X converges under mesh refinement (differences "
        "between successive meshes of h_levels shrink; not a rate: a second mesh family, "
        "measured beside, does not contract, see the notes)", shrink,
        "B-bar, successive meshes: " + ", ".join(map(_pct, d)) + "; plastic zone area "
        + ", ".join(f"h={h:g}: {a:.3f}" for h, a in zip(hs, areas)),
        kind="hypothesis", id="converges")]
    if prm.locking_study:
        full = [plasticity.run_difference(r, runs[(2, "FE", th, h, "full")])
                for r, h in zip(bb, hs)]
        grows = None if len(full) < 2 or None in full else all(
            b > a for a, b in zip(full, full[1:]))
        claims.append(Claim(
            "(beyond the thesis) fully integrated Q1 locks: its ||dev sigma|| curve at X "
            "departs further from the B-bar curve on the same mesh as h decreases",
            grows, "fully integrated Q1 vs B-bar on the same mesh: " + ", ".join(
                f"h={h:g}: {_pct(v)}" for h, v in zip(hs, full)) + "; B-bar between "
            "successive meshes: " + ", ".join(map(_pct, d)), kind="beyond", id="locking"))
    return claims


def _all_hold(parts: list) -> bool | None:
    """True when every part holds, None when one is undecided, else False."""
    return None if any(p is None for p in parts) else bool(all(parts))


def bebe_curve_claim(prm: Params, runs: dict, bebe: dict) -> Claim:
    """BE/BE ||dev sigma|| at X (and the applied force) along the load path against
    FE/FE on the same mesh, FE/FE and FE/BE at h_figure: max relative differences, for
    every theta (``bebe`` from :func:`bebe_runs`)."""
    text = "the BE/BE curve shows qualitatively similar behaviour"
    if not bebe:
        return Claim(text, None, "BE/BE not run (bebe = false)", id="bebe")
    ok, ev = [], []
    force = lambda r: r.load_curve("force")                   # noqa: E731
    for th, pair in bebe.items():
        bb = pair["BE/BE"]
        if not bb.converged:
            ok.append(None)                   # undecided: no converged BE/BE curve
            ev.append(f"theta={th:g}: BE/BE did not converge: {bb.touches[0].reason}")
            continue
        refs = {f"FE/FE h={bb.h:g}": pair["FE/FE"],
                f"FE/FE h={prm.h_figure:g}": runs[(2, "FE", th, prm.h_figure, "bbar")],
                f"FE/BE h={prm.h_figure:g}": runs[(2, "BE", th, prm.h_figure, "bbar")]}
        ds = {k: plasticity.run_difference(r, bb, plasticity.Run.load_curve)
              for k, r in refs.items()}
        df = {k: plasticity.run_difference(r, bb, force) for k, r in refs.items()}
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


def _plastic_area(run: plasticity.Run, zone_tol: float) -> float:
    """Area of the plastic zone at the peak of the first touch: BE/BE cells or FE
    elements with (mean) ||eps_p|| > zone_tol."""
    eps = run.touches[0].peak.fields["eps_p_norm"]
    areas = run.fe.cells.areas if run.stamp == "BE/BE" else element_areas(run.fe)
    return float(areas[eps > zone_tol].sum())


def _successive(prm: Params, study: dict, name: str) -> dict:
    """Successive differences of one discretisation over the meshes of ``study``: max
    relative difference of the ||dev sigma|| and force curves (relative to the finer
    mesh's peak), relative difference of the plastic zone area, and the same divided by
    log2(h_i / h_i+1) (per halving of h: the meshes are not refined by a constant ratio;
    a sequence converging at any positive order has shrinking scaled differences)."""
    hs, rs = list(study), [study[h][name] for h in study]
    area = [_plastic_area(r, prm.zone_tol) for r in rs]
    d = {"dev": [curve_difference(rs[i + 1].load_curve(), rs[i].load_curve())
                 for i in range(len(hs) - 1)],
         "force": [curve_difference(rs[i + 1].load_curve("force"),
                                    rs[i].load_curve("force")) for i in range(len(hs) - 1)],
         "zone": [abs(area[i + 1] - area[i]) / max(area[i + 1], 1e-300)
                  for i in range(len(hs) - 1)]}
    per = [np.log2(hs[i] / hs[i + 1]) for i in range(len(hs) - 1)]
    return dict(raw=d, scaled={k: [v / q for v, q in zip(x, per)] for k, x in d.items()},
                area=area, peak_dev=[float(r.load_curve()[-1]) for r in rs],
                peak_force=[float(r.load_curve("force")[-1]) for r in rs])


def _shrinks(x: list) -> bool:
    return all(b < a or b == 0 for a, b in zip(x, x[1:]))


def bebe_mesh_claim(prm: Params, runs: dict, study: dict) -> Claim:
    """Beyond the thesis: BE/BE under mesh refinement (bebe_h_levels, thetas[0]): the
    successive differences (per halving of h) of the ||dev sigma|| curve at X, of the
    applied force and of the plastic zone area shrink; beside them FE/FE on the same
    meshes, FE/FE on h_levels and BE/BE vs FE/FE on each mesh (``study`` from
    :func:`bebe_mesh_study`)."""
    hs = list(study) or list(prm.bebe_h_levels)
    text = ("(beyond the thesis) BE/BE converges under mesh refinement, h = "
            + ", ".join(f"{h:g}" for h in hs) + f", theta = {prm.thetas[0]:g}: the "
            "successive differences of ||dev sigma|| at X along the load path, of the "
            "applied force and of the plastic zone area, per halving of h (difference / "
            "log2(h_i / h_i+1)), shrink")
    if not study:
        return Claim(text, None, "BE/BE mesh study not run (bebe = false or fewer than "
                                 "two bebe_h_levels)", kind="beyond", id="bebe_study")
    bad = [f"{k} h={h:g}: {r.touches[-1].reason}" for h, p in study.items()
           for k, r in p.items() if not r.converged or r.touches[0].peak is None]
    if bad:
        return Claim(text, None, "did not converge: " + "; ".join(bad), kind="beyond",
                     id="bebe_study")
    bb, ff = _successive(prm, study, "BE/BE"), _successive(prm, study, "FE/FE")
    pct = lambda x: ", ".join(f"{v:.2%}" for v in x)            # noqa: E731
    num = lambda x: ", ".join(f"{v:.4g}" for v in x)            # noqa: E731
    ev = []
    for name, r in (("BE/BE", bb), ("FE/FE same meshes", ff)):
        ev.append(f"{name}: successive differences (raw / per halving) ||dev sigma|| at X "
                  f"{pct(r['raw']['dev'])} / {pct(r['scaled']['dev'])}, force "
                  f"{pct(r['raw']['force'])} / {pct(r['scaled']['force'])}, plastic zone "
                  f"area {pct(r['raw']['zone'])} / {pct(r['scaled']['zone'])}; at full "
                  f"lift ||dev sigma||_X {num(r['peak_dev'])}, force "
                  f"{num(r['peak_force'])}, zone area {num(r['area'])}")
    same = [(curve_difference(p["FE/FE"].load_curve(), p["BE/BE"].load_curve()),
             curve_difference(p["FE/FE"].load_curve("force"),
                              p["BE/BE"].load_curve("force"))) for p in study.values()]
    ev.append("BE/BE vs FE/FE on the same mesh (||dev sigma|| / force): " + ", ".join(
        f"h={h:g}: {a:.2%} / {b:.2%}" for h, (a, b) in zip(hs, same)))
    th, fh = prm.thetas[0], prm.h_levels
    fe = [runs[(2, "FE", th, h, "bbar")] for h in fh]
    ev.append("FE/FE on h_levels " + ", ".join(f"{h:g}" for h in fh) + ": successive "
              "||dev sigma|| differences " + ", ".join(
                  _pct(plasticity.run_difference(fe[i + 1], fe[i])) for i in range(len(fh) - 1)))
    holds = None if len(hs) < 3 else bool(all(_shrinks(bb["scaled"][k])
                                              for k in ("dev", "force", "zone")))
    return Claim(text, holds, "; ".join(ev), kind="beyond", id="bebe_study")


def bebe_field_claims(prm: Params, bebe: dict) -> tuple[Claim, Claim]:
    """Deformed top surface and plastic strain of BE/BE against FE/FE on the same grid
    at full lift, for every theta (``bebe`` from :func:`bebe_runs`)."""
    t_mesh = (f"BE/BE deformed mesh qualitatively as FE/FE (top surface u_y at full lift "
              f"within {prm.similar_tol:.0%} of FE/FE on the same mesh)")
    t_eps = (f"BE/BE ||eps_p|| qualitatively as FE/FE (L2 difference and plastic zone "
             f"mismatch <= {prm.similar_tol:.0%} against FE/FE on the same mesh)")
    if not bebe:
        return (Claim(t_mesh, None, "BE/BE not run", id="bebe_mesh"),
                Claim(t_eps, None, "BE/BE not run", id="bebe_eps"))
    ok_u, ok_e, ev_u, ev_e = [], [], [], []
    for th, pair in bebe.items():
        bb, ff = pair["BE/BE"], pair["FE/FE"]
        if not (bb.converged and ff.converged):         # undecided: nothing to compare
            why = "; ".join(f"theta={th:g}: {k} failed: {r.touches[-1].reason}"
                            for k, r in pair.items() if not r.converged)
            ok_u.append(None), ok_e.append(None), ev_u.append(why), ev_e.append(why)
            continue
        w, eb, ef, ub, uf = plasticity.bebe_vs_fe(pair)
        du = float(np.abs(ub - uf).max() / np.abs(uf).max())
        l2 = float(np.sqrt(w @ (eb - ef) ** 2 / (w @ ef ** 2)))
        zb, zf = eb > prm.zone_tol, ef > prm.zone_tol
        mis = float(w[zb ^ zf].sum() / max(w[zb | zf].sum(), 1e-300))
        ok_u.append(du <= prm.similar_tol)
        ok_e.append(l2 <= prm.similar_tol and mis <= prm.similar_tol)
        ev_u.append(f"theta={th:g}, h = {bb.h:g}: max |u_y(BE/BE) - u_y(FE/FE)| / "
                    f"max |u_y(FE/FE)| on the top surface = {du:.2%}")
        ev_e.append(f"theta={th:g}, h = {bb.h:g}, element means: ||eps_p|| L2 difference "
                    f"{l2:.2%}, zone mismatch {mis:.2%}, max ||eps_p|| BE/BE {eb.max():.3e} "
                    f"vs FE/FE {ef.max():.3e}")
    return (Claim(t_mesh, _all_hold(ok_u), "; ".join(ev_u), id="bebe_mesh"),
            Claim(t_eps, _all_hold(ok_e), "; ".join(ev_e), id="bebe_eps"))
