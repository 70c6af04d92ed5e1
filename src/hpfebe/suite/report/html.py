"""The report as one self-contained HTML page (``report/index.html``): inline CSS,
figures embedded (:mod:`.figures`).
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

from .figures import png_for_html
from .status import (LINK_EXPLANATION, LINK_HYPOTHESIS, LINK_NONE, STATUS_DAMAGED,
                     STATUS_DIFF_EXPL, STATUS_DIFF_HYP, STATUS_MATCH, STATUS_PUB_MISSING,
                     STATUS_UNREADABLE, claim_kind)
from .tables import (CLAIM_SECTIONS, CODE_RE, INTRO, MAX_TABLE_ROWS, STATUS_COUNTS_INTRO,
                     SUMMARY_HEADER, TIMING_HEADER, TIMING_INTRO, claim_line,
                     comparison_groups, comparison_table, compile_record,
                     difference_lines, fmt, fmt_tol, provenance_summary, status_counts,
                     summary_rows, timing_rows)

__all__ = ["render_html"]


CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;
max-width:1600px;padding:0 1em;color:#222;line-height:1.45}
h1{border-bottom:2px solid #444}h2{border-bottom:1px solid #bbb;margin-top:2em}
table{border-collapse:collapse;margin:.6em 0;font-size:.82em}
th,td{border:1px solid #ccc;padding:.2em .35em;text-align:right;vertical-align:top}
th{background:#f0f0f0}td.l,th.l{text-align:left}th.g{text-align:center}
td.w{text-align:left;min-width:10em}
.ok{background:#e3f5e1}.off{background:#fbe0de}.na{background:#f2f2f2;color:#555}
.st-match{color:#1b6e20;font-weight:600}.st-expl{color:#6b5a00;font-weight:600}
.st-hyp{color:#b35900;font-weight:600}.st-diff{color:#a0361f;font-weight:600}
.st-none{color:#666}.banner{background:#fff6d5;border:1px solid #e0c050;padding:.5em 1em}
img{max-width:100%;height:auto;border:1px solid #ddd}details{margin:.5em 0}
.claim-holds{color:#1b6e20}.claim-differs{color:#a0361f}.claim-undecided{color:#666}
.kind{font-size:.8em;border:1px solid #999;border-radius:3px;padding:0 .3em;color:#444}
footer{margin-top:3em;font-size:.85em;color:#444;border-top:1px solid #bbb}
.scroll{overflow-x:auto;max-width:100%}code{background:#f4f4f4;padding:0 .2em}
pre{white-space:pre-wrap;word-break:break-word}
.ev{color:#444;font-size:.9em;margin:.1em 0 .4em}.links{color:#6b5a00;font-style:italic}
"""


def _e(s) -> str:
    return html.escape(str(s), quote=True)


def _status_class(status: str) -> str:
    if status.startswith(STATUS_MATCH):
        return "st-match"
    if status.startswith(STATUS_DIFF_EXPL):
        return "st-expl"
    if status.startswith(STATUS_DIFF_HYP):
        return "st-hyp"
    if status.startswith("differs") or status in (STATUS_PUB_MISSING, STATUS_UNREADABLE,
                                                  STATUS_DAMAGED):
        return "st-diff"
    return "st-none"


_LEVEL_CLASS = {LINK_EXPLANATION: "st-expl", LINK_HYPOTHESIS: "st-hyp",
                LINK_NONE: "st-diff"}


