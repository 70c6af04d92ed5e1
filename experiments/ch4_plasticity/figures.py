"""The figures of Figures 4.1-4.12: the deformed work piece and stamp (x magnification)
with ||eps_p||, the BE/BE cell grid, ||dev sigma|| at X against the applied force."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from hpfebe.scenes import plasticity, plasticity_fields
from hpfebe.suite import new_figure, style_axes

EDGES = dict(edgecolors="k", linewidths=0.2)


def _frame(ax, *points):
    """Equal-aspect limits holding every (magnified) deformed body, with a margin."""
    p = np.vstack(points)
    lo, hi = p.min(axis=0), p.max(axis=0)
    pad = 0.05 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")


def _draw(ax, prm, run, snap, values, vmax: float, stamp_face: str | None = None):
    """Deformed work piece (cells coloured by ``values``, or plain) and stamp (beside a
    coloured work piece: coloured as zero, or ``stamp_face``)."""
    pw, cw, ps, cs = plasticity_fields.deformed_bodies(run, snap, prm.magnification,
                                                       prm.h_figure)
    if values is None:
        work, stamp = dict(facecolors="lightsteelblue"), dict(facecolors="wheat")
    else:
        work = dict(array=values, cmap="jet")
        stamp = (dict(facecolors=stamp_face) if stamp_face else
                 dict(array=np.zeros(len(cs)), cmap="jet"))
    pcs = [PolyCollection(p[c], **kw, **EDGES) for p, c, kw in ((pw, cw, work),
                                                                (ps, cs, stamp))]
    for pc in pcs:
        if pc.get_array() is not None:
            pc.set_clim(0.0, vmax)
        ax.add_collection(pc)
    _frame(ax, pw, ps)
    return pcs[0] if values is not None else None


def field_figure(prm, run: plasticity.Run, field: str | None, title: str) -> Figure:
    """FE/FE or FE/BE at the peak of every touch, coloured by ``field`` (None: plain)."""
    snaps = [t.peak for t in run.touches if t.peak is not None]
    fig, axes = new_figure((5.0 * len(snaps), 3.9), 1, len(snaps), squeeze=False)
    axes = axes[0]
    vmax = max(float(s.fields["eps_p_norm"].max()) for s in snaps) if field else 0.0
    for ax, s in zip(axes, snaps):
        pc = _draw(ax, prm, run, s, s.fields[field] if field else None, vmax or 1.0)
        ax.set_title(f"{title}, touch {s.touch} at full lift (x{prm.magnification:g})",
                     fontsize=9)
    if pc is not None:
        fig.colorbar(pc, ax=axes.tolist(), shrink=0.7, label="||eps_p||")
    return fig


def bebe_figure(prm, bebe: dict, field: str | None, title: str) -> Figure:
    """BE/BE at full lift: the work piece's cell grid deformed by the displacement at its
    nodes (representation formula, x magnification), the BE stamp on its auxiliary grid;
    cells coloured by ``field``; ``bebe``: one theta's {"BE/BE": Run, "FE/FE": Run}."""
    snap = bebe["BE/BE"].touches[0].peak if bebe else None
    if snap is None:
        fig, ax = new_figure((6, 2))
        ax.axis("off")
        ax.text(0.5, 0.5, "BE/BE: no converged state (see the claims)", ha="center",
                va="center", wrap=True, fontsize=9)
        return fig
    fig, ax = new_figure((5.5, 4.0))
    vals = snap.fields[field] if field else None
    vmax = (float(vals.max()) or 1.0) if field else 1.0
    pc = _draw(ax, prm, bebe["BE/BE"], snap, vals, vmax, stamp_face="white")
    if pc is not None:
        fig.colorbar(pc, ax=ax, shrink=0.7, label="||" + field.removesuffix("_norm") + "||")
    ax.set_title(f"{title}, h = {bebe['BE/BE'].h:g}, full lift (x{prm.magnification:g})",
                 fontsize=9)
    return fig


def curve_figure(prm, runs: dict, example: int, bebe: dict | None = None,
                 study: dict | None = None) -> Figure:
    """||dev sigma|| at X against the applied force: FE/FE, FE/BE (and BE/BE) per theta;
    last panel: the FE/FE mesh study (B-bar, full Q1) and the BE/BE mesh study."""
    ths, last = prm.thetas, len(plasticity.STAMPS[example])
    fig, axes = new_figure((4.8 * (len(ths) + 1), 4.2), 1, len(ths) + 1)
    ylabel = f"||dev sigma|| at X = {plasticity.POINT[example]}"
    for ax, th in zip(axes, ths):
        for st, style, kw in (("FE", "-o", dict(ms=6, mfc="none")),
                              ("BE", "--s", dict(ms=3))):
            r = runs[(example, st, th, prm.h_figure, "bbar")]
            for k, t in enumerate(r.touches, start=1):
                ax.plot(*r.branch(k), style, **kw,
                        label=f"FE/{st}, touch {k}" if t.records else None)
        if bebe and th in bebe and bebe[th]["BE/BE"].records:
            r, f = bebe[th]["BE/BE"], bebe[th]["FE/FE"]
            ax.plot(*r.branch(1), ":^", ms=3, label=f"BE/BE (h = {r.h:g})")
            ax.plot(*f.branch(1), "-", lw=0.8, color="grey",
                    label=f"FE/FE (h = {f.h:g}, same mesh as BE/BE)")
        style_axes(ax, "applied force (bottom reaction)", ylabel,
                   f"theta = {th:g}, h = {prm.h_figure:g}", title_size=9,
                   legend=dict(fontsize=7), grid=False)
    ax = axes[-1]
    forms = ("bbar", "full") if example == 2 and prm.locking_study else ("bbar",)
    for i, h in enumerate(prm.h_levels):
        for form, style in zip(forms, ("-", ":")):
            ax.plot(*runs[(example, "FE", ths[0], h, form)].branch(last), style,
                    color=f"C{i}",
                    label=f"FE/FE {'B-bar' if form == 'bbar' else 'full Q1'} h={h:g}")
    for i, (h, pair) in enumerate((study or {}).items()):
        r = pair["BE/BE"]
        if r.records:
            ax.plot(*r.branch(1), "-.^", ms=2, color=f"C{len(prm.h_levels) + i}",
                    label=f"BE/BE h={h:.3g}")
    style_axes(ax, "applied force", ylabel, f"mesh study, theta = {ths[0]:g}, touch {last}",
               title_size=9, legend=dict(fontsize=7), grid=False)
    fig.tight_layout()
    return fig
