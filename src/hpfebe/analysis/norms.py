"""Error norms of boundary element solutions against exact data.

Exact data are callables ``f(x, n)`` of points x (m, 2) and outward unit normals n (m, 2)
(so that a Neumann datum grad u . n can be written directly).

Energy norms use a richer space on the same mesh: the exact function is projected
(W_hp) or interpolated (V_hp) at degree p_I + ``extra`` - for data that are smooth on
each element this adds an error of higher order than the one measured - and the discrete
solution is embedded exactly (the spaces are nested).  Then

* ||psi - psi_h||_V = <V e, e>^(1/2)          (H^-1/2(Gamma)-equivalent, Neumann data),
* |u - u_h|_W      = <W e, e>^(1/2)          (H^1/2(Gamma) seminorm, Dirichlet data),

with V, W of the richer space (same kernel scale as the operator passed in).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..quadrature import gauss_legendre
from ..spaces import ContinuousSpace, DiscontinuousSpace, legendre_values


def energy_norm(S, U) -> float:
    """sqrt(max(U . S U, 0)) for a symmetric positive semi-definite S (dense or sparse):
    round-off can make U . S U slightly negative when U is nearly in the kernel."""
    U = np.asarray(U, dtype=float)
    if U.ndim != 1 or S.shape != (U.size, U.size):
        raise ValueError(f"S must be square of the size of U; got S {S.shape}, U {U.shape}")
    return float(np.sqrt(max(float(U @ S @ U), 0.0)))


def _points(mesh, nq: int):
    """Gauss points of every element: elem (ne*nq,), t, x (.,2), n (.,2), weights ds."""
    t, w = gauss_legendre(nq)
    ne = mesh.n_elements
    elem = np.repeat(np.arange(ne), nq)
    tt = np.tile(t, ne)
    x = mesh.points(elem, tt)
    n = mesh.normals[elem]
    ds = np.tile(w, ne) * mesh.lengths[elem] / 2.0
    return elem, tt, x, n, ds


def boundary_l2_error(space, coeffs, exact, extra: int = 6) -> float:
    """||exact - U_h||_{L2(Gamma)} by Gauss quadrature with p_max + ``extra`` points."""
    nq = int(space.mesh.degrees.max()) + extra
    elem, t, x, n, ds = _points(space.mesh, nq)
    diff = np.asarray(exact(x, n), dtype=float) - space.evaluate(coeffs, elem, t)
    return float(np.sqrt(np.sum(ds * diff**2)))


def _degree_groups(mesh, f, extra: int):
    """Per degree p of the mesh: the elements of that degree, a Gauss rule with p + extra
    points on [-1, 1], and the values f(x, n) at its points, shape (n_elements, n_points)."""
    for p in np.unique(mesh.degrees):
        p = int(p)
        els = np.flatnonzero(mesh.degrees == p)
        t, w = gauss_legendre(p + extra)
        x = mesh.points(els[:, None], t[None, :]).reshape(-1, 2)
        n = np.repeat(mesh.normals[els], len(t), axis=0)
        yield p, els, t, w, np.asarray(f(x, n), dtype=float).reshape(len(els), len(t))


def neumann_functional(space: ContinuousSpace, flux, extra: int = 6) -> np.ndarray:
    """F_j = int_Gamma flux U_j ds for the basis U_j of V_hp (the load of a Neumann
    problem; flux(x, n))."""
    mesh = space.mesh
    F = np.zeros(space.ndof)
    for p, els, t, w, fv in _degree_groups(mesh, flux, extra):
        loc = (fv * w) @ space._values(p, t) * (mesh.lengths[els, None] / 2.0)  # (ne, p+1)
        d = space.elem_dofs[els, :p + 1]
        np.add.at(F, d[d >= 0], loc[d >= 0])
    return F


def _richer(op, extra: int):
    from ..bem.laplace import LaplaceBEM

    return LaplaceBEM(op.mesh.with_degrees(op.mesh.degrees + extra), scale=op.scale)


def _project_W(space: DiscontinuousSpace, f, extra: int = 6) -> np.ndarray:
    """L2 projection of f(x, n) onto W_hp, element by element."""
    c = np.zeros(space.ndof)
    for p, els, t, w, fv in _degree_groups(space.mesh, f, extra):
        k = np.arange(p)
        c[space.elem_dofs[els, :p]] = (fv * w) @ legendre_values(p, t) * ((2 * k + 1) / 2.0)
    return c


def energy_error_neumann(op, psi_h, flux, extra: int = 4) -> float:
    """||flux - psi_h||_V for psi_h in op.W_space (Legendre coefficients are nested:
    the first p_I coefficients of each element carry over to the richer space)."""
    hi = _richer(op, extra)
    e = _project_W(hi.W_space, flux)
    lo_d, hi_d = op.W_space.elem_dofs, hi.W_space.elem_dofs
    mask = lo_d >= 0
    e[hi_d[:, :lo_d.shape[1]][mask]] -= np.asarray(psi_h)[lo_d[mask]]
    return energy_norm(hi.V, e)


def interpolation_difference(lo_space, hi_space, u_h, u) -> np.ndarray:
    """Coefficients in ``hi_space`` (V_hp of higher degrees on the same mesh) of
    I_hi u - u_h: u(x, n) is interpolated at the richer Gauss-Lobatto points and u_h
    (coefficients in ``lo_space``, shape (ndof,) or (ndof, d)) is embedded by evaluation
    there, which is exact since the spaces are nested."""
    from ..quadrature import gauss_lobatto

    u_h = np.asarray(u_h, dtype=float)
    e = np.zeros((hi_space.ndof,) + u_h.shape[1:])
    mesh = hi_space.mesh
    for p in np.unique(mesh.degrees):
        p = int(p)
        els = np.flatnonzero(mesh.degrees == p)
        xl, _ = gauss_lobatto(p + 1)
        elem = np.repeat(els, p + 1)
        t = np.tile(xl, len(els))
        vals = (np.asarray(u(mesh.points(elem, t), mesh.normals[elem]), dtype=float)
                - lo_space.evaluate(u_h, elem, t))
        e[hi_space.elem_dofs[els, :p + 1].ravel()] = vals
    return e


def energy_error_dirichlet(op, u_h, u, extra: int = 4) -> float:
    """|u - u_h|_W: u interpolated at degree p_I + extra, u_h embedded exactly."""
    hi = _richer(op, extra)
    e = interpolation_difference(op.V_space, hi.V_space, u_h, u)
    return energy_norm(hi.W, e)


def dual_energy_norm(op, residual) -> float:
    """||r||_* = sup_v r.v / ||v||, ||v||^2 = <W v, v> + (int v)^2 (an H^1/2(Gamma)
    norm on closed curves): the norm in which S_hat U - <flux, .> is measured."""
    mV = np.asarray(op.M.sum(axis=0)).ravel()  # int U_j ds
    A = op.W + np.outer(mV, mV)
    r = np.asarray(residual, dtype=float)
    return float(np.sqrt(max(r @ sla.solve(A, r, assume_a="pos"), 0.0)))
