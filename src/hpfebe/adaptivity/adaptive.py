"""Algorithm 3.2: the adaptive h-refinement loop for FEM and BEM, for one mesh or several.

    for k = 0, 1, ...:  solve -> estimate eta_I -> stop if sum eta_I^2 <= TOL^2
                        -> mark -> refine (with closure: done by the mesh's own refinement)

The loop knows nothing about the discretisation: it is given callables

* ``solve(mesh) -> (state, ndof)``,
* ``estimate(mesh, state) -> eta`` (one non-negative indicator per element, not squared),
* ``refine(mesh, marked) -> mesh`` (default :func:`default_refine`:
  ``mesh.refine(marked)`` for a :class:`~hpfebe.geometry.BoundaryMesh`,
  :func:`hpfebe.fem.meshes.refine_labelled` - red-green-blue refinement with closure,
  boundary labels kept - for a scikit-fem mesh),
* optionally ``error(mesh, state) -> float`` (the true error measure where known) and
  ``stop(record) -> bool`` (end the loop after the record of a step, e.g. once a
  reference run has reached a number of dofs).

``marking`` is "max" (eta_I >= theta max eta, the thesis's choice with theta = 0.9),
"bulk" (the ceil((1 - theta) N) largest), "doerfler", or "uniform" (refine everything:
the reference run).  The stopping test (c) uses ``tol`` on (sum eta_I^2)^(1/2).

Several meshes (e.g. the two bodies of a contact problem, Section 4.2.8): pass ``mesh`` as
a tuple of meshes.  Then ``solve(meshes)`` returns ``(state, ndofs)`` with one dof count
per mesh, ``estimate(meshes, state)`` one indicator array per mesh, and ``error``
receives the tuple.  Each mesh is marked on its own indicators (its own maximum);
``marking``, ``theta`` and ``refine`` may be given once for all meshes or as one entry
per mesh.  The records then hold one entry per mesh for ``n_elements``, ``ndof``,
``eta`` and ``n_marked``; ``eta_total`` = (sum over all meshes of eta_I^2)^(1/2) is what
``tol`` is tested against.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..checks import array, choice, integer, real
from ..fem.meshes import refine_labelled
from .marking import MARKERS

log = logging.getLogger(__name__)

MARKINGS = tuple(sorted(MARKERS)) + ("uniform",)


def default_refine(mesh, marked):
    """Refinement of the marked elements: ``BoundaryMesh.refine`` (bisection), or for a
    scikit-fem mesh :func:`hpfebe.fem.meshes.refine_labelled` (labels kept)."""
    marked = np.asarray(marked, dtype=bool)
    if hasattr(mesh, "refined") and not hasattr(mesh, "refine"):
        return refine_labelled(mesh, marked)
    return mesh.refine(marked)


@dataclass
class AdaptiveHistory:
    """One record per solved mesh: step, n_elements, ndof, eta (= (sum eta_I^2)^(1/2)),
    eta_total (the same over all meshes), error (NaN if not given), efficiency
    (eta_total / error), n_marked, t_solve, t_estimate, t_refine (seconds); with several
    meshes n_elements, ndof, eta and n_marked are tuples (one entry per mesh).

    Per step also ``meshes`` (the mesh, or the tuple of meshes, that was solved),
    ``etas`` (the indicators) and ``marked`` (boolean masks of the elements refined
    after that step; all False for the last step, which is not refined).  ``mesh``,
    ``state`` and ``eta`` are those of the last step; ``reason`` says why the loop
    ended ("n_steps", "tol" or "stop")."""

    records: list = field(default_factory=list)
    meshes: list = field(default_factory=list)
    etas: list = field(default_factory=list)
    marked: list = field(default_factory=list)
    mesh: object = None
    state: object = None
    eta: object = None
    reason: str = ""
    n_meshes: int | None = None     # None: one mesh (scalars in the records)

    def column(self, name: str, index: int | None = None) -> np.ndarray:
        """The values of ``name`` over the steps (with several meshes, per-mesh
        quantities give one column per mesh; ``index`` selects mesh ``index``)."""
        col = np.array([r[name] for r in self.records])
        if index is None:
            return col
        if self.n_meshes is None:
            raise ValueError("index is only meaningful with several meshes")
        return col[:, index] if col.ndim == 2 else col


def _per_mesh(value, n: int, name: str) -> list:
    if isinstance(value, (list, tuple)):
        if len(value) != n:
            raise ValueError(f"{name} must be one value or one per mesh ({n}), got {value!r}")
        return list(value)
    return [value] * n


def _check_marking(markings, thetas) -> None:
    for marking, theta in zip(markings, thetas):
        choice("marking", marking, MARKINGS)
        if marking != "uniform":
            MARKERS[marking](np.ones(1), theta)  # validates theta early


def _mark(eta, marking: str, theta) -> np.ndarray:
    return np.ones(eta.size, dtype=bool) if marking == "uniform" else MARKERS[marking](eta, theta)


def adapt(mesh, solve, estimate, n_steps: int, theta=0.9, marking="max", refine=None,
          error=None, tol: float = 0.0, stop=None, progress=None) -> AdaptiveHistory:
    """Run Algorithm 3.2 for at most ``n_steps`` solves (the last mesh is solved and
    estimated but not refined) on one mesh or a tuple of meshes (module doc).
    ``progress`` optionally wraps the step range (e.g. a progress bar).  Returns an
    :class:`AdaptiveHistory`."""
    n_steps = integer("n_steps", n_steps, lo=1)
    tol = real("tol", tol, nonnegative=True)
    several = isinstance(mesh, (tuple, list))
    meshes = list(mesh) if several else [mesh]
    n = len(meshes)
    if n == 0:
        raise ValueError("mesh must be a mesh or a non-empty tuple of meshes, got ()")
    markings, thetas = _per_mesh(marking, n, "marking"), _per_mesh(theta, n, "theta")
    _check_marking(markings, thetas)
    refines = [default_refine if r is None else r for r in _per_mesh(refine, n, "refine")]
    pack = tuple if several else (lambda v: v[0])    # noqa: E731
    hist = AdaptiveHistory(reason="n_steps", n_meshes=n if several else None)
    steps = range(int(n_steps))
    for k in (steps if progress is None else progress(steps)):
        current = pack(meshes)
        t0 = time.perf_counter()
        state, ndof = solve(current)
        t1 = time.perf_counter()
        etas = estimate(current, state)
        t2 = time.perf_counter()
        # a NaN indicator would silently disable marking: refused, naming the step
        etas = [array(f"eta (indicators of mesh {i} at step {k})", e, ndim=1)
                for i, e in enumerate(etas if several else [etas])]
        ndofs = [integer("ndof (from solve)", d, lo=0) for d in (ndof if several else [ndof])]
        if len(etas) != n or len(ndofs) != n:
            raise ValueError(f"estimate and solve must give one entry per mesh ({n}), got "
                             f"{len(etas)} indicator arrays and {len(ndofs)} dof counts")
        totals = [float(np.sqrt(np.sum(e ** 2))) for e in etas]
        total = float(np.sqrt(np.sum([np.sum(e ** 2) for e in etas]))) if several else totals[0]
        err = float(error(current, state)) if error is not None else math.nan
        rec = dict(step=k, n_elements=pack([int(e.size) for e in etas]), ndof=pack(ndofs),
                   eta=pack(totals), eta_total=total, error=err,
                   efficiency=total / err if err > 0 else math.nan,
                   n_marked=pack([0] * n), t_solve=t1 - t0, t_estimate=t2 - t1, t_refine=0.0)
        hist.records.append(rec)
        hist.meshes.append(current)
        hist.etas.append(pack(etas))
        hist.marked.append(pack([np.zeros(e.size, dtype=bool) for e in etas]))
        hist.mesh, hist.state, hist.eta = current, state, pack(etas)
        log.info("adaptive step %d: ndof %s, eta %s", k, rec["ndof"], rec["eta"])
        if total <= tol:
            hist.reason = "tol"
            break
        if stop is not None and stop(rec):
            hist.reason = "stop"
            break
        if k == n_steps - 1:
            break
        marked = [_mark(e, m, th) for e, m, th in zip(etas, markings, thetas)]
        rec["n_marked"] = pack([int(m.sum()) for m in marked])
        hist.marked[-1] = pack(marked)
        t3 = time.perf_counter()
        meshes = [r(m, mk) for r, m, mk in zip(refines, meshes, marked)]
        rec["t_refine"] = time.perf_counter() - t3
    return hist
