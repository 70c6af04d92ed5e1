"""The report in Markdown (``report/report.md``): the same content as the HTML page,
figures linked from ``results/``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from .status import claim_kind
from .tables import (CLAIM_SECTIONS, CODE_RE, INTRO, MAX_TABLE_ROWS, STATUS_COUNTS_INTRO,
                     SUMMARY_HEADER, TIMING_HEADER, TIMING_INTRO, claim_line,
                     comparison_table, compile_record, difference_lines, fmt, fmt_tol,
                     provenance_summary, status_counts, summary_rows, timing_rows)

__all__ = ["render_markdown"]


def _md_text(s) -> str:
    """Markdown of a text: inline code as `x` (RST double backticks, roles dropped)."""
    return CODE_RE.sub(lambda m: f"`{m.group(2)}`", str(s))


def _md_escape(s) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def _md_table(header, rows) -> str:
    out = ["| " + " | ".join(_md_escape(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_md_escape(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def _md_df(df: pd.DataFrame, max_rows=None) -> str:
    max_rows = MAX_TABLE_ROWS if max_rows is None else max_rows
    rows = [[fmt(v) for v in r] for r in df.head(max_rows).itertuples(index=False)]
    s = _md_table([str(c) for c in df.columns], rows)
    if len(df) > max_rows:
        s += f"\n\n({len(df) - max_rows} more rows in the CSV file)"
    return s


def render_markdown(entries, out_dir: Path, results_dir: Path) -> str:
    """The Markdown page: status counts, summary, timing, one section per artefact (figures
    linked relative to ``out_dir``), provenance."""
    L = ["# hpfebe: reproduction report", "", INTRO, ""]
    if any(e.quick for e in entries):
        L += ["> **Quick configuration**: sweeps are reduced (config/quick.yaml); rows "
              "marked 'not run' are expected.", ""]
    L += ["## Status counts", "", STATUS_COUNTS_INTRO, "",
          _md_table(*status_counts(entries)), ""]
    L += ["## Summary", "", _md_table(SUMMARY_HEADER, summary_rows(entries)), ""]
    timing = timing_rows(entries, compile_record(results_dir))
    if timing:
        L += ["## Timing", "", TIMING_INTRO, "", _md_table(TIMING_HEADER, timing), ""]
    for e in entries:
        job = f" - job `{e.job}`" if e.doc and e.job and e.job != e.module else ""
        L += [f"## {e.name}", "", f"*{e.kind}* - module `{e.module or '-'}`{job} - "
              f"status: **{e.status}**"
              + (f" - reading: *{_md_text(e.reading)}*" if e.reading else ""), ""]
        if e.published_caption:
            L += [f"Published: `{e.published_path.name}` - {e.published_caption}", ""]
        if e.error:
            L += [f"**Problem:** {_md_text(e.error)}", ""]
        if e.doc is None:
            if e.published_table is not None:
                L += ["Published numbers (nothing reproduced yet):", "",
                      _md_df(e.published_table), ""]
            continue
        diffs = difference_lines(e)
        if diffs:
            L += ["### Differences and what explains them", ""]
            L += [f"- {_md_text(t)}: {_md_text(link)}" for t, link, _ in diffs] + [""]
        if e.comparison is not None:
            cmp = e.comparison
            tols = "; ".join(f"{c}: {fmt_tol(cmp.tolerances[c])}" for c in cmp.columns)
            shown = (f" Not judged: {', '.join(cmp.shown)}." if cmp.shown else "")
            header, rows, _ = comparison_table(cmp)
            L += ["### Published vs reproduced", "", f"Tolerances: {tols}.{shown}", "",
                  _md_table(header, rows), ""]
        if e.png is not None:
            rel = os.path.relpath(e.png, out_dir)
            L += [f"![{e.name}]({Path(rel).as_posix()})", ""]
        for title, kinds in CLAIM_SECTIONS:
            cs = e.claims_of(*kinds)
            if not cs:
                continue
            L += [f"### {title}", ""]
            for c in cs:
                v, text, links, ev = claim_line(c)
                label = f"{claim_kind(c)}, " if len(kinds) > 1 else ""
                L += [f"- **{label}{v}**: {_md_text(text)}"
                      + (f" ({_md_text(links)})" if links else "")
                      + (f" - {_md_text(ev)}" if ev else "")]
            L += [""]
        if e.notes_shared or e.notes_home or e.notes_own:
            L += ["### Notes", ""]
            if e.notes_shared:
                L += [f"*Shared with {', '.join(e.notes_sharers)} (module "
                      f"`{e.module}`):* {_md_text(e.notes_shared)}", ""]
            if e.notes_home:
                L += [f"*The notes this artefact shares with module `{e.module}`: see "
                      f"[{e.notes_home}](#{e.notes_home}).*", ""]
            if e.notes_own:
                L += [_md_text(e.notes_own), ""]
        if e.table is not None:
            L += ["### Reproduced table", "", _md_df(e.table), ""]
    L += ["## Provenance", ""]
    L += [f"- {k}: {v}" for k, v in provenance_summary(entries).items()]
    return "\n".join(L) + "\n"
