"""Closed-form lowest-order Laplace V and K (hpfebe.bem.lowest_order, issue 14).

Reference: the general quadrature path (``LaplaceBEM(..., closed_form=False)``), closed
forms of simple configurations, and the Gauss identity of the double layer."""

import math

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LaplaceBEM
from hpfebe.bem.lowest_order import applies, laplace_p1_vk
from hpfebe.bem.lowest_order_pairs import N_SERIES, Q_NEAR, _pair_far, _pair_near

from p1_meshes import MESHES as ALL_MESHES
from p1_meshes import SQUARE, graded, rel

MESHES = {k: ALL_MESHES[k] for k in ("square16", "square64", "square256", "L-shape",
                                     "slit-1e-2", "slit-1e-8", "wedge-3deg", "graded-12",
                                     "annulus")}


@pytest.mark.parametrize("scale", [None, 1.0])
@pytest.mark.parametrize("name", list(MESHES))
def test_matches_general_path(name, scale):
    """max |A - A_ref| / max |A_ref| <= 1e-13 for V, K and W = T^T V T."""
    mesh = MESHES[name]()
    fast = LaplaceBEM(mesh, scale=scale)
    ref = LaplaceBEM(mesh, scale=scale, closed_form=False)
    assert fast.closed_form and not ref.closed_form
    for k in "VKW":
        assert rel(getattr(fast, k), getattr(ref, k)) <= 1e-13, k


def test_collinear_adjacent_closed_form():
    """E_i = [0, 1], E_j = [1, 2] on a line: int int log|x - y| = 2 log 2 - 3/2; K = 0."""
    mesh = BoundaryMesh.from_segments([(0, 0), (1, 0), (2, 0), (1, -1)],
                                      [(0, 1), (1, 2), (2, 3), (3, 0)])
    op = LaplaceBEM(mesh, scale=1.0)
    ends = [{tuple(mesh.nodes[k]) for k in mesh.elements[e]} for e in range(4)]
    i = ends.index({(0.0, 0.0), (1.0, 0.0)})
    j = ends.index({(1.0, 0.0), (2.0, 0.0)})
    assert op.V[i, j] == pytest.approx(-(2 * math.log(2) - 1.5) / (2 * math.pi),
                                       rel=1e-15, abs=0)
    assert op.V[i, i] == pytest.approx(1.5 / (2 * math.pi), rel=1e-15, abs=0)
    # collinear pairs: the double layer kernel vanishes identically, so the hat of the
    # node (1, 0) (on E_i and E_j only) has K entries exactly 0 in both rows
    r = next(r for r in range(2) if tuple(mesh.nodes[mesh.elements[j, r]]) == (1.0, 0.0))
    dof = op.V_space.elem_dofs[j, r]
    assert op.K[i, dof] == 0.0 and op.K[j, dof] == 0.0
    assert op.K[i].any() and op.K[j].any()


@pytest.mark.parametrize("name", ["square64", "wedge-3deg", "slit-1e-8", "graded-12"])
def test_gauss_identity_and_symmetry(name):
    """(K + 1/2) 1 = 0 on a closed curve: the row sums of K are -|E_i| / 2; V symmetric."""
    mesh = MESHES[name]()
    op = LaplaceBEM(mesh)
    assert np.abs(op.K.sum(axis=1) + 0.5 * mesh.lengths).max() <= 1e-14 * mesh.lengths.max()
    assert np.array_equal(op.V, op.V.T)


@pytest.mark.parametrize("q", [0.9 * Q_NEAR, 0.5 * Q_NEAR, 0.2 * Q_NEAR])
def test_series_matches_closed_form(q):
    """Far-pair series and the closed form agree (independent formulas: (V1), (K1), (Q1)
    against their series, module doc) on random pairs
    at (L_i + L_j) / (2 |w_m|) = q, to the closed form's cancellation error ~ eps / q^3
    (of J1; measured 2.5e-13 relative to L_i L_j / |w_m| at q = 0.11, 1.2e-12 at q =
    0.05: why the closed form is used only for q >= Q_NEAR)."""
    rng = np.random.default_rng(7)
    ap = np.empty(N_SERIES + 1, np.complex128)
    bp = np.empty(N_SERIES + 1, np.complex128)
    for _ in range(50):
        Li, Lj = rng.uniform(0.2, 1.0, 2)
        u, v = np.exp(2j * np.pi * rng.random(2))
        wm = 0.5 * (Li + Lj) / q * np.exp(2j * np.pi * rng.random())
        ai = wm - 0.5 * Li * u            # m_j = 0, m_i = w_m
        bi = wm + 0.5 * Li * u
        aj, bj = -0.5 * Lj * v, 0.5 * Lj * v
        near = _pair_near(ai, bi, aj, bj, Li, Lj, u, v, wm, 0.3)
        far = _pair_far(Li, Lj, u, v, wm, 0.3, ap, bp)
        # (I, J0, J1, J0', J1'; Q of the Lame operators: its corner sum (Q1) loses less,
        # measured 5.8e-15, 1.1e-14, 2.4e-14 of L_i L_j at q = 0.225, 0.125, 0.05)
        scale = (Li * Lj, Li * Lj / abs(wm), Li * Lj / abs(wm), Li * Lj / abs(wm),
                 Li * Lj / abs(wm), Li * Lj)
        tol = (1e-15 / q ** 3,) * 5 + (4e-15 / q,)
        assert len(near) == len(far) == len(scale)
        for n, f, s, t in zip(near, far, scale, tol):
            assert abs(n - f) <= t * s


