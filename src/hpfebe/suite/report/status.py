"""The status of an artefact in the report: what differs from the thesis and whether it
is explained.

Status of an artefact (:func:`judge`).  The *off items* are the cells outside their
tolerance and the thesis claims that fail (``holds`` False; a claim with ``holds``
None is undecided, neither holding nor differing).  An ``explanation`` or
``hypothesis`` claim links to off items through ``Claim.explains`` (claim ids, or
``cells:*``, ``cells:<column>``, ``cells:<column>[key=value,...]``); a link counts only
if that claim holds (an explanation that fails, or is undecided, explains nothing).
Each off item's best link is an explanation that holds, else a hypothesis that holds,
else none:

    matches                no off item (and some cell compared within tolerance)
    differs (explained)    every off item's best link is an explanation that holds
    differs (hypothesis)   every off item is linked, some only by a hypothesis
    differs (unexplained)  some off item has no link that holds
    no published numbers   no off item and no table compared (figures: their claims
                           are listed and counted)

``beyond`` claims and failed explanations / hypotheses never make an artefact differ
from the thesis: they are listed (and counted per kind), not compared with it.  An
artefact whose result carries ``meta["reading"]`` (:data:`READING_KEY`: the reading of
the thesis under which the numbers are compared, e.g. Table 4.3's two-pass contact) has
it shown beside its status.  Missing results are "not built"; a published table without
any experiment is "not implemented"; a result whose files do not match what its JSON
records (:func:`hpfebe.suite.results.check_result`) is "damaged" with the mismatches, and none
of its numbers or figures is used.  Results written before claims had kinds count as
``thesis`` claims with no links.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..claims import CELLS_PREFIX, CLAIM_KINDS
from ..published import Comparison, key_value

if TYPE_CHECKING:
    from .entries import Entry

__all__ = ["judge", "claim_kind", "claim_explains", "OffItem", "READING_KEY",
           "STATUS_ORDER", "ALWAYS_COUNTED", "LINK_EXPLANATION", "LINK_HYPOTHESIS",
           "LINK_NONE", "STATUS_MATCH", "STATUS_DIFF_EXPL", "STATUS_DIFF_HYP",
           "STATUS_DIFF_UNEXPL", "STATUS_NO_PUB", "STATUS_NOT_BUILT", "STATUS_NOT_IMPL",
           "STATUS_NO_OVERLAP", "STATUS_PUB_MISSING", "STATUS_UNREADABLE", "STATUS_DAMAGED"]


STATUS_MATCH = "matches"
STATUS_DIFF_EXPL = "differs (explained)"
STATUS_DIFF_HYP = "differs (hypothesis)"
STATUS_DIFF_UNEXPL = "differs (unexplained)"
STATUS_NO_PUB = "no published numbers"
STATUS_NOT_BUILT = "not built"
STATUS_NOT_IMPL = "not implemented"
STATUS_NO_OVERLAP = "no rows in common"
STATUS_PUB_MISSING = "published file missing"
STATUS_UNREADABLE = "unreadable result"
STATUS_DAMAGED = "damaged"

#: the order of the status counts; the first five are always shown
STATUS_ORDER = (STATUS_MATCH, STATUS_DIFF_EXPL, STATUS_DIFF_HYP, STATUS_DIFF_UNEXPL,
                STATUS_NO_PUB, STATUS_NO_OVERLAP, STATUS_PUB_MISSING, STATUS_UNREADABLE,
                STATUS_DAMAGED, STATUS_NOT_BUILT, STATUS_NOT_IMPL)
ALWAYS_COUNTED = STATUS_ORDER[:5]

#: result meta key: the reading of the thesis under which the artefact is compared
#: (a short phrase, e.g. "two-pass penalty contact (Section 4.4)"), shown with its status
READING_KEY = "reading"

#: link strength of an off item: an explanation that holds, a hypothesis that holds, none
LINK_EXPLANATION, LINK_HYPOTHESIS, LINK_NONE = 2, 1, 0
_LEVEL_STATUS = {LINK_EXPLANATION: STATUS_DIFF_EXPL, LINK_HYPOTHESIS: STATUS_DIFF_HYP,
                 LINK_NONE: STATUS_DIFF_UNEXPL}


@dataclass
class OffItem:
    """A cell outside its tolerance or a thesis claim that fails, with its best link."""

    what: str                            # "cell" or "claim"
    column: str = ""                     # cell: its column
    key: dict = field(default_factory=dict)      # cell: its row's key values
    claim: dict | None = None            # claim: the claim
    level: int = LINK_NONE               # best link that holds (LINK_*)
    by: list[str] = field(default_factory=list)  # the claims linking it at ``level``
    dead: list[str] = field(default_factory=list)  # linked by claims that do not hold


def claim_kind(c: dict) -> str:
    """A claim's kind; missing (results written before kinds) or unknown: "thesis"."""
    k = c.get("kind") or "thesis"
    return k if k in CLAIM_KINDS else "thesis"


