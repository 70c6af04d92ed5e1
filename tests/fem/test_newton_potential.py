"""Newton potential of an initial strain on cells (hpfebe.fem.newton_potential): the
closed-form edge integrals against scipy quadrature, the cell integrals against an
independent Duffy (polar) cell quadrature, the strongly singular gradient against finite
differences of that quadrature."""

import numpy as np
import pytest
from scipy import integrate

from hpfebe.fem.newton_potential import (CellComplex, edge_integrals, initial_stress,
                                         kelvin_constants, newton_operators)

E, NU = 1000.0, 0.3
C1, C2 = kelvin_constants(E, NU)


def dG_dr(r):
    """d G_ia / d r_b, r = x - y, shape (2, 2, 2)."""
    r2 = r @ r
    eye = np.eye(2)
    return C1 * (-np.einsum("ia,b->iab", eye, r) / r2
                 + C2 * (np.einsum("ib,a->iab", eye, r) + np.einsum("ab,i->iab", eye, r)) / r2
                 - 2 * C2 * np.einsum("i,a,b->iab", r, r, r) / r2 ** 2)


def duffy_cell(x, poly, tau):
    """int_cell eps_y(G(x, y)) : tau dy by splitting the cell into triangles (x, A, B) and
    the Duffy map y = x + s (A + t (B - A) - x) (Jacobian s |(A - x) x (B - A)|, which
    cancels the 1/r singularity), adaptive scipy dblquad - independent of the edge
    formulas."""
    T = np.array([[tau[0], tau[2]], [tau[2], tau[1]]])
    out = np.zeros(2)
    for k in range(len(poly)):
        A, B = poly[k], poly[(k + 1) % len(poly)]
        jac = (A - x)[0] * (B - A)[1] - (A - x)[1] * (B - A)[0]
        if abs(jac) < 1e-14:
            continue
        for i in range(2):
            def f(s, t, i=i):
                y = x + s * (A + t * (B - A) - x)
                # eps_y(G e_i) : tau = d_{y_b} G_ia tau_ab = -dG/dr_b
                return -np.einsum("ab,ab->", dG_dr(x - y)[i], T) * s * jac
            out[i] += integrate.dblquad(f, 0, 1, 0, 1, epsabs=1e-11, epsrel=1e-10)[0]
    return out


def test_edge_integrals_match_scipy_quad():
    a, b = np.array([[0.1, 0.2]]), np.array([[0.7, 0.5]])
    x = np.array([[0.3, 0.45], [0.41, 0.351], [1.0, -0.2], [0.7, 0.5001]])
    IG, _ = edge_integrals(x, a, b, C1, C2)
    L = np.hypot(*(b - a)[0])
    for p in range(len(x)):
        def G(s, i, k):
            r = x[p] - (a[0] + s * (b - a)[0])
            rr = np.hypot(*r)
            return C1 * (-np.log(rr) * (i == k) + C2 * r[i] * r[k] / rr ** 2) * L
        sp = np.clip((x[p] - a[0]) @ (b - a)[0] / L ** 2, 0.0, 1.0)   # nearest point
        ref = [[integrate.quad(G, 0, 1, args=(i, k), limit=400, points=[sp] if 0 < sp < 1 else None, epsabs=1e-14,
                               epsrel=1e-12)[0] for k in range(2)] for i in range(2)]
        assert np.allclose(IG[p, 0], ref, atol=1e-12, rtol=1e-9)


def test_edge_gradient_matches_finite_differences():
    a, b = np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([[1.0, 0.0], [1.0, 1.0]])
    x = np.array([[0.3, 0.05], [0.95, 0.7], [0.5, -0.4]])
    _, IdG = edge_integrals(x, a, b, C1, C2)
    h = 1e-6
    for m in range(2):
        e = np.zeros(2)
        e[m] = h
        fd = (edge_integrals(x + e, a, b, C1, C2, False)
              - edge_integrals(x - e, a, b, C1, C2, False)) / (2 * h)
        assert np.allclose(IdG[..., m], fd, atol=1e-7)


QUAD = np.array([[0.0, 0.0], [1.0, 0.1], [1.2, 0.9], [0.1, 1.0]])
TRI = np.array([[0.0, 0.0], [1.0, 0.0], [0.3, 0.8]])


@pytest.mark.parametrize("poly", [QUAD, TRI], ids=["quad", "tri"])
@pytest.mark.parametrize("x", [(0.5, 0.5), (0.02, 0.01), (0.5, 0.0005), (1.6, 0.4), (0.5, 0.0)],
                         ids=["inside", "near-vertex", "near-edge", "outside", "on-edge"])