def test_dispatch_and_input_checks():
    p1 = BoundaryMesh.polygon(SQUARE, n=2, p=1)
    mixed = BoundaryMesh.polygon(SQUARE, n=2, p=[1, 2, 1, 1])
    assert applies(p1) and not applies(mixed)
    assert not LaplaceBEM(mixed).closed_form
    assert not LaplaceBEM(p1, closed_form=False).closed_form
    with pytest.raises(ValueError, match="closed_form"):
        LaplaceBEM(p1, closed_form="yes")
    op = LaplaceBEM(mixed)
    with pytest.raises(ValueError, match="degrees"):
        laplace_p1_vk(op.W_space, op.V_space, 1.0)
    op = LaplaceBEM(p1)
    with pytest.raises(ValueError, match="scale"):
        laplace_p1_vk(op.W_space, op.V_space, -1.0)
    # V and K come from one pass and are cached together
    V = op.V
    assert "K" in op._cache and op.V is V


def test_threads_bitwise(monkeypatch):
    """The threaded pass (rows on 2 threads, K of the pairs (j, i) gathered afterwards)
    gives the bits of the single-thread pass."""
    import numba

    from hpfebe.bem import lowest_order

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    mesh = graded(6)
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = laplace_p1_vk(*_spaces(mesh), 1.7)
        numba.set_num_threads(2)
        monkeypatch.setattr(lowest_order, "MIN_PAIRS_PER_THREAD", 1)
        two = laplace_p1_vk(*_spaces(mesh), 1.7)
    finally:
        numba.set_num_threads(old)
    assert all(np.array_equal(a, b) for a, b in zip(one, two))


def _spaces(mesh):
    op = LaplaceBEM(mesh, closed_form=False)
    return op.W_space, op.V_space


def test_smooth_curve():
    """A 256-gon: K entries of neighbours are small by cancellation (module doc); closed
    form and general path agree to 5e-14 (V, K); W to 1.1e-13, the general path's error on
    adjacent nearly collinear pairs (mpmath: the closed form is exact there)."""
    th = np.linspace(0, 2 * np.pi, 256, endpoint=False)
    mesh = BoundaryMesh.from_segments(np.column_stack([np.cos(th), np.sin(th)]),
                                      np.column_stack([np.arange(256),
                                                       (np.arange(256) + 1) % 256]))
    fast = LaplaceBEM(mesh)
    ref = LaplaceBEM(mesh, closed_form=False)
    assert rel(fast.V, ref.V) <= 1e-13
    assert rel(fast.K, ref.K) <= 1e-13
    assert rel(fast.W, ref.W) <= 3e-13


@pytest.mark.parametrize("short", [1e-6, 1e-9, 1e-12])
def test_tiny_element_beside_long_collinear_ones(short):
    """A side split into one element of length ``short`` and three of length 1/3: the V
    entries of the short element against its collinear neighbours to 1e-14 of each entry
    (reference: the one-dimensional closed form in mpmath, on the mesh's own floating
    point nodes), and W = T^T V T (which scales these rows by 1/short^2) to 1e-13 of its
    largest entry against the quadrature path.  Forming log(w+/w-) from the rounded
    corner differences lost 4e-8 of these entries at short = 1e-9."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 40
    m = BoundaryMesh.polygon([(0, 0), (1, 0), (1, short), (1, 1), (0, 1)],
                             n=[4, 1, 3, 4, 4], p=1)
    op, ref = LaplaceBEM(m), LaplaceBEM(m, closed_form=False)
    e = int(np.argmin(m.lengths))
    y = [tuple(mp.mpf(float(m.nodes[k, 1])) for k in m.elements[f]) for f in range(e, e + 4)]
    logR = mp.log(mp.mpf(op.scale))

    def phi(x):
        return mp.mpf(0) if x == 0 else x ** 2 / 2 * (mp.log(abs(x)) - mp.mpf(3) / 2)

    for k, (b0, b1) in enumerate(y):
        a0, a1 = y[0]
        integral = -(phi(a1 - b1) - phi(a1 - b0) - phi(a0 - b1) + phi(a0 - b0))
        exact = -(integral - (a1 - a0) * (b1 - b0) * logR) / (2 * mp.pi)
        assert abs(op.V[e, e + k] - exact) <= 1e-14 * abs(exact), (k, op.V[e, e + k], exact)
    assert np.abs(op.W - ref.W).max() <= 1e-13 * np.abs(ref.W).max()
