"""The figures' embedding in the HTML report: each result's PNG, narrowed and
re-encoded with fewer colours when that makes it smaller.
"""

from __future__ import annotations

import io
from pathlib import Path

__all__ = ["png_for_html", "MAX_FIGURE_WIDTH"]


#: figures are embedded at most this wide (pixels; the page is narrower)
MAX_FIGURE_WIDTH = 1400


def png_for_html(path: Path) -> bytes:
    """The figure's PNG for embedding: at most :data:`MAX_FIGURE_WIDTH` pixels wide and
    re-encoded with 256 colours (matplotlib's plots have few; ~half the bytes) when
    that is smaller; the file's bytes if Pillow cannot read it."""
    data = path.read_bytes()
    try:
        from PIL import Image

        with Image.open(io.BytesIO(data)) as im:
            im.load()
            rgba = im.convert("RGBA")
        img = Image.alpha_composite(Image.new("RGBA", rgba.size, "white"), rgba)
        img = img.convert("RGB")
        if img.width > MAX_FIGURE_WIDTH:
            img = img.resize((MAX_FIGURE_WIDTH,
                              max(1, round(img.height * MAX_FIGURE_WIDTH / img.width))),
                             Image.LANCZOS)
        buf = io.BytesIO()
        img.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
                     ).save(buf, "PNG", optimize=True)
    except Exception:  # noqa: BLE001 - the original is always a valid PNG to embed
        return data
    return buf.getvalue() if len(buf.getvalue()) < len(data) else data
