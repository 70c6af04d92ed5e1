"""The drawings of Figures 4.21 and 4.22: u_x, u_y of the work piece (row 1) and of the
stamp (row 2), the work piece's ||dev sigma|| (with the plastic region of the mortar
solution outlined), and the colour bar ranges (ours | the thesis's) beside them
(:func:`hpfebe.scenes.section44_fields.colour_ranges`)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from hpfebe.suite import new_figure

LIMITS = {"work": ((-2.1, 2.1), (-2.1, 0.1)), "stamp": ((-0.6, 0.6), (-0.1, 2.1))}


def _panel(fig, ax, p, cells, values, clim, title, fmt):
    pc = PolyCollection(p[cells], array=values, cmap="jet", edgecolors="none")
    pc.set_clim(*clim)
    ax.add_collection(pc)
    # the colour bar as an inset of the axes: it keeps the height of the drawn
    # (equal-aspect) box instead of the height of the grid cell
    cax = ax.inset_axes([1.04, 0.0, 0.05, 1.0])
    fig.colorbar(pc, cax=cax, format=fmt)
    cax.tick_params(labelsize=8)
    ax.set_title(title, fontsize=9)


def _displacement_panels(bodies: dict):
    """The 2 x 3 figure of Figures 4.21/4.22 with u_x, u_y of the work piece (row 1) and
    the stamp (row 2) drawn in the first two columns; the rows' heights follow the
    bodies' shapes (work piece 4 x 2, stamp 1 x 2)."""
    fig, axes = new_figure((13, 7.8), 2, 3, height_ratios=(1.0, 1.6), layout="constrained")
    fig.get_layout_engine().set(w_pad=0.15, wspace=0.12)
    for row, b in enumerate(("work", "stamp")):
        p, cells, u = bodies[b]
        for c in (0, 1):
            _panel(fig, axes[row, c], p, cells, u[cells, c].mean(axis=1),
                   (u[:, c].min(), u[:, c].max()), f"{b}: u_{'xy'[c]}", "%.2e")
            axes[row, c].set_xlim(*LIMITS[b][0])
            axes[row, c].set_ylim(*LIMITS[b][1])
            axes[row, c].set_aspect("equal")
    return fig, axes


def _finish_dev_and_ranges(axes, ranges: pd.DataFrame) -> None:
    """Both figures' last column: the work piece's ||dev sigma|| panel framed like the
    displacement panels, and the colorbar ranges (ours | thesis) as text below it."""
    axes[0, 2].set_xlim(*LIMITS["work"][0])
    axes[0, 2].set_ylim(*LIMITS["work"][1])
    axes[0, 2].set_aspect("equal")
    axes[1, 2].axis("off")
    lines = ["colorbar ranges: ours | thesis"] + [
        f"{x.body} {x.field}: {x.ours_min:.3e}..{x.ours_max:.3e} | "
        + ("max " if np.isnan(x.published_min) else f"{x.published_min:.3e}..")
        + f"{x.published_max:.3e}" for x in ranges.itertuples()]
    axes[1, 2].text(0.0, 0.5, "\n".join(lines), fontsize=7, va="center", family="monospace")


def fields_figure(bodies: dict, ranges: pd.DataFrame, dev: np.ndarray, title: str,
                  plastic: np.ndarray | None = None) -> Figure:
    """Figures 4.21/4.22: row 1 the work piece's u_x, u_y and ||dev sigma|| (element
    values ``dev``; ``plastic``: the elements of the plastic region, outlined), row 2
    the stamp's u_x, u_y and the colorbar ranges beside the published ones."""
    fig, axes = _displacement_panels(bodies)
    p, cells, _ = bodies["work"]
    _panel(fig, axes[0, 2], p, cells, dev, (0.0, dev.max()), "work piece: ||dev sigma||"
           + ("" if plastic is None else " (black: plastic region)"), "%.2f")
    if plastic is not None:
        axes[0, 2].add_collection(PolyCollection(p[cells[plastic]], facecolors="none",
                                                 edgecolors="k", linewidths=0.4))
    _finish_dev_and_ranges(axes, ranges)
    fig.suptitle(title, fontsize=10)
    return fig
