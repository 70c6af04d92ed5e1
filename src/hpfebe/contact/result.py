"""The outcome of Algorithm 4.1 for a penalty contact problem (:class:`ContactResult`):
the displacement, the load path's diagnostics and the contact state at the points."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..constitutive.laws import SLIP, STATE_NAMES, STICK
from ..solvers import SolverInfo


@dataclass
class ContactResult:
    """Outcome of :meth:`~hpfebe.contact.TwoBodyContact.solve` (and of
    :func:`~hpfebe.contact.solve_friction`).

    Parameters
    ----------
    U, u_slave, u_master : ndarray
        the global dof vector (slave dofs first) and its two parts
    converged, reason : bool, str
        the overall outcome (the reason names the failed load step)
    info : SolverInfo
        of the load path; ``steps`` is its SolverInfo per attempted load step
        (load_factor, iterations, residuals, converged, reason, state_counts)
    points, weights : ndarray
        the slave contact points (n, 2) and their quadrature weights (0 for points
        outside the master); the contact state below is at these points, last iterate
    g_n, g_t : ndarray
        the signed gap (< 0 is penetration) and the relative tangential displacement
    p_n, t_t, bound : ndarray
        the contact pressure (>= 0), the tangential traction and the slip bound s
    state, slip : ndarray
        OPEN / STICK / SLIP, and g_t^p after the last converged step
    elements : ndarray, optional
        the slave element (BE) or facet (FE) of each point
    load_vector, obstacle_motion : ndarray, optional
        the load and the obstacle motion w of the last step (to continue loading with
        ``initial=``)
    friction : str
        "coulomb" or "tresca"
    passes : ndarray, optional
        the pass of each contact point (0: slave points on the master; 1, with
        ``two_pass``: master points on the slave, whose ``elements`` are master
        facets); ``weights * (passes == 0)`` integrates over the slave side only.  With
        two passes ``total_forces`` sums both (the physical total force)
    """

    U: np.ndarray
    u_slave: np.ndarray
    u_master: np.ndarray
    converged: bool
    reason: str
    info: SolverInfo
    points: np.ndarray
    weights: np.ndarray
    g_n: np.ndarray
    g_t: np.ndarray
    p_n: np.ndarray
    t_t: np.ndarray
    bound: np.ndarray
    state: np.ndarray
    slip: np.ndarray
    elements: np.ndarray = None
    load_vector: np.ndarray = None
    obstacle_motion: np.ndarray = None
    friction: str = "coulomb"
    passes: np.ndarray = None

    @property
    def steps(self) -> list:
        return self.info.steps

    @property
    def iterations(self) -> list:
        return [s.iterations for s in self.steps]

    @property
    def residuals(self) -> list:
        return [s.residuals for s in self.steps]

    residual_histories = residuals

    @property
    def state_names(self) -> list:
        return [STATE_NAMES[int(k)] for k in self.state]

    @property
    def stick(self) -> np.ndarray:
        return self.state == STICK

    @property
    def slipping(self) -> np.ndarray:
        return self.state == SLIP

    @property
    def gap_function(self) -> np.ndarray:
        """The penetration function U_n - g = -g_n (positive where the bodies overlap)."""
        return -self.g_n

    @property
    def rel_slip(self) -> np.ndarray:
        return self.g_t

    def total_forces(self) -> tuple[float, float]:
        """(int p_n ds, int t_t ds) over Gamma_C."""
        return float(self.weights @ self.p_n), float(self.weights @ self.t_t)
