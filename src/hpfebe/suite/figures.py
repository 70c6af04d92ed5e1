"""The plotting patterns every experiment repeats: a figure with its axes, the labels and
the log grid, reference slopes on convergence plots, readable tick labels on a log axis
that spans a decade or two.

    fig, ax = new_figure((6.0, 4.5))
    ax.loglog(dof, err, "o-", label="p = 1")
    reference_slope(ax, dof, err[0], -1.0, "DOF$^{-1}$")      # annotated at its end
    slope_line(ax, dof, -0.5, (dof[0], err[0]), label="DOF$^{-1/2}$")  # in the legend
    style_axes(ax, "DOF", "error", "Example 1", legend=dict(fontsize=7))

Figures are :class:`matplotlib.figure.Figure` objects (no pyplot state); the CLI writes
and closes them.  Plotting lives here and in the experiments, never in numerical code.
"""

from __future__ import annotations

import io
import math

import matplotlib
import numpy as np
from matplotlib import colors as mcolors
from matplotlib import image as mimage
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
from mpl_toolkits.axes_grid1 import make_axes_locatable

__all__ = ["new_figure", "style_axes", "reference_slope", "slope_line",
           "readable_log_ticks", "GRID", "mesh_sequence_figure", "deformed_field_figure",
           "png_bytes"]

#: the grid of every convergence and work-precision plot: major and minor ticks, faint
GRID = dict(which="both", alpha=0.3)


def new_figure(figsize, nrows: int = 1, ncols: int = 1, **subplots):
    """(figure, axes): a :class:`~matplotlib.figure.Figure` of ``figsize`` inches with
    ``nrows`` x ``ncols`` axes (one axes object for 1 x 1, else the array of
    :meth:`Figure.subplots`); ``layout`` goes to the figure, the other keywords to
    ``subplots`` (``sharey``, ``gridspec_kw``, ...)."""
    fig = Figure(figsize=figsize, layout=subplots.pop("layout", None))
    return fig, fig.subplots(nrows, ncols, **subplots)


def style_axes(ax, xlabel: str | None = None, ylabel: str | None = None,
               title: str | None = None, *, title_size=None, legend: dict | None = None,
               grid: bool = True):
    """Label ``ax`` (``None``: leave as is), draw the :data:`GRID` (``grid``) and, with
    ``legend`` (the keywords of :meth:`Axes.legend`, ``{}`` for its defaults), the
    legend of what is plotted so far.  ``title_size`` is the title's font size (``None``:
    matplotlib's title size).  Returns ``ax``."""
    if xlabel is not None:
        ax.set_xlabel(xlabel)
    if ylabel is not None:
        ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title, **({} if title_size is None else dict(fontsize=title_size)))
    if grid:
        ax.grid(True, **GRID)
    if legend is not None:
        ax.legend(**legend)
    return ax


def reference_slope(ax, x, y0, slope, label, below=False, **kw):
    """Reference line y = y0 (x / x[0])^slope over the range of x, labelled above (or
    ``below``) its right end, right-aligned so that the label stays inside the axes."""
    x = np.asarray([np.min(x), np.max(x)], float)
    ax.loglog(x, y0 * (x / x[0]) ** slope, "k--", lw=0.8, alpha=0.7, **kw)
    ax.annotate(label, (x[-1], y0 * (x[-1] / x[0]) ** slope), xytext=(0, -3 if below else 3),
                textcoords="offset points", ha="right", va="top" if below else "bottom",
                fontsize=7, alpha=0.8)


def slope_line(ax, x, slope, through, fmt: str = "k--", **kw):
    """Reference line y = y_t (x / x_t)^slope through the point ``through`` = (x_t, y_t),
    drawn at the points ``x`` in the format ``fmt`` (keywords to ``loglog``: ``label``
    puts it in the legend, ``alpha``, ``color`` ...); returns the line."""
    x = np.asarray(x, float)
    xt, yt = through
    line, = ax.loglog(x, yt * (x / xt) ** slope, fmt, **kw)
    return line


