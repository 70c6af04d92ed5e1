"""The report: every reproduced number beside the published one.

Reads ``results/<artefact>.json/.csv/.png`` (written by :func:`hpfebe.suite.results.write_result`)
and ``report/published/*.csv`` (the thesis's numbers; first line a ``#`` comment), and
writes

    report/index.html   self-contained (inline CSS, figures embedded as base64 PNG,
                        re-encoded to at most MAX_FIGURE_WIDTH pixels and 256 colours)
    report/report.md    the same content in Markdown (figures linked from results/)

Top: the counts of artefacts per status, in all and per chapter (with the thesis
claims holding / differing / undecided); a summary (artefact, kind, module, status,
cells within tolerance, thesis claims, the other claims by kind, wall time); a timing
table: one line per workflow job (a module, or one scene of it: ``provenance.run.job``;
the module for older results) with its wall time, numba compile time and JIT time
(written by the command line's :class:`hpfebe.cli.JitTimer`; older results show "-").
Per table artefact with a published file: published | reproduced | difference | status
for every column with a tolerance, joined on the result's ``keys`` (rows on one side
only are marked "not run" / "not published"), and published | reproduced for the
columns both tables have that are not judged (e.g. Table 4.3's Newton iterations).
Per artefact: what differs and what explains it, the figure, the claims by kind with
verdict and evidence, the notes (the opening a module's artefacts share is shown once,
at its first artefact; the others link to it), the reproduced table.  Footer:
provenance.

The parts: :mod:`.entries` (one entry per artefact: its result, published table and
comparison, :mod:`hpfebe.suite.published`), :mod:`.status` (judging: the statuses and
their rules), :mod:`.tables` (the rows and texts both renderings show),
:mod:`.markdown`, :mod:`.html` and :mod:`.figures` (the figures' embedding).

An edge module: no numerics beyond comparing numbers.
"""

from __future__ import annotations

from pathlib import Path

from ..results import atomic_write
from .entries import Entry, chapter_of, collect
from .figures import MAX_FIGURE_WIDTH
from .html import render_html
from .markdown import render_markdown
from .status import READING_KEY, claim_kind, judge

__all__ = ["build_report", "collect", "judge", "Entry", "chapter_of", "claim_kind",
           "render_markdown", "render_html", "READING_KEY", "MAX_FIGURE_WIDTH"]


def build_report(results_dir: Path | str, out_dir: Path | str,
                 published_dir: Path | str, expected: dict[str, str] | None = None
                 ) -> list[Path]:
    """Write ``out_dir/index.html`` and ``out_dir/report.md``; ``expected`` maps the
    artefacts that should exist to their modules (missing ones are "not built")."""
    results_dir, out_dir, published_dir = Path(results_dir), Path(out_dir), Path(published_dir)
    entries = collect(results_dir, published_dir, expected)
    md = render_markdown(entries, out_dir, results_dir)
    page = render_html(entries, results_dir)
    return [atomic_write(out_dir / "index.html", lambda f: f.write(page)),
            atomic_write(out_dir / "report.md", lambda f: f.write(md))]
