"""Progress bars for the experiments' sweeps, quiet where nobody watches."""

from __future__ import annotations

import sys
from typing import Iterable

from .watch import check_terminated

__all__ = ["progress"]


def progress(iterable: Iterable, **kw):
    """The items of ``iterable`` with a tqdm progress bar on stderr, shown only when
    stderr is a terminal (quiet in Snakemake jobs, CI and log files); keyword arguments
    go to ``tqdm``.  Before each item, a SIGTERM/SIGHUP whose exception was swallowed
    where it arrived (a finalizer, a broad except in library code) ends the sweep
    (:func:`hpfebe.suite.watch.check_terminated`): a killed job stops at its next case,
    not at its end."""
    from tqdm.auto import tqdm

    kw.setdefault("disable", not sys.stderr.isatty())
    kw.setdefault("file", sys.stderr)
    with tqdm(iterable, **kw) as bar:
        for item in bar:
            check_terminated()
            yield item
