"""Laplace BEM on the unit square: convergence of the Neumann data (beyond the thesis).

A demonstration of the whole pipeline (core -> experiment -> results -> report), not an
artefact of the thesis.  The interior Dirichlet problem of the Laplacian on the unit
square (0,1)^2 with the harmonic solution

    u(x) = log|x - x0|,   x0 = (1.5, 1.5) outside the closed square,

is solved for its Neumann data psi = du/dn through the Calderon identity of Section 1.4,
V psi = (K + 1/2) u (:meth:`hpfebe.bem.LaplaceBEM.Psi`), with the Dirichlet data replaced
by its Gauss-Lobatto interpolant in V_hp (continuous, degree p) and psi sought in W_hp
(discontinuous Legendre, degree p - 1).  The exact Neumann data on element I with
outward normal n_I is (x - x0) . n_I / |x - x0|^2; it jumps at the corners, which W_hp
resolves since the corners are element ends.

Choices (the thesis has no such experiment):
* L2(Gamma) error by Gauss-Legendre quadrature with p + 10 points per element (the
  integrand is smooth on each element, so this is exact to rounding for these meshes);
* uniform meshes with n elements per side, h = 1/n, degrees p = 1, 2, 3;
* dof = dimension of W_hp (= 4 n p, equal to the dimension of V_hp on a closed curve);
* rate = log(e_prev / e) / log(h_prev / h) (log2 of the error ratio when n doubles);
* LaplaceBEM defaults: kernel length scale = diameter of the mesh, Psi constrained to
  zero total flux (the exact Neumann data of a harmonic function has zero flux).
Expected: ||psi - psi_h||_L2 = O(h^p), the best approximation order of W_hp in L2
(the Galerkin error is O(h^(p+1/2)) in H^-1/2; the interpolated Dirichlet data
contribute O(h^(p+1/2)) in H^-1/2 as well).
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hpfebe import BoundaryMesh
from hpfebe.bem import LaplaceBEM
from hpfebe.quadrature import gauss_legendre
from hpfebe.results import ArtefactResult, Claim, progress

ARTEFACTS = ("figure_bem_laplace",)

log = logging.getLogger(__name__)

SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
RATE_TOLERANCE = 0.15


def neumann_l2_error(degree: int, n: int, x0: np.ndarray, extra_points: int = 10):
    """Solve on the unit square with n elements per side and degree p; return
    (L2 error of the Neumann data, dof)."""
    mesh = BoundaryMesh.polygon(SQUARE, n=n, p=degree)
    op = LaplaceBEM(mesh)
    g = op.V_space.interpolate(lambda x: np.log(np.linalg.norm(x - x0, axis=1)))
    psi = op.Psi(g)

    t, w = gauss_legendre(degree + extra_points)
    ne = mesh.n_elements
    elem = np.repeat(np.arange(ne), len(t))
    tt = np.tile(t, ne)
    approx = op.W_space.evaluate(psi, elem, tt)
    d = mesh.points(elem, tt) - x0
    exact = np.einsum("ij,ij->i", d, mesh.normals[elem]) / np.einsum("ij,ij->i", d, d)
    weights = np.tile(w, ne) * np.repeat(0.5 * mesh.lengths, len(t))
    return float(np.sqrt(np.sum(weights * (approx - exact) ** 2))), op.W_space.ndof


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    degrees = [int(p) for p in config.get("degrees", [1, 2, 3])]
    ns = [int(n) for n in config.get("n_per_side", [2, 4, 8] if quick else [2, 4, 8, 16])]
    x0 = np.asarray(config.get("x0", [1.5, 1.5]), dtype=float)
    extra = int(config.get("extra_quadrature_points", 10))
    if np.all((x0 >= 0) & (x0 <= 1)):
        raise ValueError(f"x0 must lie outside the closed unit square, got {x0.tolist()}")

    t0 = time.perf_counter()
    neumann_l2_error(1, 1, x0, extra)  # compile (or load the numba cache) once
    jit_s = time.perf_counter() - t0

    rows = []
    t_run = time.perf_counter()
    for p in degrees:
        prev = None
        for n in progress(ns, desc=f"p={p}"):
            t1 = time.perf_counter()
            err, dof = neumann_l2_error(p, n, x0, extra)
            wall = time.perf_counter() - t1
            h = 1.0 / n
            rate = np.nan if prev is None else np.log(prev[1] / err) / np.log(prev[0] / h)
            rows.append(dict(p=p, n_per_side=n, h=h, dof=dof, l2_error=err, l2_rate=rate,
                             wall_time_s=wall))
            log.info("p=%d n=%d dof=%d error=%.3e rate=%s", p, n, dof, err,
                     "-" if prev is None else f"{rate:.3f}")
            prev = (h, err)
    run_s = time.perf_counter() - t_run
    table = pd.DataFrame(rows)

    last = {p: table[table.p == p].l2_rate.iloc[-1] for p in degrees}
    holds = bool(all(np.isfinite(r) and abs(r - p) <= RATE_TOLERANCE for p, r in last.items()))
    evidence = "; ".join(f"p={p}: last observed rate {r:.3f} (expected {p})"
                         for p, r in last.items())
    evidence += (f" - all within {RATE_TOLERANCE} of p" if holds else
                 f" - not all within {RATE_TOLERANCE} of p (pre-asymptotic meshes or an "
                 "error in the operators)")
    claim = Claim(text="L2 error of the Neumann data converges like h^p", holds=holds,
                  evidence=evidence)

    fig = Figure(figsize=(6.0, 4.5))
    ax = fig.subplots()
    for p in degrees:
        sub = table[table.p == p]
        line, = ax.loglog(sub.h, sub.l2_error, "o-", label=f"p = {p}")
        h_ref = sub.h.to_numpy()
        e_ref = sub.l2_error.iloc[-1] * (h_ref / h_ref[-1]) ** p * 0.6
        ax.loglog(h_ref, e_ref, "--", color=line.get_color(), alpha=0.6,
                  label=f"$h^{p}$ (reference)")
    ax.set_xticks(1.0 / np.asarray(ns, dtype=float), [f"1/{n}" for n in ns])
    ax.minorticks_off()
    ax.set_xlabel("h = 1/n (n elements per side)")
    ax.set_ylabel(r"$\|\psi - \psi_h\|_{L^2(\Gamma)}$")
    ax.set_title("Laplace BEM, unit square: Neumann data, u = log|x - x0|")
    ax.invert_xaxis()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small", ncol=2)

    notes = (
        "Beyond the thesis: a pipeline demonstration. Interior Dirichlet problem on the "
        "unit square, u = log|x - x0|, x0 = ({:.3g}, {:.3g}); Neumann data psi_h in W_hp "
        "(degree p-1) from V psi = (K + 1/2) g with g the GLL interpolant in V_hp "
        "(degree p). L2(Gamma) error by {}-point Gauss quadrature beyond p per element. "
        "dof = dim W_hp = 4 n p. The first rate of each degree is empty (no previous "
        "mesh): l2_rate is allowed NaN there."
    ).format(x0[0], x0[1], extra)
    meta = dict(jit_s=round(jit_s, 3), run_s=round(run_s, 3),
                max_dof=int(table.dof.max()), allow_nan_columns=["l2_rate"],
                rate_tolerance=RATE_TOLERANCE)
    return [ArtefactResult(name="figure_bem_laplace", table=table, figure=fig,
                           keys=("p", "n_per_side"), claims=[claim], notes=notes,
                           meta=meta)]
