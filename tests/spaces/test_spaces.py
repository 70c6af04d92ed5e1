"""hp spaces V_hp (continuous, GLL Lagrange) and W_hp (Legendre): dof maps,
interpolation, evaluation, derivative and mass matrices, mixed degrees up to 12."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh, ContinuousSpace, DiscontinuousSpace

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def mixed_mesh():
    return BoundaryMesh.polygon(SQUARE, n=[2, 1, 3, 2], labels=["D", "N", "N", "I"],
                                p=[1, 12, 5, 3])


def test_dof_counts():
    m = mixed_mesh()
    V, W = ContinuousSpace(m), DiscontinuousSpace(m)
    assert W.ndof == m.degrees.sum()
    assert V.ndof == m.n_elements + (m.degrees - 1).sum()   # one closed curve
    Vd = ContinuousSpace(m, zero_on=("D",))
    # the 2 D elements carry 3 vertices (closure) and no interior dofs (p=1)
    assert Vd.ndof == V.ndof - 3
    assert len(V.dofs_on("D")) == 3


@pytest.mark.parametrize("p", [1, 2, 7, 12])
def test_interpolation_exact_for_polynomials_and_continuity(p):
    m = BoundaryMesh.polygon(SQUARE, n=2, p=p)
    V = ContinuousSpace(m)
    f = lambda x: (x[:, 0] - 0.3) ** p + 2 * x[:, 1] ** p  # noqa: E731
    c = V.interpolate(f)
    t = np.linspace(-1, 1, 7)
    for e in range(m.n_elements):
        x = m.points(np.full(7, e), t)
        assert np.allclose(V.evaluate(c, np.full(7, e), t), f(x), atol=1e-11)
    # continuity: the end of element e equals the start of e+1
    ends = V.evaluate(c, np.arange(m.n_elements), np.ones(m.n_elements))
    starts = V.evaluate(c, (np.arange(m.n_elements) + 1) % m.n_elements, -np.ones(m.n_elements))
    assert np.allclose(ends, starts, atol=1e-12)


def test_derivative_matrix_is_exact_arc_length_derivative():
    m = mixed_mesh()
    V, W = ContinuousSpace(m), DiscontinuousSpace(m)
    c = V.interpolate(lambda x: np.sin(3 * x[:, 0]) + x[:, 1] ** 2)
    T = V.derivative_matrix(W)
    dc = T @ c
    elem = np.repeat(np.arange(m.n_elements), 5)
    t = np.tile(np.linspace(-0.9, 0.9, 5), m.n_elements)
    assert np.allclose(W.evaluate(dc, elem, t), V.evaluate(c, elem, t, derivative=True),
                       atol=1e-10)
    # constants are in the kernel of d/ds
    assert np.abs(T @ np.ones(V.ndof)).max() < 1e-11


def test_mass_matrix_integrates_products():
    m = mixed_mesh()
    V, W = ContinuousSpace(m), DiscontinuousSpace(m)
    M = V.mass_matrix(W)
    one_W = W.project(lambda x: np.ones(len(x)))
    one_V = V.interpolate(lambda x: np.ones(len(x)))
    assert np.isclose(one_W @ M @ one_V, 4.0)   # perimeter
    fx = V.interpolate(lambda x: x[:, 0])
    # int_Gamma x ds over the unit square = 0.5 + 1 + 0.5 + 0 = 2
    assert np.isclose(one_W @ M @ fx, 2.0)


def test_evaluate_bad_coeffs():
    m = mixed_mesh()
    V = ContinuousSpace(m)
    with pytest.raises(ValueError, match="coeffs"):
        V.evaluate(np.zeros(3), [0], [0.0])


@pytest.mark.parametrize("Space", [ContinuousSpace, DiscontinuousSpace])
def test_trace_matrix_equals_evaluate(Space):
    m = mixed_mesh()
    S = Space(m)
    rng = np.random.default_rng(0)
    c = rng.standard_normal((S.ndof, 2))
    elem = rng.integers(0, m.n_elements, 40)
    t = rng.uniform(-1, 1, 40)
    t[:3] = [-1.0, 1.0, 0.0]
    A = S.trace_matrix(elem, t)
    assert A.shape == (40, S.ndof)
    assert np.allclose(A @ c[:, 0], S.evaluate(c[:, 0], elem, t), atol=1e-12)
    A2 = S.trace_matrix(elem, t, components=2)
    assert A2.shape == (80, 2 * S.ndof)
    assert np.allclose((A2 @ c.ravel()).reshape(-1, 2), S.evaluate(c, elem, t), atol=1e-12)
    D = S.trace_matrix(elem, 0.9 * t, derivative=True)
    assert np.allclose(D @ c[:, 1], S.evaluate(c[:, 1], elem, 0.9 * t, derivative=True),
                       atol=1e-9)


def test_trace_matrix_drops_removed_dofs_and_checks_input():
    m = mixed_mesh()
    Vd = ContinuousSpace(m, zero_on=("D",))
    on_d = np.flatnonzero(m.where("D"))
    A = Vd.trace_matrix(on_d, np.zeros(len(on_d)))
    assert A.nnz == 0                   # p = 1 on Gamma_D: every function there removed
    with pytest.raises(ValueError, match="components"):
        Vd.trace_matrix([0], [0.0], components=3)
    with pytest.raises(ValueError, match="elem"):
        Vd.trace_matrix([m.n_elements], [0.0])
    with pytest.raises(ValueError, match="t must"):
        Vd.trace_matrix([0], [1.5])


def test_free_dofs():
    m = mixed_mesh()
    V = ContinuousSpace(m)
    free = V.free_dofs()
    assert np.array_equal(free, np.setdiff1d(np.arange(V.ndof), V.dofs_on("D")))
    assert len(free) == ContinuousSpace(m, zero_on=("D",)).ndof
    f2 = V.free_dofs(components=2)
    assert np.array_equal(f2[0::2], 2 * free) and np.array_equal(f2[1::2], 2 * free + 1)
    assert np.array_equal(V.free_dofs("D", "I"), np.setdiff1d(free, V.dofs_on("I")))
