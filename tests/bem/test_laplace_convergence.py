"""Exact harmonic solutions with observed convergence rates (issue 2, test 3).

u = log|x - x0| (x0 outside, smooth on Gamma) and u = Re z^3 (polynomial), on the unit
square and on an L-shape, three problems:

(a) Dirichlet: V psi = (K + M/2) g (g the interpolant of u) gives the Neumann data;
(b) S_hat applied to the interpolant gives the Neumann data, as a functional on V_hp;
(c) mixed: Dirichlet data on half of the sides, Neumann data on the rest, solved with
    S_hat, gives the Dirichlet data.

Rates are computed from the runs (n = 8, 16, 32 elements per side, the last pair) and
compared with the theory for smooth data:

    (a) ||psi - psi_h||_V ~ h^(p+1/2),  ||psi - psi_h||_L2 ~ h^p,
    (b) ||S_hat g_h - <psi, .>||_*  <~ h^(p+1/2)   (an upper bound: for p = 1 the discrete
        dual norm superconverges, ~h^2 observed; asserted one-sided),
    (c) |u - u_h|_W ~ h^(p+1/2),  ||u - u_h||_L2 ~ h^(p+1).
"""

from functools import lru_cache

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.analysis import (boundary_l2_error, dual_energy_norm, energy_error_dirichlet,
                             energy_error_neumann, neumann_functional, observed_rates)
from hpfebe.bem import LaplaceBEM

DOMAINS = {
    "square": ([(0, 0), (1, 0), (1, 1), (0, 1)], (2.0, 1.7)),
    "L-shape": ([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], (2.5, 2.2)),
}
TOL = 0.15


def log_solution(x0):
    x0 = np.asarray(x0, dtype=float)

    def u(x, n=None):
        d = x - x0
        return 0.5 * np.log(np.sum(d * d, axis=1))

    def flux(x, n):
        d = x - x0
        return np.sum(d * n, axis=1) / np.sum(d * d, axis=1)
    return u, flux


def solve_all(verts, p, n, u, flux):
    """Errors of (a), (b), (c) on the mesh with n elements per side and degree p."""
    mesh = BoundaryMesh.polygon(verts, n=n, p=p)
    op = LaplaceBEM(mesh)
    g = op.V_space.interpolate(lambda x: u(x))
    psi = op.Psi(g)                                                       # (a)
    F = neumann_functional(op.V_space, flux)
    res_b = op.S_hat @ g - F                                              # (b)
    half = len(verts) // 2
    labels = ["D"] * half + ["N"] * (len(verts) - half)
    opm = LaplaceBEM(BoundaryMesh.polygon(verts, n=n, p=p, labels=labels))
    D = opm.V_space.dofs_on("D")
    free = np.setdiff1d(np.arange(opm.V_space.ndof), D)
    U = opm.V_space.interpolate(lambda x: u(x))                           # (c)
    Fm = neumann_functional(opm.V_space, flux)
    S = opm.S_hat
    U[free] = np.linalg.solve(S[np.ix_(free, free)], Fm[free] - S[np.ix_(free, D)] @ U[D])
    return {
        "a_energy": energy_error_neumann(op, psi, flux),
        "a_l2": boundary_l2_error(op.W_space, psi, flux),
        "b_dual": dual_energy_norm(op, res_b),
        "c_energy": energy_error_dirichlet(opm, U, u),
        "c_l2": boundary_l2_error(opm.V_space, U, u),
    }


@lru_cache(maxsize=None)
def h_sweep(domain, p):
    verts, x0 = DOMAINS[domain]
    u, flux = log_solution(x0)
    ns = (8, 16, 32)
    runs = [solve_all(verts, p, n, u, flux) for n in ns]
    h = 1.0 / np.array(ns)
    return {k: observed_rates(h, [r[k] for r in runs])[-1] for k in runs[0]}


@pytest.mark.parametrize("domain", list(DOMAINS))
@pytest.mark.parametrize("p", [1, 2, 3])
def test_h_version_rates(domain, p):
    rates = h_sweep(domain, p)
    expected = {"a_energy": p + 0.5, "a_l2": p, "c_energy": p + 0.5, "c_l2": p + 1}
    for key, theory in expected.items():
        assert abs(rates[key] - theory) <= TOL, (key, rates[key], theory)
    # (b): the theory is an upper bound of the error, i.e. a lower bound of the rate
    assert rates["b_dual"] >= p + 0.5 - TOL, rates["b_dual"]
    if p > 1:
        assert abs(rates["b_dual"] - (p + 0.5)) <= TOL, rates["b_dual"]


def test_p_version_exponential():
    """Fixed mesh (2 elements per side), p = 1..12: the energy error of the Neumann data
    decreases geometrically and falls below 1e-10."""
    verts, x0 = DOMAINS["square"]
    u, flux = log_solution(x0)
    errs = []
    for p in range(1, 13):
        op = LaplaceBEM(BoundaryMesh.polygon(verts, n=2, p=p))
        psi = op.Psi(op.V_space.interpolate(lambda x: u(x)))
        errs.append(energy_error_neumann(op, psi, flux, extra=6))
    errs = np.array(errs)
    ratios = errs[1:] / errs[:-1]
    assert errs[-1] < 1e-10, errs
    # geometric: on average at least a factor 3 per degree, never an increase
    assert np.all(ratios < 1.0), ratios
    assert np.exp(np.mean(np.log(ratios))) < 1 / 3, ratios


@pytest.mark.parametrize("domain", list(DOMAINS))
def test_polynomial_solution_reproduced_exactly(domain):
    """u = Re z^3 = x^3 - 3 x y^2: cubic on every side, so for p >= 3 the interpolant is
    exact, psi_h = psi (degree 2 per side) and S_hat g = <psi, .> up to rounding."""
    verts, _ = DOMAINS[domain]

    def u(x, n=None):
        return x[:, 0] ** 3 - 3 * x[:, 0] * x[:, 1] ** 2

    def flux(x, n):
        gx = 3 * x[:, 0] ** 2 - 3 * x[:, 1] ** 2
        gy = -6 * x[:, 0] * x[:, 1]
        return gx * n[:, 0] + gy * n[:, 1]

    op = LaplaceBEM(BoundaryMesh.polygon(verts, n=2, p=3))
    g = op.V_space.interpolate(lambda x: u(x))
    psi = op.Psi(g)
    assert boundary_l2_error(op.W_space, psi, flux) < 1e-10
    F = neumann_functional(op.V_space, flux)
    assert np.abs(op.S_hat @ g - F).max() < 1e-10 * np.abs(F).max()


def test_representation_formula_interior_points():
    """(1.2) with the computed Neumann data reproduces u inside, also close to Gamma
    (elements near a point are subdivided); the error follows the boundary error."""
    verts, x0 = DOMAINS["L-shape"]
    u, flux = log_solution(x0)
    op = LaplaceBEM(BoundaryMesh.polygon(verts, n=8, p=6))
    g = op.V_space.interpolate(lambda x: u(x))
    psi = op.Psi(g)
    pts = np.array([[0.5, 0.5], [1.5, 0.5], [0.5, 1.5], [0.9, 0.9], [1.0, 0.5],
                    [0.5, 1e-3], [1e-3, 1.0], [1.999, 0.5]])
    err = np.abs(op.representation(pts, g, psi) - u(pts))
    assert err.max() < 1e-8, err
    with pytest.raises(ValueError, match="points"):
        op.representation(np.zeros((3, 3)), g, psi)
