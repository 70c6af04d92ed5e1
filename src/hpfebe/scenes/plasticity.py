"""The two stamping examples of Section 4.2.7 (thesis lines 14810-14920, Figures
4.1-4.12) as scenes: the work piece, the stamp positions, the characteristic points X
and the runs of one example (all its touches with one stamp discretisation, hardening
theta and mesh size) on :func:`hpfebe.scenes.stamping.touch` / :func:`touch_be`.

Example 1: the stamp (slave, elastic) at [0.2, 1.2] x [-1, 1] for the first touch and at
[-1.8, -0.8] x [-1, 1] for the second, its top fixed; work piece (master,
elastoplastic) [-2, 2] x [-3, -1], its bottom lifted by 4.3e-3 in increments;
X = (-0.9, -1.1).  Example 2: one touch of the stamp [-1, 1] x [-1, 0], lift 4.2e-3;
X = (1, -1.1); BE/BE: the plastic BE work piece of Section 4.2.4 under a BE stamp.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from ..checks import choice, integer, real
from ..constitutive.j2 import J2Material
from ..contact import LU_ORDERINGS, ContactSettings
from .materials import E, H, NU, SIGMA_Y
from .stamping import (StampContact, be_work_piece, curve_difference, stamp_body, touch,
                       touch_be, work_piece)

WORK = (-2.0, 2.0, -3.0, -1.0)
STAMPS = {1: ((0.2, 1.2, -1.0, 1.0), (-1.8, -0.8, -1.0, 1.0)), 2: ((-1.0, 1.0, -1.0, 0.0),)}
POINT = {1: (-0.9, -1.1), 2: (1.0, -1.1)}

log = logging.getLogger(__name__)


@dataclass
class Run:
    """All touches of one example: the stamp discretisation ("FE", "BE" or "BE/BE"),
    theta, h, the work piece's formulation (or BE/BE cells), the work piece itself
    (its committed state after the last touch), the :class:`TouchResult` of every
    touch and the wall time."""

    example: int
    stamp: str
    theta: float
    h: float
    formulation: str
    fe: object
    touches: list
    wall_s: float

    @property
    def converged(self) -> bool:
        return all(t.converged for t in self.touches)

    @property
    def records(self) -> list:
        return [r for t in self.touches for r in t.records]

    def curve(self, touch_id=None) -> np.ndarray:
        """||dev sigma|| at X of every record (of touch ``touch_id``)."""
        return np.array([r.dev_sigma_X for r in self.records
                         if touch_id is None or r.touch == touch_id])

    def load_curve(self, attr: str = "dev_sigma_X") -> np.ndarray:
        """``attr`` of the loading records (the unloading ones left out)."""
        return np.array([getattr(r, attr) for r in self.records if r.phase == "load"])


def run_difference(a: Run, b: Run, curve=None) -> float | None:
    """curve_difference of two runs' curves (``curve``: default all records of
    ||dev sigma|| at X), None unless both runs converged (their records differ in
    length otherwise)."""
    curve = curve or Run.curve
    return curve_difference(curve(a), curve(b)) if a.converged and b.converged else None


@dataclass(frozen=True)
class StampingScene:
    """The data of both examples: the material (E, nu, sigma_Y, H of Sections 4.2-4.4),
    penalty and friction (1/eps = factor x E, Coulomb mu_f), the Newton settings of a
    touch, the load path (n_load increments up, n_unload down; lifts ex1_u, ex2_u), the
    BE stamp's degree, the BE/BE cells and the sparse LU ordering."""

    E: float = E
    nu: float = NU
    sigma_Y: float = SIGMA_Y
    H: float = H
    mu_f: float = 0.2
    eps_n_factor: float = 10.0
    eps_t_factor: float = 5.0
    rtol: float = 1e-8
    max_newton: int = 40
    max_cuts: int = 4
    predictor: bool = True               # bonded predictor of TwoBodyContact per increment
    n_load: int = 10
    n_unload: int = 2
    ex1_u: float = 4.3e-3
    ex2_u: float = 4.2e-3
    be_degree: int = 1
    bebe_cells: str = "crossed"
    lu_ordering: str = "MMD_AT_PLUS_A"   # sparse LU ordering (ContactSettings)

    def __post_init__(self):
        choice("lu_ordering", self.lu_ordering, LU_ORDERINGS)
        choice("bebe_cells", self.bebe_cells, ("quad", "crossed"))
        for name in ("ex1_u", "ex2_u"):
            real(name, getattr(self, name), positive=True)
        integer("n_load", self.n_load, lo=1)
        integer("n_unload", self.n_unload, lo=0)
        integer("be_degree", self.be_degree, lo=1)
        # the material (every theta) and the contact settings are checked now, not at
        # the first run
        self.material(1.0)
        self.settings  # noqa: B018 (validates mu_f, the penalty and Newton settings)

    @property
    def settings(self) -> StampContact:
        """The penalty contact and Newton settings of every touch."""
        return StampContact(self.eps_n_factor, self.eps_t_factor, self.mu_f,
                            solver=ContactSettings(
                                rtol=self.rtol, max_iter=self.max_newton,
                                max_cuts=self.max_cuts, line_search=True,
                                predictor=self.predictor, lu_ordering=self.lu_ordering))

    def material(self, theta: float) -> J2Material:
        return J2Material(self.E, self.nu, self.sigma_Y, self.H, theta)

    def lift(self, example: int) -> float:
        return self.ex1_u if example == 1 else self.ex2_u

    def run_example(self, example: int, stamp: str, theta: float, h: float,
                    formulation: str = "bbar") -> Run:
        """All touches of one example with one stamp discretisation, theta and mesh
        size; a failed touch ends the run (with a warning)."""
        t0 = time.perf_counter()
        fe = work_piece(WORK, h, self.material(theta), formulation)
        touches, offset = [], None
        for k, box in enumerate(STAMPS[example], start=1):
            body = stamp_body(stamp, box, h, self.E, self.nu, p=self.be_degree)
            tr = touch(body, fe, self.lift(example), self.n_load, self.n_unload,
                       POINT[example], self.settings, offset=offset, touch_id=k)
            touches.append(tr)
            if not tr.converged:
                log.warning("example %d %s theta=%g h=%g: %s", example, stamp, theta, h,
                            tr.reason)
                break
            offset = tr.u_work
        return Run(example, stamp, theta, h, formulation, fe, touches,
                   time.perf_counter() - t0)

    def run_bebe(self, theta: float, h: float) -> Run:
        """Example 2 with the BE work piece (cells of size h) under a BE stamp
        (degree 1), loading only."""
        t0 = time.perf_counter()
        be = be_work_piece(WORK, h, self.material(theta), self.bebe_cells)
        body = stamp_body("BE", STAMPS[2][0], h, self.E, self.nu, p=1)
        tr = touch_be(body, be, self.ex2_u, self.n_load, POINT[2], self.settings)
        if not tr.converged:
            log.warning("BE/BE theta=%g h=%g: %s", theta, h, tr.reason)
        return Run(2, "BE/BE", theta, h, self.bebe_cells, be, [tr],
                   time.perf_counter() - t0)