def readable_log_ticks(axis, numticks=None) -> None:
    """Labelled major ticks at 1, 2, 5 x 10^k (2, 5, 10, 20; 0.002, 0.005, 0.01) in plain
    numbers, no minor labels: a log ``axis`` (``ax.xaxis``) spanning a decade or two
    reads.  ``numticks``: at most that many ticks (``None``: matplotlib's choice)."""
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0), numticks=numticks))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def mesh_sequence_figure(panels, title: str, columns: int = 4):
    """A figure of a sequence of boundary meshes (adaptive refinement), one panel per
    entry of ``panels``: (mesh, marked, polygon, panel title) with the elements of
    ``mesh`` (its ``a``, ``b`` end points) in black, the ``marked`` ones in red, and the
    closed ``polygon`` (e.g. the deformed boundary) in blue; at most ``columns`` panels
    per row."""
    n = len(panels)
    cols = min(columns, n)
    rows = int(math.ceil(n / cols))
    fig, axs = new_figure((3.0 * cols, 3.1 * rows), rows, cols)
    axs = np.atleast_1d(axs).ravel()
    for ax, (mesh, marked, P, name) in zip(axs, panels):
        marked = np.asarray(marked, dtype=bool)
        segs = np.stack([mesh.a, mesh.b], axis=1)             # (n_elements, 2, 2)
        # one collection per style (not one line per element: cheaper to draw)
        for sel, c, lw in ((~marked, "k", 0.8), (marked, "red", 2.0)):
            if sel.any():
                ax.add_collection(LineCollection(segs[sel], colors=c, linewidths=lw))
        ax.plot(mesh.a[:, 0], mesh.a[:, 1], "k.", ms=3)
        ax.plot(P[:, 0], P[:, 1], "b-", lw=0.8)
        ax.set_title(name, fontsize="small")
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in axs[n:]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize="small")
    return fig


def deformed_field_figure(X, Y, u, mag: float, title: str):
    """Two panels: the x and y components of a displacement field ``u`` (n, n, 2) on the
    grid (X, Y), drawn on the grid deformed by ``mag`` u, with every (n - 1) // 20-th
    grid line and a colour bar as high as the axes (ticks with the power on top)."""
    fig, axs = new_figure((10.0, 4.6), 1, 2, gridspec_kw=dict(wspace=0.3))
    Xd, Yd = X + mag * u[..., 0], Y + mag * u[..., 1]
    for ax, c, name in zip(axs, (0, 1), ("x-component", "y-component")):
        m = ax.pcolormesh(Xd, Yd, u[..., c], shading="gouraud", cmap="jet")
        step = max(1, (X.shape[0] - 1) // 20)
        for i in range(0, X.shape[0], step):
            ax.plot(Xd[i, :], Yd[i, :], "k-", lw=0.3)
            ax.plot(Xd[:, i], Yd[:, i], "k-", lw=0.3)
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


def png_bytes(fig: Figure, dpi: float = 120.0, pad_inches: float = 0.1) -> bytes:
    """The PNG of ``fig`` as ``fig.savefig(..., dpi=dpi, bbox_inches="tight")`` writes it,
    from one draw: savefig's tight bounding box costs a second (dry-run) draw, about a
    third of the time of writing a figure (measured: 14 figures of three quick jobs
    3.03 s -> 1.90 s).  The figure is drawn once on an Agg canvas at ``dpi``; the
    picture is the canvas cut to its tight bounding box padded by ``pad_inches``
    (the pad outside the canvas in the face colour), the same size as savefig's;
    the drawing differs from savefig's by its sub-pixel offset only (antialiased
    edges).  Content outside the canvas (which savefig's tight box takes in): savefig
    itself."""
    old_dpi, old_canvas = fig.dpi, fig.canvas
    canvas = FigureCanvasAgg(fig)
    try:
        fig.set_dpi(dpi)
        canvas.draw()
        tight = fig.get_tightbbox(canvas.get_renderer())           # inches
        W, H = canvas.get_width_height()
        inside = (tight.x0 >= 0 and tight.y0 >= 0 and tight.x1 * dpi <= W
                  and tight.y1 * dpi <= H)
        if inside:
            box = tight.padded(pad_inches)
            m = int(math.ceil(pad_inches * dpi)) + 1               # room for the pad
            img = np.asarray(canvas.buffer_rgba())
            face = np.round(255 * np.array(mcolors.to_rgba(fig.get_facecolor())))
            big = np.empty((H + 2 * m, W + 2 * m, 4), dtype=img.dtype)
            big[...] = face.astype(img.dtype)
            big[m:m + H, m:m + W] = img
            w, h = int(box.width * dpi), int(box.height * dpi)    # savefig's size
            c0, r0 = int(round(box.x0 * dpi)) + m, int(round(H - box.y1 * dpi)) + m
            buf = io.BytesIO()
            mimage.imsave(buf, big[r0:r0 + h, c0:c0 + w], format="png", dpi=dpi,
                          metadata={"Software": f"Matplotlib version"
                                    f"{matplotlib.__version__}, https://matplotlib.org/"})
            return buf.getvalue()
    finally:
        fig.set_dpi(old_dpi)
        fig.set_canvas(old_canvas)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", pad_inches=pad_inches)
    return buf.getvalue()
