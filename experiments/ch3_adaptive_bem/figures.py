"""Figures 3.2-3.9 of ``experiments.ch3_adaptive_bem``: the geometry of both examples,
the initial mesh, the mesh sequences with the deformed boundary, the interior
displacement fields and the error curves of Fig. 3.6."""

from __future__ import annotations

import numpy as np

from hpfebe.scenes import adaptive_bem as scene
from hpfebe.suite import mesh_sequence_figure, new_figure, readable_log_ticks, style_axes


def fig_geometry(example, d, title):
    """The body, Gamma_C, Gamma_D and the obstacle of Example 1 or 2."""
    fig, ax = new_figure((4.5, 5.0))
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
    ax.set_aspect("equal")
    ax.set_xlim(-1.5, 1.5)
    ax.set_ylim(-1.5, 1.4)
    ax.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.05))
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
    panels = [(r["mesh"], r["marked"], scene.boundary_polygon(
        r["mesh"], r["state"]["op"].V_space, r["state"]["U"], mag),
        f"step {r['step']}: {r['mesh'].n_elements} el., {r['state']['ndof']} DOF")
        for r in recs]
    return mesh_sequence_figure(panels, title + f" (red: refined in this step; blue: "
                                f"deformed, x{mag:g})")


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
