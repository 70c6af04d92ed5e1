"""The figures' embedding in the HTML report: each result's PNG, narrowed and
re-encoded with fewer colours when that makes it smaller.

The re-encoding (about 70 ms a figure: half of the report job) is kept in a cache keyed
on the PNG's bytes and this encoder's settings (``$XDG_CACHE_HOME/hpfebe/report-png``,
else ``~/.cache/...``): a rerun of the workflow redraws the figures bit for bit where
their data did not change, and the report re-encodes only the others.  The cache holds
the :data:`CACHE_KEEP` most recently used entries.
"""

from __future__ import annotations

import hashlib
import io
import os
from pathlib import Path

__all__ = ["png_for_html", "encode_for_html", "MAX_FIGURE_WIDTH"]


#: figures are embedded at most this wide (pixels; the page is narrower)
MAX_FIGURE_WIDTH = 1400
#: entries kept in the re-encoding cache
CACHE_KEEP = 400
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_ENCODER = f"width<={MAX_FIGURE_WIDTH} quantize=mediancut-256 optimize v1".encode()


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "hpfebe" / "report-png"


def png_for_html(path: Path) -> bytes:
    """:func:`encode_for_html` of the PNG file ``path``, from the cache when there."""
    data = path.read_bytes()
    cache = _cache_dir()
    entry = cache / f"{hashlib.blake2b(_ENCODER + data, digest_size=16).hexdigest()}.png"
    try:
        out = entry.read_bytes()
        if out.startswith(PNG_SIGNATURE):     # (else damaged: encoded again)
            os.utime(entry)                   # (recently used)
            return out
    except OSError:
        pass
    out = encode_for_html(data)
    try:
        cache.mkdir(parents=True, exist_ok=True)
        tmp = entry.with_name(f".{entry.name}.{os.getpid()}")
        tmp.write_bytes(out)
        os.replace(tmp, entry)                # (a reader never sees half an entry)
        old = sorted(cache.glob("*.png"), key=lambda p: p.stat().st_mtime)[:-CACHE_KEEP]
        for p in old:
            p.unlink(missing_ok=True)
    except OSError:                           # a read-only or full cache: no cache
        pass
    return out


def encode_for_html(data: bytes) -> bytes:
    """The figure's PNG for embedding: at most :data:`MAX_FIGURE_WIDTH` pixels wide and
    re-encoded with 256 colours (matplotlib's plots have few; ~half the bytes) when
    that is smaller; the bytes as given if Pillow cannot read them."""
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
