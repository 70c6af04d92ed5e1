"""The figures and VTU exports of Figures 4.1-4.12: the deformed work piece and stamp
(x magnification) with ||eps_p||, the BE/BE cell grid, ||dev sigma|| at X against the
applied force."""

from __future__ import annotations

import meshio
import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from hpfebe.io import fe_vtu
from hpfebe.scenes import stamp_interior
from hpfebe.scenes import plasticity
from hpfebe.suite import new_figure, style_axes

from .scene import Params


def _polys(p: np.ndarray, cells: np.ndarray) -> np.ndarray:
    return p[cells]                                        # (ncells, nv, 2)


def _draw(ax, prm: Params, snap, fe, field: str | None, vmax: float):
    """Deformed (x magnification) work piece and stamp; cells coloured by ``field``."""
    mag = prm.magnification
    pw = fe.mesh.p.T + mag * fe.elastic.nodal_displacement(snap.u_work).T
    ps, us, cs = stamp_interior(snap.stamp, snap.u_stamp, *_grid(snap.stamp, prm))
    kw = dict(edgecolors="k", linewidths=0.2)
    if field is None:
        ax.add_collection(PolyCollection(_polys(pw, fe.mesh.t.T), facecolors="lightsteelblue",
                                         **kw))
        ax.add_collection(PolyCollection(_polys(ps + mag * us, cs), facecolors="wheat", **kw))
        pc = None
    else:
        pc = PolyCollection(_polys(pw, fe.mesh.t.T), array=snap.fields[field],
                            cmap="jet", **kw)
        pc.set_clim(0.0, vmax)
        ax.add_collection(pc)
        st = PolyCollection(_polys(ps + mag * us, cs), array=np.zeros(len(cs)), cmap="jet",
                            **kw)
        st.set_clim(0.0, vmax)
        ax.add_collection(st)
    _frame(ax, pw, ps + mag * us)
    return pc


def _frame(ax, *points):
    """Equal-aspect limits holding every deformed body (the magnified displacement moves
    the work piece's sides beyond its box) with a margin."""
    p = np.vstack(points)
    lo, hi = p.min(axis=0), p.max(axis=0)
    pad = 0.05 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")


def _grid(stamp, prm: Params):
    """Cells of the auxiliary FE-like grid of a BE stamp (mesh size h_figure)."""
    if hasattr(stamp, "mesh") and hasattr(stamp.mesh, "a"):
        lo, hi = stamp.mesh.a.min(axis=0), stamp.mesh.a.max(axis=0)
        return (max(1, int(round((hi[0] - lo[0]) / prm.h_figure))),
                max(1, int(round((hi[1] - lo[1]) / prm.h_figure))))
    return (0, 0)


def field_figure(prm: Params, run: plasticity.Run, field: str | None, title: str) -> Figure:
    snaps = [t.peak for t in run.touches if t.peak is not None]
    fig, axes = new_figure((5.0 * len(snaps), 3.9), 1, len(snaps), squeeze=False)
    axes = axes[0]
    vmax = max(float(s.fields["eps_p_norm"].max()) for s in snaps) if field else 0.0
    for ax, s in zip(axes, snaps):
        pc = _draw(ax, prm, s, run.fe, field, vmax or 1.0)
        ax.set_title(f"{title}, touch {s.touch} at full lift (x{prm.magnification:g})",
                     fontsize=9)
    if pc is not None:
        fig.colorbar(pc, ax=axes.tolist(), shrink=0.7, label="||eps_p||")
    return fig


def bebe_figure(prm: Params, bebe: dict, field: str | None, title: str) -> Figure:
    """BE/BE at full lift: the work piece's cell grid deformed by the displacement at its
    nodes (representation formula, x magnification), the BE stamp on its auxiliary grid;
    cells coloured by ``field``; ``bebe``: one theta's {"BE/BE": Run, "FE/FE": Run}."""
    snap = bebe["BE/BE"].touches[0].peak if bebe else None
    if snap is None:
        return missing_figure("BE/BE: no converged state (see the claims)")
    be, mag = bebe["BE/BE"].fe, prm.magnification
    fig, ax = new_figure((5.5, 4.0))
    pw = be.cells.nodes + mag * snap.fields["node_u"]
    ps, us, cs = stamp_interior(snap.stamp, snap.u_stamp, *_grid(snap.stamp, prm))
    kw = dict(edgecolors="k", linewidths=0.2)
    if field is None:
        ax.add_collection(PolyCollection(pw[be.cells.cells], facecolors="lightsteelblue",
                                         **kw))
        ax.add_collection(PolyCollection(ps[cs] + mag * us[cs], facecolors="wheat", **kw))
    else:
        vals = snap.fields[field]
        pc = PolyCollection(pw[be.cells.cells], array=vals, cmap="jet", **kw)
        pc.set_clim(0.0, float(vals.max()) or 1.0)
        ax.add_collection(pc)
        ax.add_collection(PolyCollection(ps[cs] + mag * us[cs], facecolors="white", **kw))
        fig.colorbar(pc, ax=ax, shrink=0.7,
                     label="||" + field.removesuffix("_norm") + "||")
    _frame(ax, pw, ps + mag * us)
    ax.set_title(f"{title}, h = {bebe['BE/BE'].h:g}, full lift (x{mag:g})", fontsize=9)
    return fig


