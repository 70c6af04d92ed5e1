"""The fields of the stamping runs of Section 4.2.7 (:mod:`.plasticity`, Figures
4.1-4.12) compared, measured and drawn: the permanent dent under each stamp, the plastic
zones and ||eps_p|| of two discretisations on one mesh, the BE/BE work piece against
FE/FE on the same grid, successive differences of a mesh study, the deformed bodies of
the figures and their VTU exports.

Differences of curves are :func:`hpfebe.scenes.stamping.curve_difference` (max relative
difference along the load path, relative to the first curve's peak), of element fields
:func:`~hpfebe.scenes.stamping.field_difference` (relative L2) and of plastic zones
:func:`~hpfebe.scenes.stamping.zone_mismatch` (|A xor B| / |A or B|).
"""

from __future__ import annotations

from dataclasses import dataclass

import meshio
import numpy as np

from ..io import fe_vtu
from .plasticity import STAMPS, WORK, Run
from .stamping import (curve_difference, element_areas, field_difference, plastic_zone,
                       stamp_interior, zone_mismatch)


# --------------------------------------------------------------------------- comparisons
def dent_depths(run: Run) -> list[tuple[int, float, float]]:
    """The permanent dent of each touch: (touch, mean residual depth -u_y of the work
    piece's top under the stamp after unloading, deepest point)."""
    fe = run.fe
    top = fe.elastic.boundary_vertices("top")
    x = fe.mesh.p[0, top]
    out = []
    for tr, box in zip(run.touches, STAMPS[run.example]):
        uy = fe.elastic.nodal_displacement(tr.u_work)[1, top]
        under = (x >= box[0]) & (x <= box[1])
        out.append((tr.records[0].touch, float(-uy[under].mean()), -uy[under].min()))
    return out


def zone_comparison(a: Run, b: Run, zone_tol: float) -> tuple[float, float]:
    """Two runs on one work piece mesh after their last touch: (relative L2 difference
    of the element mean ||eps_p||, mismatch of the plastic zones ||eps_p|| > zone_tol)."""
    fa = a.fe.fields()["eps_p_norm_mean"]
    fb = b.fe.fields()["eps_p_norm_mean"]
    diff = field_difference(a.fe, fa, fb)
    mis = zone_mismatch(a.fe, plastic_zone(a.fe, fa, zone_tol),
                        plastic_zone(b.fe, fb, zone_tol))
    return diff, mis


def bebe_vs_fe(bebe: dict):
    """BE/BE fields and top displacement against FE/FE on the same grid at the peak
    (``bebe``: {"BE/BE": Run, "FE/FE": Run}): (FE element areas, BE ||eps_p|| averaged
    over the cells in each FE element (area weights; every cell lies in one element),
    FE element mean ||eps_p||, BE top u_y, FE top u_y)."""
    be, fe = bebe["BE/BE"].fe, bebe["FE/FE"].fe
    el = np.array([fe.elements_at(c)[0] for c in be.cells.centroids])
    sb, sf = bebe["BE/BE"].touches[0].peak, bebe["FE/FE"].touches[0].peak
    w = np.bincount(el, be.cells.areas, minlength=fe.nel)
    eb = np.bincount(el, be.cells.areas * sb.fields["eps_p_norm"], minlength=fe.nel) / w
    ef = sf.fields["eps_p_norm"]
    nodes = be.cells.nodes
    top = np.flatnonzero(np.isclose(nodes[:, 1], WORK[3]))
    xf = fe.mesh.p[:, fe.elastic.boundary_vertices("top")]
    uf = fe.elastic.nodal_displacement(sf.u_work)[1, fe.elastic.boundary_vertices("top")]
    ufe = np.interp(nodes[top, 0], xf[0][np.argsort(xf[0])], uf[np.argsort(xf[0])])
    return w, eb, ef, sb.fields["node_u"][top, 1], ufe


@dataclass(frozen=True)
class FieldDifferences:
    """BE/BE against FE/FE on the same grid at full lift: ``u_top`` = max |u_y(BE/BE) -
    u_y(FE/FE)| / max |u_y(FE/FE)| on the top surface, ``eps_l2`` = relative L2
    difference of the element mean ||eps_p||, ``zone_mismatch`` of the plastic zones,
    the maxima ``eps_max_bebe``, ``eps_max_fe`` of ||eps_p||."""

    u_top: float
    eps_l2: float
    zone_mismatch: float
    eps_max_bebe: float
    eps_max_fe: float


def bebe_field_differences(bebe: dict, zone_tol: float) -> FieldDifferences:
    """:class:`FieldDifferences` of a pair {"BE/BE": Run, "FE/FE": Run}
    (:func:`bebe_vs_fe`; plastic zones: ||eps_p|| > zone_tol)."""
    w, eb, ef, ub, uf = bebe_vs_fe(bebe)
    zb, zf = eb > zone_tol, ef > zone_tol
    return FieldDifferences(
        u_top=float(np.abs(ub - uf).max() / np.abs(uf).max()),
        eps_l2=float(np.sqrt(w @ (eb - ef) ** 2 / (w @ ef ** 2))),
        zone_mismatch=float(w[zb ^ zf].sum() / max(w[zb | zf].sum(), 1e-300)),
        eps_max_bebe=eb.max(), eps_max_fe=ef.max())


