"""The model problems of Section 2.2.5: geometry, meshes and exact solutions.

* Example 1 (smooth, (2.10)-(2.12)): Omega = [-1,1]^2, Omega2 = [-1,0] x [-1/2,1/2] (BEM),
  Omega1 = Omega minus Omega2 (FEM), Gamma_D = {-1} x [-1,1],
  u = (x+1)/((x+1)^2+(y+2)^2) = -2 pi d/dx G((-1,-2), (x,y)), f = 0, t_hat = du/dn.
* Example 2 (singular, (2.13)-(2.15)): the L-shape Omega = [-1,1]^2 minus [0,1] x [-1,0],
  Omega2 = [-1/2,1/2]^2 minus [0,1/2] x [-1/2,0], Gamma_D = {0} x [-1,0] U [0,1] x {0},
  u = r^(2/3) sin(2 theta/3), theta in [0, 3 pi/2] measured from the positive x axis.

Meshes (the thesis gives only the sizes): the FE mesh of size 1/h_inv is the per-block
tensor grid of :func:`~hpfebe.fem.meshes.tensor_block_mesh`; the BE mesh of size 1/h_inv
puts ``ceil(|side| h_inv)`` equal elements on each side of the polygon dOmega2.  Sides of
dOmega2 on Gamma_D get the label "D", the others "I" (interface; neither example has a BE
Neumann part).  FE boundary facets are labelled "D", "I" (on dOmega2) or "N".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..fem.meshes import FEDomain, tensor_block_mesh
from ..geometry import BoundaryMesh

_TOL = 1e-12


@dataclass(frozen=True)
class InterfaceProblem:
    """An FE/BE interface problem (2.2) with known solution.

    ``u(x, y)``, ``grad_u(x, y) -> (ux, uy)`` and ``f(x, y)`` (None: f = 0) are vectorised.
    ``singular_points``: where grad u is unbounded (error integrals are graded there).
    """

    name: str
    u: Callable
    grad_u: Callable
    f: Callable | None
    xbreaks: tuple
    ybreaks: tuple
    in_omega1: Callable
    in_omega2: Callable
    fe_label: Callable
    be_vertices: tuple
    be_labels: tuple
    singular_points: tuple = ()

    def fe_domain(self, h_inv: float) -> FEDomain:
        """FE mesh of Omega1 with cells of size <= 1/h_inv (module doc)."""
        return tensor_block_mesh(self.xbreaks, self.ybreaks, h_inv, self.in_omega1,
                                 self.fe_label)

    def omega2_domain(self, h_inv: float) -> FEDomain:
        """Rectangle mesh of Omega2 of size 1/h_inv (for the BE-part domain errors)."""
        v = np.asarray(self.be_vertices, dtype=float)
        return tensor_block_mesh(np.unique(v[:, 0]), np.unique(v[:, 1]), h_inv,
                                 self.in_omega2, lambda x, y: np.full(np.shape(x), "B"))

    def be_mesh(self, h_inv: float, p: int) -> BoundaryMesh:
        """Boundary mesh of dOmega2 with elements of size <= 1/h_inv and degree p."""
        if not (np.isfinite(h_inv) and h_inv > 0):
            raise ValueError(f"h_inv must be positive, got {h_inv!r}")
        v = np.asarray(self.be_vertices, dtype=float)
        sides = np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
        n = [max(1, int(np.ceil(L * h_inv - 1e-9))) for L in sides]
        return BoundaryMesh.polygon(v, n=n, labels=list(self.be_labels), p=p)


# ----------------------------------------------------------------------- Example 1
def _u_smooth(x, y):
    a, b = x + 1.0, y + 2.0
    return a / (a * a + b * b)


def _grad_smooth(x, y):
    a, b = x + 1.0, y + 2.0
    r4 = (a * a + b * b) ** 2
    return (b * b - a * a) / r4, -2.0 * a * b / r4


def _in_omega2_smooth(x, y):
    return (x < 0.0) & (np.abs(y) < 0.5)


def _in_omega1_smooth(x, y):
    return ~_in_omega2_smooth(x, y)


def _label_smooth(x, y):
    lab = np.full(np.shape(x), "N", dtype="<U1")
    on_d = np.abs(x + 1.0) < _TOL
    on_omega2 = (((np.abs(x) < _TOL) & (np.abs(y) <= 0.5))
                 | ((np.abs(np.abs(y) - 0.5) < _TOL) & (x <= 0.0)))
    lab[on_omega2 & ~on_d] = "I"
    lab[on_d] = "D"
    return lab


SMOOTH = InterfaceProblem(
    name="smooth", u=_u_smooth, grad_u=_grad_smooth, f=None,
    xbreaks=(-1.0, 0.0, 1.0), ybreaks=(-1.0, -0.5, 0.5, 1.0),
    in_omega1=_in_omega1_smooth, in_omega2=_in_omega2_smooth, fe_label=_label_smooth,
    # counter-clockwise; side k joins vertex k and k+1; the side x = -1 is on Gamma_D
    be_vertices=((-1.0, -0.5), (0.0, -0.5), (0.0, 0.5), (-1.0, 0.5)),
    be_labels=("I", "I", "I", "D"),
)


# ----------------------------------------------------------------------- Example 2
def _theta(x, y):
    """Polar angle in [0, 2 pi) (the L-shape uses [0, 3 pi/2])."""
    return np.mod(np.arctan2(y, x), 2.0 * np.pi)


def _u_singular(x, y):
    r = np.hypot(x, y)
    return r ** (2.0 / 3.0) * np.sin(2.0 * _theta(x, y) / 3.0)


def _grad_singular(x, y):
    r = np.hypot(x, y)
    th = _theta(x, y)
    with np.errstate(divide="ignore"):
        c = (2.0 / 3.0) * r ** (-1.0 / 3.0)
    return -c * np.sin(th / 3.0), c * np.cos(th / 3.0)


def _in_omega2_singular(x, y):
    return (np.abs(x) < 0.5) & (np.abs(y) < 0.5) & ~((x > 0.0) & (y < 0.0))


def _in_omega1_singular(x, y):
    return ~((x > 0.0) & (y < 0.0)) & ~_in_omega2_singular(x, y)


def _label_singular(x, y):
    lab = np.full(np.shape(x), "N", dtype="<U1")
    on_d = ((np.abs(x) < _TOL) & (y < 0.0)) | ((np.abs(y) < _TOL) & (x > 0.0))
    on_omega2 = np.abs(np.maximum(np.abs(x), np.abs(y)) - 0.5) < _TOL
    lab[on_omega2 & ~on_d] = "I"
    lab[on_d] = "D"
    return lab


SINGULAR = InterfaceProblem(
    name="singular", u=_u_singular, grad_u=_grad_singular, f=None,
    xbreaks=(-1.0, -0.5, 0.0, 0.5, 1.0), ybreaks=(-1.0, -0.5, 0.0, 0.5, 1.0),
    in_omega1=_in_omega1_singular, in_omega2=_in_omega2_singular, fe_label=_label_singular,
    be_vertices=((0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (-0.5, 0.5), (-0.5, -0.5), (0.0, -0.5)),
    be_labels=("D", "I", "I", "I", "I", "D"),
    singular_points=((0.0, 0.0),),
)

PROBLEMS = {"smooth": SMOOTH, "singular": SINGULAR}


def problem(name: str) -> InterfaceProblem:
    """The model problem ``"smooth"`` (Example 1) or ``"singular"`` (Example 2)."""
    if name not in PROBLEMS:
        raise ValueError(f"problem must be one of {sorted(PROBLEMS)}, got {name!r}")
    return PROBLEMS[name]
