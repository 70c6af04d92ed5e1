"""Monolithic semismooth Newton method (primal-dual active set) for the discrete global
mortar contact problem of Algorithm 4.5 (beyond the thesis), on the linear response the
problem provides: in the node frames y = (P_n, P_t) the relative displacement is
d(y) = d0 - G y, and the complementarity functions

    P_n - max(0, z_n) = 0,   P_t - clip(z_t, -b, b) = 0,
    z_n = P_n + c (d_n - g),  z_t = P_t + c d_t,  b = mu_f max(0, z_n) or F,

are solved by :func:`hpfebe.solvers.newton` (line search on 1/2 |F|^2, cycling detection
on the active/stick pattern).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import integer, tolerance
from ..constitutive.laws import friction_projection, normal_projection
from .info import Iterate, SingularStep
from .newton import newton
from .uzawa import _set, check_friction


@dataclass(frozen=True)
class SemismoothSettings:
    """Tolerance and cap of the Newton iteration, the friction law ("coulomb" with the
    coefficient ``mu_f`` or "tresca" with the problem's bound F)."""

    tol: float = 1e-10
    max_iter: int = 100
    friction: str = "coulomb"
    mu_f: float = 0.1

    def __post_init__(self):
        check_friction(self)
        _set(self, "tol", tolerance("tol", self.tol))
        _set(self, "max_iter", integer("max_iter", self.max_iter, lo=1))


class _Complementarity:
    """The complementarity functions of the module doc as a Newton problem
    (:class:`hpfebe.solvers.NewtonProblem`)."""

    def __init__(self, d0, G, gap, F: float, c: float, settings: SemismoothSettings):
        self.nc = nc = gap.size
        self.d0, self.G, self.c, self.F = d0, G, c, F
        self.closed = np.isfinite(gap)
        self.gap = np.where(self.closed, gap, 0.0)
        self.coulomb, self.mu_f = settings.friction == "coulomb", settings.mu_f
        self.eye = np.eye(2 * nc)
        self.scale = max(float(np.abs(c * d0).max()), 1e-300)

    def evaluate(self, y):
        nc, c = self.nc, self.c
        d = self.d0 - self.G @ y
        zn = np.where(self.closed, y[:nc] + c * (d[:nc] - self.gap), -1.0)
        zt = y[nc:] + c * d[nc:]
        bnd = self.mu_f * normal_projection(zn) if self.coulomb else np.full(nc, self.F)
        Fr = np.concatenate([y[:nc] - normal_projection(zn),
                             y[nc:] - friction_projection(zt, bnd)])
        act, stick = zn > 0, np.abs(zt) < bnd
        return Iterate(y, Fr, 0.5 * float(Fr @ Fr), self.scale,
                       key=(act.tobytes(), stick.tobytes()),
                       data=(act, stick, np.sign(zt)))

    def step(self, it):
        nc, c, G, eye = self.nc, self.c, self.G, self.eye
        act, stick, sg = it.data
        J = eye.copy()
        rows_n = np.flatnonzero(act)
        J[rows_n] = c * G[rows_n]
        rows_t = nc + np.flatnonzero(stick)
        J[rows_t] = c * G[rows_t]
        if self.coulomb:
            slip = np.flatnonzero(~stick & act)
            # d b / d y = mu_f (e_n - c G[n, :]) on slipping, active nodes
            J[nc + slip] -= (sg[slip] * self.mu_f)[:, None] * (eye[slip] - c * G[slip])
        try:
            return np.linalg.solve(J, -it.residual)
        except np.linalg.LinAlgError as e:
            raise SingularStep(f"singular Newton matrix: {e}") from None

    def slope(self, it, dx):
        return -2.0 * it.merit


def semismooth_contact(d0, G, gap, F: float, c: float, settings: SemismoothSettings):
    """The semismooth Newton method of the module doc: ``d0`` the relative displacement
    at y = 0 and ``G`` its response (d = d0 - G y, node frames, normal components first),
    ``gap`` per node (+inf: no constraint), ``F`` the Tresca bound, ``c`` the
    complementarity parameter.  Returns (y, SolverInfo)."""
    problem = _Complementarity(np.asarray(d0, float), np.asarray(G, float),
                               np.asarray(gap, float), float(F), float(c), settings)
    it, info = newton(problem, np.zeros(2 * problem.nc), settings.tol, settings.max_iter,
                      norm=2)
    return it.x, info
