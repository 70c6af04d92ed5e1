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

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

__all__ = ["new_figure", "style_axes", "reference_slope", "slope_line",
           "readable_log_ticks", "GRID"]

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
