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
