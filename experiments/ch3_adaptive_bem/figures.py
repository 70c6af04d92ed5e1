"""Figures 3.2-3.9 of ``experiments.ch3_adaptive_bem``: the geometry of both examples,
the initial mesh, the mesh sequences with the deformed boundary, the interior
displacement fields and the error curves of Fig. 3.6."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.collections import LineCollection
from mpl_toolkits.axes_grid1 import make_axes_locatable

from hpfebe.scenes import adaptive_bem as scene
from hpfebe.suite import new_figure, readable_log_ticks, style_axes


def _draw_body(ax, example, d, show_mesh=None):
    P = np.array(scene.SQUARE + [scene.SQUARE[0]])
    ax.fill(P[:, 0], P[:, 1], color="0.92")
    lab = {"C": ("tab:orange", r"$\Gamma_C$"), "D": ("k", r"$\Gamma_D$")}
    for k, L in enumerate(scene.LABELS):
        a, b = np.array(scene.SQUARE[k]), np.array(scene.SQUARE[(k + 1) % 4])
        ax.plot([a[0], b[0]], [a[1], b[1]], color=lab[L][0], lw=3,
                label=lab[L][1] if k in (0, 2) else None)
    ax.plot([-1, 1], [1.05, 1.05], "k", lw=0.8)
    for x in np.linspace(-1, 1, 11):
        ax.plot([x, x + 0.08], [1.05, 1.13], "k", lw=0.8)
    if example == 1:
        ax.plot([-1.3, 1.3], [-1.08, -1.08], color="tab:blue", lw=3,
                label=fr"obstacle $\gamma$: y = -1 + d (d = {d:g}; drawn shifted)")
        ax.annotate("", xy=(0, -1.0), xytext=(0, -1.35), arrowprops=dict(arrowstyle="->"))
    else:
        ax.plot([-1.08, -1.08], [-0.5, 0.5], color="tab:blue", lw=3,
                label=fr"obstacle $\gamma$: x = -1 + d, |y| <= 1/2 (d = {d:g})")
        ax.annotate("", xy=(-1.0, 0), xytext=(-1.35, 0), arrowprops=dict(arrowstyle="->"))
    if show_mesh is not None:
        ax.plot(show_mesh.a[:, 0], show_mesh.a[:, 1], "ko", ms=4)
    ax.set_aspect("equal")
    ax.set_xlim(-1.5, 1.5)
    ax.set_ylim(-1.5, 1.4)
    ax.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.05))


def fig_geometry(example, d, title):
    fig, ax = new_figure((4.5, 5.0))
    _draw_body(ax, example, d)
    ax.set_title(title, fontsize="small")
    return fig


def fig_initial_mesh(mesh):
    fig, ax = new_figure((4.2, 4.2))
    P = np.vstack([mesh.a, mesh.a[:1]])
    ax.plot(P[:, 0], P[:, 1], "k-", lw=1)
    ax.plot(mesh.a[:, 0], mesh.a[:, 1], "ko", ms=5)
    ax.set_aspect("equal")
    ax.set_title(f"Initial mesh T_h: {mesh.n_elements} elements (4 per side)",
                 fontsize="small")
    ax.set_xlim(-1.2, 1.2)
    ax.set_ylim(-1.2, 1.2)
    return fig


def fig_mesh_sequence(recs, mag, title):
    n = len(recs)
    cols = min(4, n)
    rows = int(math.ceil(n / cols))
    fig, axs = new_figure((3.0 * cols, 3.1 * rows), rows, cols)
    axs = np.atleast_1d(axs).ravel()
    for ax, rec in zip(axs, recs):
        mesh, st = rec["mesh"], rec["state"]
        marked = np.asarray(rec["marked"], dtype=bool)
        segs = np.stack([mesh.a, mesh.b], axis=1)             # (n_elements, 2, 2)
        # one collection per style (not one line per element: cheaper to draw)
        for sel, c, lw in ((~marked, "k", 0.8), (marked, "red", 2.0)):
            if sel.any():
                ax.add_collection(LineCollection(segs[sel], colors=c, linewidths=lw))
        ax.plot(mesh.a[:, 0], mesh.a[:, 1], "k.", ms=3)
        P = scene.boundary_polygon(mesh, st["op"].V_space, st["U"], mag)
        ax.plot(P[:, 0], P[:, 1], "b-", lw=0.8)
        ax.set_title(f"step {rec['step']}: {mesh.n_elements} el., {st['ndof']} DOF",
                     fontsize="small")
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in axs[n:]:
        ax.set_visible(False)
    fig.suptitle(title + f" (red: refined in this step; blue: deformed, x{mag:g})",
                 fontsize="small")
    return fig


def fig_interior(X, Y, u, mag, title):
    fig, axs = new_figure((10.0, 4.6), 1, 2, gridspec_kw=dict(wspace=0.3))
    Xd, Yd = X + mag * u[..., 0], Y + mag * u[..., 1]
    for ax, c, name in zip(axs, (0, 1), ("x-component", "y-component")):
        m = ax.pcolormesh(Xd, Yd, u[..., c], shading="gouraud", cmap="jet")
        step = max(1, (X.shape[0] - 1) // 20)
        for i in range(0, X.shape[0], step):
            ax.plot(Xd[i, :], Yd[i, :], "k-", lw=0.3)
            ax.plot(Xd[:, i], Yd[:, i], "k-", lw=0.3)
        # a colour bar as high as the (equal-aspect) axes, its ticks 1.2 with "1e-4" on
        # top: short labels that stay clear of the next panel (exact extremes: title)
        cax = make_axes_locatable(ax).append_axes("right", size="4%", pad=0.08)
        cb = fig.colorbar(m, cax=cax)
        cb.formatter.set_powerlimits((0, 0))
        cb.update_ticks()
        ax.set_aspect("equal")
        ax.set_xlim(Xd.min(), Xd.max())
        ax.set_ylim(Yd.min(), Yd.max())
        ax.set_title(f"{name}: {u[..., c].min():.4e} .. {u[..., c].max():.4e}",
                     fontsize="small")
    fig.suptitle(title + f" (grid deformed x{mag:g})", fontsize="small")
    return fig


def fig_error(errtab, title):
    """Left: the thesis's err(U) = | |||U|||_B - |||U_190|||_B | (solid) and against the
    finer reference (dashed); right: the error |||U_ref - U|||_B (W and V parts)."""
    fig, axs = new_figure((11.0, 4.5), 1, 2, layout="constrained")
    marks = {"uniform": "s", "adaptive (3.107)": "o", "adaptive (3.107) balanced": "^"}
    for kind, df in errtab.groupby("refinement", sort=False):
        mk = marks.get(kind, "x")
        for col, ls, lab in (("err", "-", "U_190"), ("err_ref", "--", "finer ref.")):
            ok = df[col] > 0
            axs[0].loglog(df.dof[ok], df[col][ok], mk + ls, ms=4,
                          label=f"{kind}, vs {lab}")
        axs[1].loglog(df.dof, df.err_true, mk + "-", ms=4, label=kind)
    axs[0].set_ylabel(r"err(U) = | |||U|||$_B$ - |||U$_{ref}$|||$_B$ |")
    axs[1].set_ylabel(r"|||U$_{ref}$ - U|||$_B$ (W and V parts)")
    for ax in axs:
        readable_log_ticks(ax.xaxis, numticks=30)
        readable_log_ticks(ax.yaxis, numticks=30)
        # below the axes: err(U) crosses zero, its curves reach every corner of the panel
        style_axes(ax, "DOF", legend=dict(fontsize="x-small", loc="upper center",
                                          bbox_to_anchor=(0.5, -0.13), ncol=2))
    fig.suptitle(title, fontsize="small")
    return fig
