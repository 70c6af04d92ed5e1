"""Claims: the checked statements an artefact makes, with their kinds.

A :class:`Claim` is a statement about an artefact with its verdict (``holds``) and the
measured numbers that decide it (``evidence``); its ``kind`` (:data:`CLAIM_KINDS`) says
whether it is the thesis's statement, our explanation of a difference, a hypothesis or a
result beyond the thesis, and ``explains`` links explanations and hypotheses to the
claims and table cells (:data:`CELLS_PREFIX`) they account for.

Claims that recur are built by helpers, so that the verdict and its evidence read the
same everywhere: :func:`rate_claim` (an observed rate against the expected one),
:func:`beats_uniform_claim` (adaptive against uniform refinement at equal DOF) and
:func:`range_claim` (a computed range against a published one, e.g. a colorbar: each
extreme by its relative difference), and
:func:`joint_claim` (one statement made of several checked parts).

:func:`validate_claims` checks an artefact's claims against the contract (kinds,
verdicts, unique ids, links that name a claim of the artefact or its cells); the report
(:mod:`hpfebe.suite.report`) judges an artefact's status from them.

This is an edge module: no numerics (the log-log interpolation is
:func:`hpfebe.analysis.rates.loglog_interpolate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np

__all__ = [
    "Claim",
    "CLAIM_KINDS",
    "CELLS_PREFIX",
    "rate_claim",
    "beats_uniform_claim",
    "range_claim",
    "joint_claim",
    "validate_claims",
]

#: what a claim is (the report counts ``thesis`` claims in its summary, the others apart):
#: ``thesis`` - a statement the thesis makes, checked against what was measured;
#: ``explanation`` - our computed test of a cause for a difference (it could have
#: failed, and it survives the changes it should not depend on), linked by ``explains``
#: to the claims or cells it explains; ``hypothesis`` - a numerical coincidence or a
#: reading not derived, linked the same way; ``beyond`` - a result beyond the thesis.
CLAIM_KINDS = ("thesis", "explanation", "hypothesis", "beyond")

#: an ``explains`` entry naming table cells instead of a claim id: ``"cells:*"`` (every
#: off cell of the artefact's table), ``"cells:<column>"`` (every off cell of that
#: column) or ``"cells:<column>[key=value,...]"`` (the off cells of the rows whose key
#: columns have those values, compared as numbers where they parse as numbers)
CELLS_PREFIX = "cells:"


@dataclass
class Claim:
    """A checked statement about an artefact.

    Parameters
    ----------
    text : str
        the statement, e.g. "BE energy rate of the h-version ~0.66 (theory 2/3)"
    holds : bool or None
        True (holds), False (differs), None (not decidable here, e.g. evaluated over
        zero converged runs)
    evidence : str
        the measured numbers that decide it
    kind : str
        one of :data:`CLAIM_KINDS` (default ``"thesis"``)
    id : str
        a short name, unique within the artefact, that ``explains`` entries refer to
    explains : tuple of str
        for ``explanation`` and ``hypothesis`` claims: the ids of the claims of the
        same artefact, and the cells (:data:`CELLS_PREFIX`), whose difference this claim
        accounts for
    """

    text: str
    holds: bool | None
    evidence: str = ""
    kind: str = "thesis"
    id: str = ""
    explains: tuple[str, ...] = ()


def _finite(name: str, v) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {v!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {v!r}")
    return x


def rate_claim(statement: str, observed: float, expected: float, tol: float,
               what: str = "rate") -> Claim:
    """Holds iff |observed - expected| <= tol (a NaN observation does not hold)."""
    expected, tol = _finite("expected", expected), _finite("tol", tol)
    if tol < 0:
        raise ValueError(f"tol must be >= 0, got {tol!r}")
    observed = float(observed)
    holds = bool(abs(observed - expected) <= tol)
    return Claim(statement, holds, f"observed {what} {observed:.3f}, expected {expected:.4g} "
                                   f"+- {tol:g}")


def beats_uniform_claim(statement: str, dof_adaptive, err_adaptive, dof_uniform,
                        err_uniform, factor: float = 1.0) -> Claim:
    """Adaptive against uniform refinement at equal DOF: holds iff the last adaptive
    error is below ``factor`` x the uniform error log-log interpolated at the last
    adaptive DOF; not decidable (holds None) if the uniform DOF range does not contain
    that DOF."""
    from ..analysis.rates import loglog_interpolate

    factor = _finite("factor", factor)
    if factor <= 0:
        raise ValueError(f"factor must be > 0, got {factor!r}")
    dof_a, err_a = np.asarray(dof_adaptive, float), np.asarray(err_adaptive, float)
    dof_u = np.asarray(dof_uniform, float)
    if dof_a.size == 0 or dof_a.shape != err_a.shape:
        raise ValueError(f"dof_adaptive and err_adaptive must be non-empty and of equal "
                         f"length, got {dof_a.shape}, {err_a.shape}")
    d, e = float(dof_a[-1]), float(err_a[-1])
    head = f"last adaptive step: {d:.0f} DOF, error {e:.4g}"
    if dof_u.size == 0 or not dof_u.min() <= d <= dof_u.max():
        rng = f"{dof_u.min():.0f}..{dof_u.max():.0f}" if dof_u.size else "none"
        return Claim(statement, None, f"{head}; the uniform DOF range ({rng}) does not "
                                      "contain it: not decidable")
    e_u = loglog_interpolate(d, dof_u, err_uniform)
    cond = f"below {factor:g} x uniform" if factor != 1.0 else "below uniform"
    return Claim(statement, bool(e < factor * e_u),
                 f"{head}; uniform at that DOF (log-log interpolated) {e_u:.4g}; ratio "
                 f"{e / e_u:.3f} (holds if {cond})")


#: the extremes of a range, as :func:`range_claim` names them
RANGE_EXTREMES = ("min", "max")


def range_claim(statement: str, name: str, ours, published, rel_tol: float,
                fixed: Iterable[str] = ()) -> Claim:
    """A computed range ``ours = (lo, hi)`` against a published one (e.g. a colour
    bar): holds iff each extreme is within ``rel_tol`` of the published one, relative
    to it: |lo - plo| / |plo| and |hi - phi| / |phi| (the relative difference of each
    max/min, not a share of the span).  A published extreme 0 has no relative
    difference: there the absolute difference, as a share of the published span,
    counts (and the evidence says so).

    ``fixed`` names the extremes (``"min"``, ``"max"``) that are fixed by construction,
    e.g. a Dirichlet value: they are no evidence, so they are not tested (the evidence
    says so and still shows them)."""
    rel_tol = _finite("rel_tol", rel_tol)
    if rel_tol < 0:
        raise ValueError(f"rel_tol must be >= 0, got {rel_tol!r}")
    try:
        lo, hi = (_finite(f"ours[{i}]", v) for i, v in enumerate(ours))
        plo, phi = (_finite(f"published[{i}]", v) for i, v in enumerate(published))
    except (TypeError, ValueError) as err:
        raise ValueError(f"ours and published must be (lo, hi) pairs: {err}") from None
    span = abs(phi - plo)
    if span == 0:
        raise ValueError(f"published range must have a non-zero span, got {published!r}")
    fixed = tuple(fixed) if not isinstance(fixed, str) else (fixed,)
    bad = [f for f in fixed if f not in RANGE_EXTREMES]
    if bad or len(set(fixed)) == len(RANGE_EXTREMES):
        raise ValueError(f"fixed must name at most one of {RANGE_EXTREMES} (an extreme "
                         f"fixed by construction), got {fixed!r}")
    parts, devs = [], []
    for which, v, pv in (("min", lo, plo), ("max", hi, phi)):
        if which in fixed:
            parts.append(f"{which} {v:.4e} fixed by construction (published {pv:.4e}): "
                         "no evidence, not tested")
            continue
        if pv != 0:
            dev = abs(v - pv) / abs(pv)
            parts.append(f"{which} {v:.4e} against {pv:.4e}: {100 * dev:.1f} % off")
        else:
            dev = abs(v) / span
            parts.append(f"{which} {v:.4e} against 0: |{which}| = {100 * dev:.1f} % of "
                         "the published span (absolute: no relative difference to 0)")
        devs.append(dev)
    return Claim(statement, bool(max(devs) <= rel_tol),
                 f"{name} {lo:.4e}..{hi:.4e} (published {plo:.4e}..{phi:.4e}): "
                 + "; ".join(parts) + f" (tolerance {100 * rel_tol:g} % of each extreme)")


def joint_claim(statement: str, *parts: Claim, note: str = "") -> Claim:
    """One statement that holds iff every part holds: False if any part is False, else
    None if any is undecidable, else True; the evidence joins the parts' evidence
    (``"; "``) and ``note``."""
    if not parts or not all(isinstance(c, Claim) for c in parts):
        raise ValueError("joint_claim needs at least one Claim part")
    verdicts = [c.holds for c in parts]
    holds = False if False in verdicts else (None if None in verdicts else True)
    evidence = "; ".join(c.evidence for c in parts if c.evidence)
    return Claim(statement, holds, evidence + (f" ({note})" if note else ""))


def validate_claims(name: str, claims: list) -> None:
    """Check the claims of artefact ``name`` against the contract; ``ValueError`` names
    what is wrong (see :func:`hpfebe.suite.results.validate`)."""
    for c in claims:
        if not isinstance(c, Claim):
            raise ValueError(f"{name}: claims must be Claim objects, got {type(c).__name__}")
        if c.holds not in (True, False, None):
            raise ValueError(f"{name}: Claim.holds must be True, False or None, got "
                             f"{c.holds!r} for {c.text!r}")
        if c.kind not in CLAIM_KINDS:
            raise ValueError(f"{name}: Claim.kind must be one of {CLAIM_KINDS}, got "
                             f"{c.kind!r} for {c.text!r}")
        if not isinstance(c.explains, (tuple, list)) or not all(
                isinstance(x, str) and x for x in c.explains):
            raise ValueError(f"{name}: Claim.explains must be a tuple of claim ids or "
                             f"'cells:...' names, got {c.explains!r} for {c.text!r}")
        if c.explains and c.kind not in ("explanation", "hypothesis"):
            raise ValueError(f"{name}: only explanation and hypothesis claims explain "
                             f"something; {c.kind} claim {c.text!r} has explains="
                             f"{tuple(c.explains)!r}")
    ids = [c.id for c in claims if c.id]
    if len(set(ids)) != len(ids):
        raise ValueError(f"{name}: claim ids must be unique, got {ids}")
    for c in claims:
        for x in c.explains:
            if not x.startswith(CELLS_PREFIX) and x not in ids:
                raise ValueError(f"{name}: claim {c.text!r} explains {x!r}, which is "
                                 f"neither a claim id of this artefact ({ids}) nor a "
                                 f"'{CELLS_PREFIX}...' name")
