r"""The mixed boundary value problem of the Laplace and Lame equations by the BEM, with
inhomogeneous Dirichlet and Neumann data.

Problem (Section 1.3): Gamma = Gamma_D + Gamma_N (boundary labels), for Laplace
(u scalar, t = du/dn) or Lame (u in R^2, t = sigma(u) n),

.. math::

   -\Delta u = 0 \ \text{resp.}\ -\operatorname{div}\sigma(u) = 0 \ \text{in } \Omega,
   \qquad u = g \ \text{on } \Gamma_D, \qquad t(u) = t_N \ \text{on } \Gamma_N.

Discretisation: the primal formulation with the discrete Steklov-Poincare operator of
Section 1.4 (:attr:`~hpfebe.bem.operators.BoundaryOperators.S_hat`,
S_hat = W + (K + M/2)^T V^{-1} (K + M/2), and the zero-flux / zero-force variant of the
operator classes), the inhomogeneous form of (3.95): find U in V_hp (V_hp^2) with
U = I_h g at the dofs of Gamma_D (closure: the vertex functions at the ends of Gamma_D
included) and

.. math::

   \langle \hat S U, v\rangle = \int_{\Gamma_N} t_N\, v\, ds
   \qquad \text{for all } v \in V_{hp} \text{ vanishing on } \Gamma_D.        \tag{M}

With the lift U_D = I_h g on the Dirichlet dofs D and the free dofs F, (M) is the
symmetric positive definite system S_FF U_F = F_F - S_FD U_D (Gamma_D of positive
length fixes the constants, resp. the rigid motions, of the kernel of S_hat).  The
Neumann trace on all of Gamma (the unknown flux / traction on Gamma_D included) is
Psi = V^{-1} (K + M/2) U in W_hp (:meth:`~hpfebe.bem.operators.BoundaryOperators.Psi`),
and the field inside is the representation formula of (U, Psi)
(:func:`hpfebe.io.interior_vtu`).

Errors: for a smooth solution and uniform h-refinement at degree p the energy error
||u - U||_{H^1/2} + ||t - Psi||_{H^-1/2} is O(h^{p + 1/2}) (Section 1.4); the boundary
L2 error of U observed in the tests and the gallery is O(h^{p+1}).  Solutions in the
spaces (harmonic polynomials of degree p, Navier fields of degree p, whose traces lie in
V_hp and whose Neumann data lie in W_hp) are reproduced to round-off.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla

from .. import checks
from ..quadrature import gauss_legendre, gauss_lobatto
from .lame import LameBEM
from .laplace import LaplaceBEM

__all__ = ["MixedData", "MixedSolution", "solve_mixed"]


@dataclass(frozen=True)
class MixedData:
    """The data of the mixed problem.

    Parameters
    ----------
    dirichlet : tuple of str
        the boundary labels of Gamma_D (default ``("D",)``); every other element is on
        Gamma_N
    g : callable, optional
        the Dirichlet datum ``g(x)`` for points x of shape (n, 2): shape (n,) (Laplace)
        or (n, 2) (Lame); called on Gamma_D only; None: g = 0
    t : callable, optional
        the Neumann datum ``t(x, n)`` (flux du/dn, or traction sigma(u) n) with the
        outward normals n of shape (n, 2): shape (n,) or (n, 2); called on Gamma_N only;
        None: t = 0
    extra : int
        the load integrals use p_I + ``extra`` Gauss points per element (default 6)
    """

    dirichlet: tuple[str, ...] = ("D",)
    g: Callable | None = None
    t: Callable | None = None
    extra: int = 6

    def __post_init__(self):
        labels = (self.dirichlet,) if isinstance(self.dirichlet, str) else self.dirichlet
        if not (isinstance(labels, (tuple, list)) and labels
                and all(isinstance(lb, str) for lb in labels)):
            raise checks.InputTypeError(f"dirichlet must be a non-empty tuple of labels, "
                                        f"got {self.dirichlet!r}")
        object.__setattr__(self, "dirichlet", tuple(labels))
        for name in ("g", "t"):
            f = getattr(self, name)
            if f is not None and not callable(f):
                raise checks.InputTypeError(f"{name} must be a callable or None, got "
                                            f"{type(f).__name__}")
        checks.integer("extra", self.extra, lo=0, hi=40)


@dataclass(frozen=True)
class MixedSolution:
    """The discrete solution of the mixed problem.

    Attributes
    ----------
    U : ndarray
        the Dirichlet trace in V_hp (Lame: V_hp^2, interleaved), U = I_h g on Gamma_D
    Psi : ndarray
        the Neumann trace in W_hp (W_hp^2) on all of Gamma, Psi = V^{-1} (K + M/2) U
    dirichlet_dofs, free_dofs : ndarray
        the prescribed and the computed entries of U
    """

    U: np.ndarray
    Psi: np.ndarray
    dirichlet_dofs: np.ndarray
    free_dofs: np.ndarray


def _dirichlet_lift(op, g, on: np.ndarray, d: int) -> np.ndarray:
    """U_D: the nodal interpolant of g at the Gauss-Lobatto points of the Gamma_D
    elements (g called there only), interleaved for d = 2."""
    mesh, V = op.mesh, op.V_space
    U = np.zeros((V.ndof, d))
    for p in np.unique(mesh.degrees[on]):
        p = int(p)
        els = np.flatnonzero(on & (mesh.degrees == p))
        xp, _ = gauss_lobatto(p + 1)
        pts = mesh.points(els[:, None], xp[None, :]).reshape(-1, 2)
        vals = g(pts).reshape(len(els), p + 1, d)
        dofs = V.elem_dofs[els, :p + 1]
        U[dofs[dofs >= 0]] = vals[dofs >= 0]
    return U.ravel()


def _neumann_load(op, t, on: np.ndarray, d: int, extra: int) -> np.ndarray:
    """F_j = int_{Gamma_N} t_N . v_j ds for the basis v_j of V_hp (V_hp^2, interleaved),
    by p_I + ``extra`` Gauss points on every Gamma_N element."""
    mesh, V = op.mesh, op.V_space
    F = np.zeros(d * V.ndof)
    for p in np.unique(mesh.degrees[on]):
        els = np.flatnonzero(on & (mesh.degrees == p))
        tq, wq = gauss_legendre(int(p) + extra)
        elem = np.repeat(els, len(tq))
        tt = np.tile(tq, len(els))
        vals = t(mesh.points(elem, tt), mesh.normals[elem]).reshape(-1, d)
        ds = np.tile(wq, len(els)) * mesh.lengths[elem] / 2.0
        F += V.trace_matrix(elem, tt, components=d).T @ (vals * ds[:, None]).ravel()
    return F


def solve_mixed(op, data: MixedData) -> MixedSolution:
    """Solve the mixed problem (M) of the module docstring.

    Parameters
    ----------
    op : LaplaceBEM or LameBEM
        the boundary element operators of the body (its mesh carries the labels)
    data : MixedData
        Gamma_D's labels and the data g, t_N

    Returns
    -------
    MixedSolution
        U (the Dirichlet trace, V_hp or V_hp^2) and Psi (the Neumann trace on all of
        Gamma, W_hp or W_hp^2), interleaved for Lame.

    Raises
    ------
    ValueError
        if the Dirichlet labels select no element (the pure Neumann problem is not
        handled here: its solution is unique only up to the kernel of S_hat), or the data
        return arrays of the wrong shape or non-finite values.
    """
    checks.instance("op", op, (LaplaceBEM, LameBEM), "a LaplaceBEM or LameBEM")
    checks.instance("data", data, MixedData)
    d = 2 if isinstance(op, LameBEM) else 1
    mesh, V = op.mesh, op.V_space
    on_D = mesh.where(*data.dirichlet)
    if not np.any(on_D):
        raise ValueError(f"dirichlet labels {data.dirichlet!r} select no element (labels "
                         f"of the mesh: {sorted(set(mesh.labels.tolist()))}): the pure "
                         "Neumann problem is not handled here")
    shape = (lambda x: (len(x),)) if d == 1 else (lambda x: (len(x), 2))
    D = V.dofs_on(*data.dirichlet)
    if d == 2:
        D = np.column_stack([2 * D, 2 * D + 1]).ravel()
    free = np.setdiff1d(np.arange(d * V.ndof), D)
    U = np.zeros(d * V.ndof)
    if data.g is not None:
        U[D] = _dirichlet_lift(op, checks.callable_returning("g", data.g, None, shape),
                               on_D, d)[D]
    F = np.zeros(d * V.ndof)
    if data.t is not None and not np.all(on_D):
        F = _neumann_load(op, checks.callable_returning("t", data.t, None, shape),
                          ~on_D, d, data.extra)
    if free.size:
        S = op.S_hat
        rhs = F[free] - S[np.ix_(free, D)] @ U[D]
        U[free] = sla.solve(S[np.ix_(free, free)], rhs, assume_a="pos")
    return MixedSolution(U=U, Psi=op.Psi(U), dirichlet_dofs=D, free_dofs=free)
