"""Progress bars for the experiments' sweeps, quiet where nobody watches."""

from __future__ import annotations

import sys
from typing import Iterable

__all__ = ["progress"]


def progress(iterable: Iterable, **kw):
    """tqdm progress bar on stderr, shown only when stderr is a terminal (quiet in
    Snakemake jobs, CI and log files).  Keyword arguments go to ``tqdm``."""
    from tqdm.auto import tqdm

    kw.setdefault("disable", not sys.stderr.isatty())
    kw.setdefault("file", sys.stderr)
    return tqdm(iterable, **kw)
