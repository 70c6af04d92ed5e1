"""Algorithm 3.2: the adaptive h-refinement loop for FEM and BEM.

    for k = 0, 1, ...:  solve -> estimate eta_I -> stop if sum eta_I^2 <= TOL^2
                        -> mark -> refine (with closure: done by the mesh's own refinement)

The loop knows nothing about the discretisation: it is given callables

* ``solve(mesh) -> (state, ndof)``,
* ``estimate(mesh, state) -> eta`` (one non-negative indicator per element, not squared),
* ``refine(mesh, marked) -> mesh`` (default: ``mesh.refine(marked)`` for a
  :class:`~hpfebe.geometry.BoundaryMesh`, ``mesh.refined(indices)`` - newest vertex
  bisection with closure - for a scikit-fem ``MeshTri``),
* optionally ``error(mesh, state) -> float`` (the true error measure where known).

``marking`` is "max" (eta_I >= theta max eta, the thesis's choice with theta = 0.9),
"bulk" (the ceil((1 - theta) N) largest), "doerfler", or "uniform" (refine everything:
the reference run).  The stopping test (c) uses ``tol`` on (sum eta_I^2)^(1/2).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .marking import MARKERS


def default_refine(mesh, marked):
    """Bisection of the marked elements: BoundaryMesh.refine or skfem MeshTri.refined."""
    marked = np.asarray(marked, dtype=bool)
    if hasattr(mesh, "refined") and not hasattr(mesh, "refine"):
        return mesh.refined(np.flatnonzero(marked))
    return mesh.refine(marked)


@dataclass
class AdaptiveHistory:
    """One record per solved mesh: step, n_elements, ndof, eta (= (sum eta_I^2)^(1/2)),
    error (NaN if not given), efficiency (eta / error), n_marked, t_solve, t_estimate,
    t_refine (seconds).  ``mesh`` and ``state`` are those of the last step; ``reason``
    says why the loop ended ("n_steps" or "tol")."""

    records: list = field(default_factory=list)
    mesh: object = None
    state: object = None
    eta: np.ndarray | None = None
    reason: str = ""

    def column(self, name: str) -> np.ndarray:
        return np.array([r[name] for r in self.records])


def adapt(mesh, solve, estimate, n_steps: int, theta: float = 0.9, marking: str = "max",
          refine=None, error=None, tol: float = 0.0) -> AdaptiveHistory:
    """Run Algorithm 3.2 for at most ``n_steps`` solves (the last mesh is solved and
    estimated but not refined).  Returns an :class:`AdaptiveHistory`."""
    if int(n_steps) != n_steps or n_steps < 1:
        raise ValueError(f"n_steps must be an integer >= 1, got {n_steps!r}")
    if marking != "uniform" and marking not in MARKERS:
        raise ValueError(f"marking must be one of {sorted(MARKERS) + ['uniform']}, "
                         f"got {marking!r}")
    if not (math.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be a finite number >= 0, got {tol!r}")
    if marking != "uniform":
        MARKERS[marking](np.ones(1), theta)  # validates theta early
    refine = default_refine if refine is None else refine
    hist = AdaptiveHistory(reason="n_steps")
    for k in range(int(n_steps)):
        t0 = time.perf_counter()
        state, ndof = solve(mesh)
        t1 = time.perf_counter()
        eta = np.asarray(estimate(mesh, state), dtype=float)
        t2 = time.perf_counter()
        if not np.all(np.isfinite(eta)):
            raise FloatingPointError(f"estimator returned non-finite indicators at step {k}")
        total = float(np.sqrt(np.sum(eta ** 2)))
        err = float(error(mesh, state)) if error is not None else math.nan
        rec = dict(step=k, n_elements=int(eta.size), ndof=int(ndof), eta=total, error=err,
                   efficiency=total / err if err > 0 else math.nan, n_marked=0,
                   t_solve=t1 - t0, t_estimate=t2 - t1, t_refine=0.0)
        hist.records.append(rec)
        hist.mesh, hist.state, hist.eta = mesh, state, eta
        if total <= tol:
            hist.reason = "tol"
            break
        if k == n_steps - 1:
            break
        marked = (np.ones(eta.size, dtype=bool) if marking == "uniform"
                  else MARKERS[marking](eta, theta))
        rec["n_marked"] = int(marked.sum())
        t3 = time.perf_counter()
        mesh = refine(mesh, marked)
        rec["t_refine"] = time.perf_counter() - t3
    return hist
