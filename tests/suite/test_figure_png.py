"""hpfebe.suite.figures.png_bytes: the PNG of savefig(bbox_inches="tight") from one draw
(the same size and, up to the sub-pixel offset of antialiased edges, the same picture;
savefig itself where content lies outside the canvas; the figure left as it was)."""

import io

import numpy as np
import pytest
from PIL import Image

from hpfebe.suite.figures import new_figure, png_bytes, style_axes


def _rgb(data: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(int)


def _savefig(fig, **kw) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight", **kw)
    return buf.getvalue()


def _convergence_figure():
    fig, axs = new_figure((7.0, 3.0), 1, 2)
    n = np.logspace(1, 4, 12)
    for ax in axs:
        ax.loglog(n, n ** -0.5, "o-", label="$N^{-1/2}$")
        ax.loglog(n, 3 * n ** -1.0, "s--", label="$N^{-1}$")
        style_axes(ax, "DOF", "error", "Example 1")
    im = axs[1].imshow(np.outer(np.arange(8), np.arange(8)), extent=(10, 1e4, 1e-4, 1))
    fig.colorbar(im, ax=axs[1])
    fig.suptitle("a title")
    return fig


def test_png_is_savefigs_picture_from_one_draw():
    fig = _convergence_figure()
    ref = _rgb(_savefig(fig))
    dpi, canvas = fig.dpi, fig.canvas
    ours = _rgb(png_bytes(fig, dpi=120))
    assert ours.shape == ref.shape
    # the same picture up to a sub-pixel shift: nearly every pixel equal, and the
    # differences where edges move, not a shifted or rescaled drawing
    diff = np.abs(ours - ref).max(axis=2)
    assert (diff > 0).mean() < 0.1 and (diff > 64).mean() < 0.02
    assert fig.dpi == dpi and fig.canvas is canvas          # the figure as it was
    # a shifted drawing would differ everywhere along the lines
    shifted = np.roll(ref, 3, axis=1)
    assert (np.abs(shifted - ref).max(axis=2) > 64).mean() > 2 * (diff > 64).mean()


def test_content_outside_the_canvas_goes_through_savefig():
    fig, ax = new_figure((3.0, 2.0))
    ax.plot([0, 1], [0, 1], label="a long legend entry outside the axes")
    ax.legend(loc="upper left", bbox_to_anchor=(1.05, 1.0))    # beyond the right edge
    calls = []
    savefig = fig.savefig
    fig.savefig = lambda *a, **kw: calls.append(kw) or savefig(*a, **kw)
    ours = png_bytes(fig, dpi=120)
    assert calls and calls[0]["bbox_inches"] == "tight"
    assert ours == _savefig(fig)


@pytest.mark.parametrize("pad", [0.0, 0.1, 0.3])
def test_pad_beyond_the_canvas_is_face_colour(pad):
    fig, ax = new_figure((3.0, 2.0))
    ax.plot([0, 1], [0, 1])
    fig.set_facecolor("#ffeeaa")
    ours, ref = _rgb(png_bytes(fig, dpi=120, pad_inches=pad)), _rgb(_savefig(fig, pad_inches=pad))
    assert ours.shape == ref.shape
    assert np.array_equal(ours[0, 0], [255, 238, 170]) and np.array_equal(ref[0, 0], ours[0, 0])