def claim_explains(c: dict) -> tuple[str, ...]:
    x = c.get("explains") or ()
    if isinstance(x, str):
        x = (x,)
    return tuple(str(v) for v in x if v)


_CELLS_RE = re.compile(r"^([^\[\]]+?)\s*(?:\[([^\[\]]*)\])?$")


def _parse_cells(spec: str) -> tuple[str, dict[str, str]] | None:
    """``cells:<column>[key=value,...]`` -> (column, {key: value}); None if malformed."""
    m = _CELLS_RE.match(spec[len(CELLS_PREFIX):].strip())
    if not m:
        return None
    cond = {}
    for part in (m.group(2) or "").split(","):
        if not part.strip():
            continue
        k, sep, v = part.partition("=")
        if not sep or not k.strip():
            return None
        cond[k.strip()] = v.strip()
    return m.group(1).strip(), cond


def _claim_label(c: dict) -> str:
    if c.get("id"):
        return str(c["id"])
    t = str(c.get("text", ""))
    return f"'{t[:60]}...'" if len(t) > 60 else f"'{t}'"


def _link_level(c: dict) -> int:
    """What a link from claim ``c`` is worth: nothing unless ``c`` holds."""
    if c.get("holds") is not True:
        return LINK_NONE
    return {"explanation": LINK_EXPLANATION, "hypothesis": LINK_HYPOTHESIS}.get(
        claim_kind(c), LINK_NONE)


def _targets(spec: str, items: list[OffItem], cmp: Comparison | None, ids: set[str]
             ) -> tuple[list[OffItem], str]:
    """The off items an ``explains`` entry names, and what is wrong with it ("" if
    nothing: naming an item that is not off is fine)."""
    if spec.startswith(CELLS_PREFIX):
        parsed = _parse_cells(spec)
        if parsed is None:
            return [], f"cannot read {spec!r} (cells:<column>[key=value,...])"
        if cmp is None:
            return [], f"{spec!r} names cells, but no table is compared"
        col, cond = parsed
        if col != "*" and col not in cmp.columns:
            return [], f"{spec!r}: {col!r} is not a judged column {cmp.columns}"
        unknown = sorted(set(cond) - set(cmp.keys))
        if unknown:
            return [], f"{spec!r}: {unknown} are not key columns {cmp.keys}"
        want = {k: key_value(v) for k, v in cond.items()}
        return [it for it in items if it.what == "cell" and col in ("*", it.column)
                and all(key_value(it.key.get(k)) == v for k, v in want.items())], ""
    if spec not in ids:
        return [], f"{spec!r} is no claim id of this artefact"
    return [it for it in items if it.what == "claim" and it.claim.get("id") == spec], ""


def judge(entry: Entry) -> str:
    """The status of a built, readable result (the rules in the module docstring);
    sets ``entry.off_items`` (each with its best link) and ``entry.link_problems``."""
    cmp, claims = entry.comparison, entry.claims
    items = []
    if cmp is not None:
        items = [OffItem("cell", column=c, key=r["key"]) for r in cmp.rows
                 if r["presence"] == "both" for c in cmp.columns
                 if r["cells"][c]["status"] == "off"]
    items += [OffItem("claim", claim=c) for c in entry.claims_of("thesis")
              if c.get("holds") is False]
    ids = {str(c["id"]) for c in claims if c.get("id")}
    problems = []
    for c in entry.claims_of("explanation", "hypothesis"):
        level, label = _link_level(c), _claim_label(c)
        for spec in claim_explains(c):
            targets, problem = _targets(spec, items, cmp, ids)
            if problem:
                problems.append(f"{label}: {problem}")
            for it in targets:
                if level == LINK_NONE:
                    if label not in it.dead:
                        it.dead.append(label)
                elif level > it.level:
                    it.level, it.by = level, [label]
                elif level == it.level and label not in it.by:
                    it.by.append(label)
    entry.off_items, entry.link_problems = items, problems
    if items:
        return _LEVEL_STATUS[min(it.level for it in items)]
    if entry.error:
        return STATUS_DIFF_UNEXPL        # the comparison failed: nothing is known to match
    if cmp is not None:
        return STATUS_MATCH if cmp.n_ok else STATUS_NO_OVERLAP
    return STATUS_NO_PUB