def curve_figure(prm: Params, runs: dict, example: int, bebe: dict | None = None,
                 study: dict | None = None) -> Figure:
    """||dev sigma|| at X against the applied force: FE/FE, FE/BE (and BE/BE) per theta;
    last panel: the FE/FE mesh study (B-bar, full Q1) and the BE/BE mesh study."""
    th0 = prm.thetas
    ncol = len(th0) + 1
    fig, axes = new_figure((4.8 * ncol, 4.2), 1, ncol)
    for ax, th in zip(axes, th0):
        for st, style, kw in (("FE", "-o", dict(ms=6, mfc="none")), ("BE", "--s",
                                                                      dict(ms=3))):
            r = runs[(example, st, th, prm.h_figure, "bbar")]
            start = (0.0, 0.0)
            for t in r.touches:
                load = [x for x in t.records if x.phase == "load"]
                ax.plot([start[0]] + [x.force for x in load],
                        [start[1]] + [x.dev_sigma_X for x in load], style, **kw,
                        label=f"FE/{st}, touch {t.records[0].touch}" if t.records else None)
                if t.records:
                    start = (t.records[-1].force, t.records[-1].dev_sigma_X)
        if bebe and th in bebe and bebe[th]["BE/BE"].records:
            r = bebe[th]["BE/BE"]
            ax.plot([0.0, *r.load_curve("force")], [0.0, *r.load_curve()], ":^", ms=3,
                    label=f"BE/BE (h = {r.h:g})")
            f = bebe[th]["FE/FE"]
            ax.plot([0.0, *f.load_curve("force")], [0.0, *f.load_curve()], "-", lw=0.8,
                    color="grey", label=f"FE/FE (h = {f.h:g}, same mesh as BE/BE)")
        style_axes(ax, "applied force (bottom reaction)",
                   f"||dev sigma|| at X = {plasticity.POINT[example]}",
                   f"theta = {th:g}, h = {prm.h_figure:g}", title_size=9,
                   legend=dict(fontsize=7), grid=False)
    ax = axes[-1]
    last = len(plasticity.STAMPS[example])
    for i, h in enumerate(prm.h_levels):
        forms = ("bbar", "full") if example == 2 and prm.locking_study else ("bbar",)
        for form, style in zip(forms, ("-", ":")):
            recs = runs[(example, "FE", th0[0], h, form)].records
            start = [x for x in recs if x.touch == last - 1][-1:] or [None]
            load = [x for x in recs if x.touch == last and x.phase == "load"]
            f0, s0 = (0.0, 0.0) if start[0] is None else (start[0].force, start[0].dev_sigma_X)
            ax.plot([f0] + [x.force for x in load], [s0] + [x.dev_sigma_X for x in load],
                    style, color=f"C{i}",
                    label=f"FE/FE {'B-bar' if form == 'bbar' else 'full Q1'} h={h:g}")
    for i, (h, pair) in enumerate((study or {}).items()):
        r = pair["BE/BE"]
        if r.records:
            ax.plot([0.0, *r.load_curve("force")], [0.0, *r.load_curve()], "-.^", ms=2,
                    color=f"C{len(prm.h_levels) + i}", label=f"BE/BE h={h:.3g}")
    style_axes(ax, "applied force", f"||dev sigma|| at X = {plasticity.POINT[example]}",
               f"mesh study, theta = {th0[0]:g}, touch {last}", title_size=9,
               legend=dict(fontsize=7), grid=False)
    fig.tight_layout()
    return fig


def vtu_exports(prm: Params, run: plasticity.Run, tag: str) -> dict:
    """Work piece (displacement, element fields ||eps_p||, ||dev sigma||, alpha) and stamp
    (displacement; a BE stamp on its auxiliary grid) at the peak of every touch."""
    out = {}
    for t in run.touches:
        if t.peak is None:
            continue
        s = t.peak
        wp = fe_vtu(run.fe.mesh, {"u": run.fe.elastic.nodal_displacement(s.u_work).T})
        wp.cell_data = {k: [np.asarray(v, dtype=float)] for k, v in s.fields.items()}
        out[f"{tag}_touch{s.touch}_work"] = wp
        pts, disp, cells = stamp_interior(s.stamp, s.u_stamp, *_grid(s.stamp, prm))
        z = np.zeros((len(pts), 1))
        out[f"{tag}_touch{s.touch}_stamp"] = meshio.Mesh(
            np.hstack([pts, z]), [("quad", np.asarray(cells))],
            point_data={"u": np.hstack([disp, z])})
    return out


def missing_figure(text: str) -> Figure:
    fig, ax = new_figure((6, 2))
    ax.axis("off")
    ax.text(0.5, 0.5, text, ha="center", va="center", wrap=True, fontsize=9)
    return fig


def bebe_exports(bebe: dict) -> dict:
    """The BE/BE work piece at full lift on its cell grid, for every theta: node
    displacement (representation formula) and the cell fields."""
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
