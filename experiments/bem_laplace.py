"""Laplace BEM on the unit square: convergence of the Neumann data (beyond the thesis).

A demonstration of the whole pipeline (core -> experiment -> results -> report), not an
artefact of the thesis.  The interior Dirichlet problem of the Laplacian on (0,1)^2 with
the harmonic solution u(x) = log|x - x0|, x0 = (1.5, 1.5) outside the closed square, is
solved for its Neumann data psi = du/dn through the Calderon identity of Section 1.4,
V psi = (K + 1/2) u (:meth:`hpfebe.bem.LaplaceBEM.Psi`), with the Dirichlet data replaced
by its Gauss-Lobatto interpolant in V_hp (degree p) and psi sought in W_hp (discontinuous,
degree p - 1).  The exact psi = (x - x0) . n_I / |x - x0|^2 jumps at the corners, which
are element ends.  Expected: ||psi - psi_h||_L2 = O(h^p), the best approximation order of
W_hp in L2.  The choices (the thesis has no such experiment): :data:`CHOICES`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from hpfebe import BoundaryMesh
from hpfebe.analysis import boundary_l2_error, observed_rates
from hpfebe.bem import LaplaceBEM
from hpfebe.suite import (ArtefactResult, from_config, joint_claim, new_figure, progress,
                          rate_claim, slope_line, style_axes, timed)

ARTEFACTS = ("figure_bem_laplace",)

CHOICES = (
    "L2(Gamma) error by Gauss-Legendre quadrature with p + extra_quadrature_points points "
    "per element (the integrand is smooth on each element, so this is exact to rounding "
    "for these meshes).",
    "Uniform meshes with n elements per side, h = 1/n.",
    "dof = dimension of W_hp (= 4 n p, equal to the dimension of V_hp on a closed curve).",
    "rate = log(e_prev / e) / log(h_prev / h) (log2 of the error ratio when n doubles).",
    "LaplaceBEM defaults: kernel length scale = diameter of the mesh, Psi constrained to "
    "zero total flux (the exact Neumann data of a harmonic function has zero flux).",
)
SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
RATE_TOLERANCE = 0.15
QUICK_N_PER_SIDE = (2, 4, 8)     # without a config value in quick mode


@dataclass(frozen=True)
class Params:
    degrees: tuple[int, ...] = (1, 2, 3)
    n_per_side: tuple[int, ...] = (2, 4, 8, 16)
    x0: tuple[float, ...] = (1.5, 1.5)        # singularity of u = log|x - x0|
    extra_quadrature_points: int = 10         # Gauss points per element beyond p

    def __post_init__(self):
        x0 = np.asarray(self.x0, dtype=float)
        if x0.shape != (2,) or np.all((x0 >= 0) & (x0 <= 1)):
            raise ValueError(f"x0 must be a point outside the closed unit square, got "
                             f"{list(self.x0)}")
        if not self.degrees or min(self.degrees) < 1 or min(self.n_per_side, default=0) < 1:
            raise ValueError(f"degrees and n_per_side must be >= 1, got {self.degrees}, "
                             f"{self.n_per_side}")


def neumann_l2_error(degree: int, n: int, x0: np.ndarray, extra_points: int = 10):
    """Solve on the unit square with n elements per side and degree p; return
    (L2 error of the Neumann data, dof)."""
    mesh = BoundaryMesh.polygon(SQUARE, n=n, p=degree)
    op = LaplaceBEM(mesh)
    g = op.V_space.interpolate(lambda x: np.log(np.linalg.norm(x - x0, axis=1)))
    psi = op.Psi(g)

    def flux(x, nrm):
        d = x - x0
        return np.einsum("ij,ij->i", d, nrm) / np.einsum("ij,ij->i", d, d)

    return boundary_l2_error(op.W_space, psi, flux, extra=extra_points), op.W_space.ndof


def _sweep(p: int, ns, x0, extra) -> pd.DataFrame:
    """Errors and observed rates of degree p on the meshes n = ns."""
    rows = []
    for n in progress(ns, desc=f"p={p}"):
        (err, dof), seconds = timed(neumann_l2_error, p, n, x0, extra)
        rows.append(dict(p=p, n_per_side=n, h=1.0 / n, dof=dof, l2_error=err,
                         wall_time_s=seconds))
    t = pd.DataFrame(rows)
    t.insert(5, "l2_rate", observed_rates(t.h.to_numpy(), t.l2_error.to_numpy()))
    return t


def _figure(table, degrees, ns):
    fig, ax = new_figure((6.0, 4.5))
    for p in degrees:
        sub = table[table.p == p]
        line, = ax.loglog(sub.h, sub.l2_error, "o-", label=f"p = {p}")
        slope_line(ax, sub.h, p, (sub.h.iloc[-1], 0.6 * sub.l2_error.iloc[-1]), "--",
                   color=line.get_color(), alpha=0.6, label=f"$h^{p}$ (reference)")
    ax.set_xticks(1.0 / np.asarray(ns, dtype=float), [f"1/{n}" for n in ns])
    ax.minorticks_off()
    ax.invert_xaxis()
    style_axes(ax, "h = 1/n (n elements per side)", r"$\|\psi - \psi_h\|_{L^2(\Gamma)}$",
               "Laplace BEM, unit square: Neumann data, u = log|x - x0|",
               legend=dict(fontsize="small", ncol=2))
    return fig


def _notes(x0, extra):
    return (
        "Beyond the thesis: a pipeline demonstration. Interior Dirichlet problem on the "
        "unit square, u = log|x - x0|, x0 = ({:.3g}, {:.3g}); Neumann data psi_h in W_hp "
        "(degree p-1) from V psi = (K + 1/2) g with g the GLL interpolant in V_hp "
        "(degree p). L2(Gamma) error by {}-point Gauss quadrature beyond p per element. "
        "dof = dim W_hp = 4 n p. The first rate of each degree is empty (no previous "
        "mesh): l2_rate is allowed NaN there. Choices: "
    ).format(x0[0], x0[1], extra) + " ".join(CHOICES)


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    prm = from_config(Params, config, scene="bem_laplace")
    if quick and "n_per_side" not in (config or {}):
        prm = replace(prm, n_per_side=QUICK_N_PER_SIDE)
    degrees, ns = prm.degrees, prm.n_per_side
    x0, extra = np.asarray(prm.x0, dtype=float), prm.extra_quadrature_points

    jit_s = timed(neumann_l2_error, 1, 1, x0, extra)[1]  # compile (or load the numba cache)
    table, run_s = timed(lambda: pd.concat([_sweep(p, ns, x0, extra) for p in degrees],
                                           ignore_index=True))
    claim = replace(joint_claim(
        "L2 error of the Neumann data converges like h^p",
        *(rate_claim("", table[table.p == p].l2_rate.iloc[-1], p, RATE_TOLERANCE,
                     f"rate for p={p}") for p in degrees),
        note="the last rate of each degree; a miss means pre-asymptotic meshes or an error "
             "in the operators"), kind="beyond")   # not an artefact of the thesis
    return [ArtefactResult(name="figure_bem_laplace", table=table,
                           figure=_figure(table, degrees, ns), keys=("p", "n_per_side"),
                           claims=[claim], notes=_notes(x0, extra),
                           meta=dict(jit_s=round(jit_s, 3), run_s=round(run_s, 3),
                                     max_dof=int(table.dof.max()),
                                     allow_nan_columns=["l2_rate"],
                                     rate_tolerance=RATE_TOLERANCE))]