def _html_table(header, rows, classes=None, left=0, groups=None, cells=None) -> str:
    """A table in a horizontal scroll container.  ``groups``: a two-row header, the
    first ``left`` columns spanning both rows and (title, sub-titles) groups after
    them; ``cells``: HTML of cells (already escaped) instead of ``rows``' text."""
    out = ['<div class="scroll"><table><thead>']
    if groups:
        out.append("<tr>" + "".join(f'<th class="l" rowspan="2">{_e(h)}</th>'
                                    for h in header[:left]))
        out += [f'<th class="g" colspan="{len(subs)}">{_e(t)}</th>' for t, subs in groups]
        out.append("</tr><tr>" + "".join(f"<th>{_e(s)}</th>" for _, subs in groups
                                         for s in subs) + "</tr>")
    else:
        out.append("<tr>" + "".join(f'<th class="{"l" if i < left else ""}">{_e(h)}</th>'
                                    for i, h in enumerate(header)) + "</tr>")
    out.append("</thead><tbody>")
    for r_i, r in enumerate(rows):
        out.append("<tr>")
        for i, c in enumerate(r):
            cls = []
            if i < left:
                cls.append("l")
            if classes and classes[r_i] and classes[r_i][i]:
                cls.append(classes[r_i][i])
            text = cells[r_i][i] if cells and cells[r_i][i] is not None else _e(c)
            out.append(f'<td class="{" ".join(cls)}">{text}</td>')
        out.append("</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def _rich(s) -> str:
    """HTML of a text: escaped, inline code marked up as <code>, no stray backtick."""
    s, out, pos = str(s), [], 0
    for m in CODE_RE.finditer(s):
        out += [_e(s[pos:m.start()]), f"<code>{_e(m.group(2))}</code>"]
        pos = m.end()
    out.append(_e(s[pos:]))
    return "".join(out).replace("`", "'")


def render_html(entries, results_dir: Path | None = None) -> str:
    """The page: status counts, summary and timing, one section per artefact
    (:func:`_html_artefact`), the provenance in the footer."""
    H = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
         "<meta name='viewport' content='width=device-width,initial-scale=1'>",
         "<title>hpfebe: reproduction report</title>", f"<style>{CSS}</style></head><body>",
         "<h1>hpfebe: reproduction report</h1>", f"<p>{_e(INTRO)}</p>"]
    if any(e.quick for e in entries):
        H.append("<p class='banner'><b>Quick configuration</b>: sweeps are reduced "
                 "(config/quick.yaml); rows marked 'not run' are expected.</p>")
    header, rows = status_counts(entries)
    H += ["<h2 id='status-counts'>Status counts</h2>", f"<p>{_e(STATUS_COUNTS_INTRO)}</p>",
          _html_table(header, rows, left=1)]
    H.append("<h2 id='summary'>Summary</h2>")
    rows = summary_rows(entries)
    classes = [[None, None, None, _status_class(r[3]) + " w", None, None, "w", None]
               for r in rows]
    cells = [[f'<a href="#{_e(r[0])}">{_e(r[0])}</a>'] + [None] * (len(r) - 1)
             for r in rows]
    H.append(_html_table(SUMMARY_HEADER, rows, classes, left=4, cells=cells))
    timing = timing_rows(entries, results_dir and compile_record(results_dir))
    if timing:
        H += ["<h2 id='timing'>Timing</h2>", f"<p>{_e(TIMING_INTRO)}</p>",
              _html_table(TIMING_HEADER, timing, left=2)]

    for e in entries:
        H += _html_artefact(e)
    H.append("<footer><h2>Provenance</h2><ul>")
    H += [f"<li>{_e(k)}: {_e(v)}</li>" for k, v in provenance_summary(entries).items()]
    H.append("</ul></footer></body></html>")
    return "\n".join(H) + "\n"


def _html_artefact(e) -> list[str]:
    """One artefact's section: status, published caption, problem, differences and what
    explains them, published vs reproduced, figure, claims, notes, reproduced table,
    meta."""
    H = [f"<h2 id='{_e(e.name)}'>{_e(e.name)}</h2>"]
    job = (f" - job <code>{_e(e.job)}</code>" if e.doc and e.job and e.job != e.module
           else "")
    reading = (f" - reading: <i>{_rich(e.reading)}</i>" if e.reading else "")
    H.append(f"<p><i>{_e(e.kind)}</i> - module <code>{_e(e.module or '-')}</code>{job}"
             f" - status: <span class='{_status_class(e.status)}'>{_e(e.status)}"
             f"</span>{reading}</p>")
    if e.published_caption:
        H.append(f"<p>Published: <code>{_e(e.published_path.name)}</code> - "
                 f"{_rich(e.published_caption)}</p>")
    if e.error:
        H.append(f"<p class='st-diff'>Problem: {_rich(e.error)}</p>")
    if e.doc is None:
        if e.published_table is not None:
            df = e.published_table
            rows = [[fmt(v) for v in r] for r in df.itertuples(index=False)]
            H.append(f"<details><summary>Published numbers ({len(df)} rows, nothing "
                     "reproduced yet)</summary>"
                     + _html_table([str(c) for c in df.columns], rows) + "</details>")
        return H
    diffs = difference_lines(e)
    if diffs:
        H.append("<h3>Differences and what explains them</h3><ul>")
        H += [f"<li>{_rich(t)}: <span class='{_LEVEL_CLASS[lv]}'>{_rich(link)}</span></li>"
              for t, link, lv in diffs]
        H.append("</ul>")
    if e.comparison is not None:
        cmp = e.comparison
        tols = "; ".join(f"{c}: {fmt_tol(cmp.tolerances[c])}" for c in cmp.columns)
        shown = (f" Shown beside, not judged: {', '.join(cmp.shown)}."
                 if cmp.shown else "")
        header, rows, classes = comparison_table(cmp)
        H.append(f"<h3>Published vs reproduced</h3><p>Tolerances: {_e(tols)}."
                 f"{_e(shown)}</p>")
        H.append(_html_table(header, rows, classes, left=len(cmp.keys),
                             groups=comparison_groups(cmp)))
    if e.png is not None:
        data = base64.b64encode(png_for_html(e.png)).decode("ascii")
        H.append(f"<p><img alt='{_e(e.name)}' src='data:image/png;base64,{data}'></p>")
    return H + _html_claims(e) + _html_notes(e) + _html_reproduced(e)


