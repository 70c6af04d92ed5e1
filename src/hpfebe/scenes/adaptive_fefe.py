"""The FE/FE frictional contact scene of Section 4.2.8 (thesis lines 14920-15080,
Figures 4.13-4.16): slave Omega_s = [-1/2, 1/2] x [0, 2] with its top fixed (u_s = 0),
master Omega_m = [-2, 2] x [-2, 0] with its bottom displaced by u_m = (0, 5e-4) (read as
upward, both components prescribed), all other boundary parts possible contact (in
practice the slave's bottom meets the master's top; the slave's sides and the rest of the
master's top stay open), E = 266926, nu = 0.29, Coulomb mu_f = 0.1; P1 triangles in both
bodies, penalty contact by :class:`hpfebe.contact.TwoBodyContact` (Algorithm 4.1).

The features where the refinement should concentrate: the contact segment and the
corners where the boundary conditions change (:func:`feature_distance`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import array, choice, instance, integer, real
from ..constitutive import PLANES
from ..contact import ContactSettings, TwoBodyContact
from ..fem import ElasticBody, distance_to_set, rectangle_mesh
from .materials import FrictionalContactScene

BODIES = ("slave", "master")
BOX = {"slave": (-0.5, 0.5, 0.0, 2.0), "master": (-2.0, 2.0, -2.0, 0.0)}
#: possible contact boundary of each body (TwoBodyContact), the part that meets the
#: other body (contact datum of (3.100)) and the open, traction free rest
CONTACT_BOUNDARY = {"slave": ["bottom", "left", "right"], "master": ["top", "left", "right"]}
CONTACT = ("bottom", "top")
OPEN = (("left", "right"), ("left", "right"))
#: features of the concentration claims: the contact segment and the corners where the
#: boundary conditions change
CONTACT_SEGMENT = ((-0.5, 0.0), (0.5, 0.0))
FEATURE_POINTS = {
    "slave": [(-0.5, 0.0), (0.5, 0.0), (-0.5, 2.0), (0.5, 2.0)],
    "master": [(-0.5, 0.0), (0.5, 0.0), (-2.0, -2.0), (2.0, -2.0)],
}


@dataclass(frozen=True)
class FEFEContactScene(FrictionalContactScene):
    """The scene's data: the master's bottom lifted by (0, u_master), penalty
    1/eps_n = eps_n_factor E, 1/eps_t = eps_t_factor E, initial meshes of slave_cells and
    master_cells rectangles (2 triangles each; h0 = 1/4)."""

    u_master: float = 5.0e-4              # master bottom lifted (0, u_master)
    eps_n_factor: float = 10.0            # 1/eps_n = eps_n_factor E
    eps_t_factor: float = 5.0             # 1/eps_t = eps_t_factor E
    slave_cells: tuple[int, ...] = (4, 8)       # h0 = 1/4, 2 triangles per cell
    master_cells: tuple[int, ...] = (16, 8)

    def __post_init__(self):
        choice("plane", self.plane, PLANES)
        for name in ("slave_cells", "master_cells"):
            v = array(name, getattr(self, name), shape=(2,), dtype=int)
            if v.min() < 1:
                raise ValueError(f"{name} must be two positive cell counts, got "
                                 f"{getattr(self, name)!r}")
        for name in ("E", "u_master", "eps_n_factor", "eps_t_factor"):
            real(name, getattr(self, name), positive=True)
        real("nu", self.nu, lo=-1.0, hi=0.5, lo_open=True, hi_open=True)
        real("mu_f", self.mu_f, nonnegative=True)

    def initial_meshes(self) -> tuple:
        """Labelled triangulations ("left", "right", "bottom", "top") of both
        rectangles."""
        return tuple(rectangle_mesh(*BOX[b], *cells, kind="tri")
                     for b, cells in zip(BODIES, (self.slave_cells, self.master_cells)))

    def solve(self, meshes, load_steps: int, settings: ContactSettings):
        """The two-body problem on the meshes (slave, master), the lift applied in
        ``load_steps`` equal increments: (problem, result)."""
        n = integer("load_steps", load_steps, lo=1)
        instance("settings", settings, ContactSettings)
        S, M = (ElasticBody(m, self.E, self.nu, self.plane) for m in meshes)
        pr = TwoBodyContact(S, M, CONTACT_BOUNDARY["slave"], CONTACT_BOUNDARY["master"],
                            eps_n=1.0 / (self.eps_n_factor * self.E),
                            eps_t=1.0 / (self.eps_t_factor * self.E), mu_f=self.mu_f)
        fixed, is_y = pr.stamp_dofs()
        res = pr.solve(None, fixed, self.u_master * is_y,
                       load_factors=np.arange(1, n + 1) / n, settings=settings)
        return pr, res


def feature_distance(body: str):
    """Distance to the features of ``body`` (contact segment and corner points)."""
    return lambda p: distance_to_set(p, [CONTACT_SEGMENT], FEATURE_POINTS[body])
