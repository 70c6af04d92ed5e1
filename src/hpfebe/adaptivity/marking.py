"""Marking strategies for adaptive refinement (Algorithm 3.2, Section 3.3).

* :func:`mark_max` - the thesis's rule: mark element I if eta_I >= theta * max_J eta_J
  (theta = 0.9 in the experiments of Section 3.4).
* :func:`mark_bulk` - the thesis's second criterion (after Algorithm 3.2): "refine I if
  eta_I belongs to (1 - p) * 100% of the largest indicators".  Read literally, as a share
  of the *number* of elements: the ceil((1 - theta) N) elements with the largest eta_I
  (at least one; ties at the threshold value are all marked, so the result does not
  depend on the element order).
* :func:`mark_doerfler` - the common alternative reading (Doerfler bulk criterion, not in
  the thesis): the smallest set M of largest indicators with
  sum_{I in M} eta_I^2 >= (1 - theta) sum_I eta_I^2.

Both return a boolean mask; if all indicators vanish nothing is marked.
"""

from __future__ import annotations

import numpy as np

from ..checks import array, real


def _check(eta, theta):
    eta = array("eta (indicators)", eta, ndim=1, min_size=1)
    if np.any(eta < 0):
        k = int(np.argmin(eta))
        raise ValueError(f"eta (indicators) must be non-negative, got {eta[k]!r} on "
                         f"element {k}")
    return eta, real("theta", theta, lo=0.0, hi=1.0, lo_open=True)


def mark_max(eta, theta: float = 0.9) -> np.ndarray:
    """Maximum strategy: mark I iff eta_I >= theta * max eta (Algorithm 3.2)."""
    eta, theta = _check(eta, theta)
    top = eta.max()
    if top == 0.0:
        return np.zeros(eta.size, dtype=bool)
    return eta >= theta * top


def mark_bulk(eta, theta: float = 0.5) -> np.ndarray:
    """Mark the ceil((1 - theta) N) largest indicators (at least one if the total is
    positive; ties at the threshold all marked)."""
    eta, theta = _check(eta, theta)
    if eta.max() == 0.0:
        return np.zeros(eta.size, dtype=bool)
    k = max(int(np.ceil((1.0 - theta) * eta.size - 1e-9)), 1)
    thresh = np.sort(eta)[::-1][k - 1]
    return eta >= thresh


def mark_doerfler(eta, theta: float = 0.5) -> np.ndarray:
    """Doerfler marking: the smallest set of largest indicators whose squares sum to at
    least (1 - theta) of sum eta^2 (at least one element if the total is positive).
    Ties at the threshold value are all marked (the result does not depend on order)."""
    eta, theta = _check(eta, theta)
    e2 = eta ** 2
    total = e2.sum()
    if total == 0.0:
        return np.zeros(eta.size, dtype=bool)
    order = np.argsort(-e2, kind="stable")
    csum = np.cumsum(e2[order])
    k = int(np.searchsorted(csum, (1.0 - theta) * total * (1 - 1e-12), side="left"))
    k = min(max(k, 0), eta.size - 1)
    return eta >= eta[order[k]]


MARKERS = {"max": mark_max, "bulk": mark_bulk, "doerfler": mark_doerfler}
