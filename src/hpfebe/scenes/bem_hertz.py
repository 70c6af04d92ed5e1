"""Hertz contact of an elastic half-disk on a rigid flat, by the compressed Lame operators
(issue 27's showcase; beyond the thesis).

The lower half-disk {|x| < R, y < 0}, R = 1, plane strain, E and nu of Chapter 3
(:mod:`.materials`), is pressed onto the rigid line y = -R by the rigid displacement
(0, -delta) of its flat top side Gamma_D (Dirichlet: it also fixes the rigid modes);
the curved side Gamma_C carries normal penalty contact (3.45)-(3.46) with
eps = kappa h / E*, E* = E / (1 - nu^2), and the gap along the outward normal
n = x / |x| to the line, g(x) = (R + y) / (-n_y) (clamped at n_y = -GAP_NY_MIN near the
corners, far from contact).  p = 1, N elements of equal length along the boundary
(N_C on the arc, the rest on the top).  Solved by
:func:`hpfebe.contact.matrix_free.solve_penalty_mixed` (LameBEM with
``compression="hmatrix"``, ``zero_force=False``).

Readings against Hertz (plane strain, a cylinder on a half-space): with F the computed
total vertical force, a_H = sqrt(4 F R / (pi E*)), p0_H = 2 F / (pi a_H); a is the
half-width of the computed contact set (exact roots of U_n - g_h), p0 the largest nodal
pressure (1/eps)(U_n - g_h)_+.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..bem import LameBEM
from ..checks import integer, real
from ..contact.matrix_free import solve_penalty_mixed
from ..geometry import BoundaryMesh
from .materials import E, NU

__all__ = ["HertzRun", "half_disk", "gap", "hertz", "solve", "R", "GAP_NY_MIN"]

R = 1.0
GAP_NY_MIN = 1e-2


@dataclass(frozen=True)
class HertzRun:
    """One run: ``n_elements`` N >= 16, ``delta`` > 0 the prescribed displacement of the
    top, ``kappa`` > 0 of eps = kappa h / E*, ``tol`` the H-matrix tolerance and the
    Newton backward error, ``dense``: the dense LameBEM and solve_penalty instead (small
    N only, for the comparison)."""

    n_elements: int = 256
    delta: float = 5e-3
    kappa: float = 1.0
    tol: float = 1e-6

    def __post_init__(self):
        integer("n_elements", self.n_elements, lo=16)
        real("delta", self.delta, positive=True)
        real("kappa", self.kappa, positive=True)
        real("tol", self.tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True)

    @property
    def n_arc(self) -> int:
        return int(round(self.n_elements * np.pi / (np.pi + 2.0)))

    @property
    def h(self) -> float:
        return np.pi * R / self.n_arc

    @property
    def e_star(self) -> float:
        return E / (1.0 - NU ** 2)

    @property
    def eps(self) -> float:
        return self.kappa * self.h / self.e_star


def half_disk(n_elements: int) -> BoundaryMesh:
    """The lower half-disk: N_C equal chords on the arc (label "C", counter-clockwise
    from (-R, 0) through (0, -R)), the rest on the top (label "D")."""
    run = HertzRun(n_elements)
    nc = run.n_arc
    nd = n_elements - nc
    th = np.pi + np.pi * np.arange(nc) / nc
    top = np.column_stack([R - 2.0 * R * np.arange(nd) / nd, np.zeros(nd)])
    nodes = np.vstack([R * np.column_stack([np.cos(th), np.sin(th)]), top])
    seg = np.column_stack([np.arange(n_elements), (np.arange(n_elements) + 1) % n_elements])
    return BoundaryMesh.from_segments(nodes, seg, ["C"] * nc + ["D"] * nd, 1)


def gap(x: np.ndarray) -> np.ndarray:
    """(R + y) / (-n_y), n = x / |x|: the distance along the normal to y = -R."""
    x = np.asarray(x, float)
    ny = x[:, 1] / np.linalg.norm(x, axis=1)
    return (R + x[:, 1]) / np.maximum(-ny, GAP_NY_MIN)


def hertz(F: float, e_star: float) -> tuple[float, float]:
    """(a_H, p0_H) of Hertz's plane-strain line contact for the force F per length."""
    a = np.sqrt(4.0 * F * R / (np.pi * e_star))
    return float(a), float(2.0 * F / (np.pi * a))


def solve(run: HertzRun, compression: str | None = "hmatrix",
          preconditioner: str = "auto") -> dict:
    """One run: the readings (a, p0, F, Hertz's, relative errors), CPU seconds, Newton
    and GMRES iterations, backward errors, the preconditioner used (compressed: that of
    :func:`solve_penalty_mixed`); ``U`` and the nodal pressure profile."""
    t0 = time.process_time()
    mesh = half_disk(run.n_elements)
    if compression is None:     # the dense path (:func:`solve_penalty`), small N
        from ..contact.penalty import solve_penalty
        from ..contact.matrix_free import PenaltyP1
        bem = LameBEM(mesh, E, NU, zero_force=False)
        n = 2 * bem.V_space.ndof
        lift = np.zeros(n)
        lift[2 * np.asarray(bem.V_space.dofs_on("D")) + 1] = -run.delta
        S = bem.S_hat
        res = solve_penalty(bem, run.eps, gap, load=-(S @ lift), S=S, tol=1e-12)
        U, converged, its = res.U + lift, res.converged, res.iterations
        pen = PenaltyP1(mesh, bem.V_space, np.flatnonzero(mesh.where("C")), gap)
        extra = dict(gmres_iterations=0, backward_error=np.nan, reason=res.reason,
                     gmres_per_step=[], times={}, preconditioner="dense LU")
    else:
        bem = LameBEM(mesh, E, NU, zero_force=False, compression=compression, tol=run.tol)
        t1 = time.process_time()
        for name in ("V", "K", "W"):
            bem.hm.hmatrix(name)
        assembly = time.process_time() - t1
        res = solve_penalty_mixed(bem, run.eps, gap, (0.0, -run.delta), tol=run.tol,
                                  preconditioner=preconditioner)
        U, converged, its, pen = res.U, res.converged, res.iterations, res.contact
        extra = dict(gmres_iterations=int(sum(res.gmres_iterations)),
                     backward_error=max(res.backward_errors), reason=res.reason,
                     gmres_per_step=list(res.gmres_iterations),
                     preconditioner=res.preconditioner,
                     times=dict(assembly_s=assembly, **res.times))
    cpu = time.process_time() - t0
    xs = pen.half_width(U)
    if xs is None:
        raise ValueError(f"delta = {run.delta}: no contact")
    a = 0.5 * (xs[1] - xs[0])
    F = pen.vertical_force(U, run.eps)
    w = pen.penetration(U)
    p0 = float(np.maximum(w, 0.0).max()) / run.eps
    aH, p0H = hertz(F, run.e_star)
    # each node ends one contact element and starts the next: its pressure once
    x_nodes, first = np.unique(np.concatenate([pen.a[:, 0], pen.b[:, 0]]),
                               return_index=True)
    p_nodes = np.maximum(np.concatenate([w[:, 0], w[:, 1]])[first], 0.0) / run.eps
    return dict(N=run.n_elements, h=run.h, delta=run.delta, eps=run.eps, a=a, p0=p0, F=F,
                a_hertz=aH, p0_hertz=p0H, err_a=abs(a - aH) / aH,
                err_p0=abs(p0 - p0H) / p0H, cpu_s=cpu, newton=its, converged=converged,
                U=U, profile=(x_nodes, p_nodes), **extra)