def _html_claims(e) -> list[str]:
    """The claims by section (thesis; explanations and hypotheses; beyond the thesis),
    each with its verdict, what it explains and its evidence."""
    H = []
    for title, kinds in CLAIM_SECTIONS:
        cs = e.claims_of(*kinds)
        if not cs:
            continue
        H.append(f"<h3>{_e(title)}</h3><ul>")
        for c in cs:
            v, text, links, ev = claim_line(c)
            cls = {"holds": "claim-holds", "differs": "claim-differs"}.get(
                v, "claim-undecided")
            label = (f"<span class='kind'>{_e(claim_kind(c))}</span> "
                     if len(kinds) > 1 else "")
            H.append(f"<li>{label}<b class='{cls}'>{_e(v)}</b>: {_rich(text)}"
                     + (f" <span class='links'>({_rich(links)})</span>" if links else "")
                     + (f"<div class='ev'>{_rich(ev)}</div>" if ev else "") + "</li>")
        H.append("</ul>")
    return H


def _html_notes(e) -> list[str]:
    """The notes: the opening shared with the module's other artefacts (here, or a link
    to the artefact that shows it) and this artefact's own."""
    if not (e.notes_shared or e.notes_home or e.notes_own):
        return []
    H = ["<h3>Notes</h3>"]
    if e.notes_shared:
        links = ", ".join(f"<a href='#{_e(n)}'>{_e(n)}</a>" for n in e.notes_sharers)
        H.append(f"<p><i>Shared with {links} (module <code>{_e(e.module)}</code>):"
                 "</i></p>" + "".join(f"<p>{_rich(p)}</p>"
                                      for p in e.notes_shared.split("\n\n")))
    if e.notes_home:
        H.append(f"<p><i>The notes this artefact shares with module "
                 f"<code>{_e(e.module)}</code>: see <a href='#{_e(e.notes_home)}'>"
                 f"{_e(e.notes_home)}</a>.</i></p>")
    if e.notes_own:
        if e.notes_shared or e.notes_home:
            H.append("<p><i>This artefact:</i></p>")
        H += [f"<p>{_rich(p)}</p>" for p in e.notes_own.split("\n\n")]
    return H


def _html_reproduced(e) -> list[str]:
    """The reproduced table (at most :data:`MAX_TABLE_ROWS` rows) and the result's meta,
    folded."""
    H = []
    if e.table is not None:
        df = e.table
        rows = [[fmt(v) for v in r] for r in df.head(MAX_TABLE_ROWS).itertuples(
            index=False)]
        more = (f"<p>({len(df) - MAX_TABLE_ROWS} more rows in {_e(e.name)}.csv)</p>"
                if len(df) > MAX_TABLE_ROWS else "")
        H.append(f"<details><summary>Reproduced table ({len(df)} rows)</summary>"
                 + _html_table([str(c) for c in df.columns], rows) + more
                 + "</details>")
    meta = e.doc.get("meta") or {}
    if meta:
        H.append("<details><summary>meta</summary><pre>"
                 + _e(json.dumps(meta, indent=1)).replace("`", "'")
                 + "</pre></details>")
    return H