def bebe_vs_fe(bebe: dict):
    """BE/BE fields and top displacement against FE/FE on the same grid at the peak
    (``bebe``: {"BE/BE": Run, "FE/FE": Run}): (FE element areas, BE ||eps_p|| averaged
    over the cells in each FE element (area weights; every cell lies in one element),
    FE element mean ||eps_p||, BE top u_y, FE top u_y)."""
    be, fe = bebe["BE/BE"].fe, bebe["FE/FE"].fe
    el = np.array([fe.elements_at(c)[0] for c in be.cells.centroids])
    sb, sf = bebe["BE/BE"].touches[0].peak, bebe["FE/FE"].touches[0].peak
    w = np.bincount(el, be.cells.areas, minlength=fe.nel)
    eb = np.bincount(el, be.cells.areas * sb.fields["eps_p_norm"], minlength=fe.nel) / w
    ef = sf.fields["eps_p_norm"]
    nodes = be.cells.nodes
    top = np.flatnonzero(np.isclose(nodes[:, 1], WORK[3]))
    xf = fe.mesh.p[:, fe.elastic.boundary_vertices("top")]
    uf = fe.elastic.nodal_displacement(sf.u_work)[1, fe.elastic.boundary_vertices("top")]
    ufe = np.interp(nodes[top, 0], xf[0][np.argsort(xf[0])], uf[np.argsort(xf[0])])
    return w, eb, ef, sb.fields["node_u"][top, 1], ufe