def peak_plastic_area(run: Run, zone_tol: float) -> float:
    """Area of the plastic zone at the peak of the first touch: BE/BE cells or FE
    elements with (mean) ||eps_p|| > zone_tol."""
    eps = run.touches[0].peak.fields["eps_p_norm"]
    areas = run.fe.cells.areas if run.stamp == "BE/BE" else element_areas(run.fe)
    return float(areas[eps > zone_tol].sum())


def mesh_study_differences(study: dict, name: str, zone_tol: float) -> dict:
    """Successive differences of one discretisation (``name``: "BE/BE" or "FE/FE") over
    the meshes of a mesh study {h: {name: Run}}: ``raw`` = max relative difference of
    the ||dev sigma|| and force curves (relative to the finer mesh's peak) and relative
    difference of the plastic zone area; ``scaled`` = the same divided by
    log2(h_i / h_i+1) (per halving of h: the meshes are not refined by a constant ratio;
    a sequence converging at any positive order has shrinking scaled differences);
    ``area``, ``peak_dev``, ``peak_force`` at full lift on each mesh."""
    hs, rs = list(study), [study[h][name] for h in study]
    area = [peak_plastic_area(r, zone_tol) for r in rs]
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


def same_mesh_differences(study: dict) -> list[tuple[float, float]]:
    """BE/BE against FE/FE on each mesh of a mesh study: (max relative difference of the
    ||dev sigma|| curve at X, of the force curve)."""
    return [(curve_difference(p["FE/FE"].load_curve(), p["BE/BE"].load_curve()),
             curve_difference(p["FE/FE"].load_curve("force"),
                              p["BE/BE"].load_curve("force"))) for p in study.values()]


# --------------------------------------------------------------------------- drawing
def stamp_grid(stamp, h: float) -> tuple[int, int]:
    """Cells of the auxiliary FE-like grid of a BE stamp (mesh size h); (0, 0) for an FE
    stamp (its own mesh)."""
    if hasattr(stamp, "mesh") and hasattr(stamp.mesh, "a"):
        lo, hi = stamp.mesh.a.min(axis=0), stamp.mesh.a.max(axis=0)
        return (max(1, int(round((hi[0] - lo[0]) / h))),
                max(1, int(round((hi[1] - lo[1]) / h))))
    return (0, 0)


def deformed_bodies(run: Run, snap, magnification: float, h: float):
    """Work piece and stamp of a snapshot displaced by ``magnification`` x u: (work
    piece points, its cells (FE elements or BE/BE cells), stamp points, its cells; a BE
    stamp on its auxiliary grid of size h, :func:`stamp_grid`)."""
    mag = magnification
    if run.stamp == "BE/BE":
        pw, cells = run.fe.cells.nodes + mag * snap.fields["node_u"], run.fe.cells.cells
    else:
        pw = run.fe.mesh.p.T + mag * run.fe.elastic.nodal_displacement(snap.u_work).T
        cells = run.fe.mesh.t.T
    ps, us, cs = stamp_interior(snap.stamp, snap.u_stamp, *stamp_grid(snap.stamp, h))
    return pw, cells, ps + mag * us, cs


def touch_exports(run: Run, tag: str, h: float) -> dict:
    """VTU meshes of the work piece (displacement, element fields ||eps_p||,
    ||dev sigma||, alpha) and the stamp (displacement; a BE stamp on its auxiliary grid
    of size h) at the peak of every touch: {f"{tag}_touch{k}_work" / "_stamp": Mesh}."""
    out = {}
    for t in run.touches:
        if t.peak is None:
            continue
        s = t.peak
        wp = fe_vtu(run.fe.mesh, {"u": run.fe.elastic.nodal_displacement(s.u_work).T})
        wp.cell_data = {k: [np.asarray(v, dtype=float)] for k, v in s.fields.items()}
        out[f"{tag}_touch{s.touch}_work"] = wp
        pts, disp, cells = stamp_interior(s.stamp, s.u_stamp, *stamp_grid(s.stamp, h))
        z = np.zeros((len(pts), 1))
        out[f"{tag}_touch{s.touch}_stamp"] = meshio.Mesh(
            np.hstack([pts, z]), [("quad", np.asarray(cells))],
            point_data={"u": np.hstack([disp, z])})
    return out


def bebe_exports(bebe: dict) -> dict:
    """VTU meshes of the BE/BE work piece at full lift on its cell grid, for every theta
    of ``bebe`` ({theta: {"BE/BE": Run, ...}}): node displacement (representation
    formula) and the cell fields."""
    out = {}
    for th, pair in bebe.items():
        snap = pair["BE/BE"].touches[0].peak
        if snap is None:
            continue
        cx = pair["BE/BE"].fe.cells
        z = np.zeros((len(cx.nodes), 1))
        kind = "triangle" if cx.cells.shape[1] == 3 else "quad"
        cells = {k: [np.asarray(v, dtype=float)] for k, v in snap.fields.items()
                 if k != "node_u"}
        out[f"BEBE_theta{th:g}_touch1_work"] = meshio.Mesh(
            np.hstack([cx.nodes, z]), [(kind, np.asarray(cx.cells))],
            point_data={"u": np.hstack([snap.fields["node_u"], z])}, cell_data=cells)
    return out