def test_cell_potential_matches_duffy_quadrature(poly, x):
    x = np.array(x, dtype=float)
    cx = CellComplex(poly, np.arange(len(poly))[None])
    tau = np.array([3.0, -1.0, 2.0])
    Nw, _ = newton_operators(cx, x[None], E, NU, gradient=False)
    ref = duffy_cell(x, cx.nodes[cx.cells[0]], tau)
    assert np.allclose(Nw @ tau, ref, atol=1e-9 * np.abs(ref).max(), rtol=1e-8)


@pytest.mark.parametrize("x", [(0.5, 0.5), (0.05, 0.04), (1.05, 0.5)], ids=["centre", "near-vertex",
                                                                           "near-edge"])
def test_strongly_singular_gradient_against_fd_of_independent_quadrature(x):
    """eps(w) inside a cell (the CPV cell integral with its free term in Telles-Brebbia's
    form) against central differences of the Duffy quadrature of w."""
    x = np.array(x, dtype=float)
    cx = CellComplex(QUAD, np.arange(4)[None])
    tau = np.array([1.0, 2.0, -0.5])
    _, Ng = newton_operators(cx, x[None], E, NU)
    g = (Ng @ tau).reshape(2, 2)
    h = 1e-4
    fd = np.zeros((2, 2))
    for m in range(2):
        e = np.zeros(2)
        e[m] = h
        fd[:, m] = (duffy_cell(x + e, QUAD, tau) - duffy_cell(x - e, QUAD, tau)) / (2 * h)
    assert np.allclose(g, fd, atol=1e-6 * np.abs(g).max())


def test_uniform_initial_strain_gives_eshelby_interior_field():
    """Uniform eps_p on a union of cells: eps(w) is the same as for one big cell (interior
    edges cancel), and on a disc (polygon with many sides) the interior field is the
    Eshelby one, uniform: eps(w) = S : eps_p with the plane-strain circular-inclusion
    tensor - checked here through the uniformity of eps(w) on the cells' interior."""
    th = np.linspace(0, 2 * np.pi, 129)[:-1]
    poly = np.c_[np.cos(th), np.sin(th)]
    nodes = np.vstack([poly, [[0.0, 0.0]]])
    cells = np.c_[np.arange(128), (np.arange(128) + 1) % 128, np.full(128, 128)]
    cx = CellComplex(nodes, cells)
    tau = np.tile([1.0, 0.0, 0.0], 128)
    pts = np.array([[0.1, 0.05], [-0.3, 0.2], [0.2, -0.4]])
    _, Ng = newton_operators(cx, pts, E, NU)
    g = (Ng @ tau).reshape(3, 2, 2)
    assert np.allclose(g, g[0], atol=2e-3 * np.abs(g[0]).max())
    # Eshelby (plane strain, circle): eps(w) = S eps*, with tau = C eps* and eps* = diag(e, 0):
    # eps_11 = (5 - 4 nu) / (8 (1 - nu)) e*... checked via tau = lam tr e + 2 mu e.
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    M = np.array([[lam + 2 * mu, lam], [lam, lam + 2 * mu]])
    e11, e22 = np.linalg.solve(M, [1.0, 0.0])       # eps* with C eps* = tau (in-plane)
    S1111 = (5 - 4 * NU) / (8 * (1 - NU))
    S1122 = (4 * NU - 1) / (8 * (1 - NU))
    assert np.allclose([g[0, 0, 0], g[0, 1, 1]],
                       [S1111 * e11 + S1122 * e22, S1122 * e11 + S1111 * e22], rtol=2e-3)


def test_initial_stress_and_bad_input():
    ep = np.zeros((1, 3, 3))
    ep[0, 0, 0], ep[0, 2, 2], ep[0, 0, 1] = 1.0, -1.0, 0.5
    ep[0, 1, 0] = 0.5
    tau = initial_stress(ep, E, NU)
    mu = E / (2 * (1 + NU))
    assert np.allclose(tau, [[2 * mu, 0.0, mu]])
    with pytest.raises(ValueError, match="eps_p"):
        initial_stress(np.zeros((2, 2)), E, NU)
    with pytest.raises(ValueError, match="cells"):
        CellComplex(QUAD, np.array([[0, 1]]))
    with pytest.raises(ValueError, match="points"):
        newton_operators(CellComplex(QUAD, np.arange(4)[None]), [[np.nan, 0.0]], E, NU)
