"""Structure of the Laplace Galerkin matrices (issue 2, test 2): V SPD, W SPSD with the
constants as kernel, (K + M/2) 1 = 0 for the interior problem, S_hat symmetric and
independent of the kernel's length scale."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LaplaceBEM

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
LSHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]


def ops():
    yield "square mixed p", LaplaceBEM(BoundaryMesh.polygon(SQUARE, n=[2, 3, 1, 4],
                                                            p=[1, 4, 8, 2]))
    yield "L-shape p=3", LaplaceBEM(BoundaryMesh.polygon(LSHAPE, n=2, p=3))
    outer = BoundaryMesh.polygon([(-2, -2), (2, -2), (2, 2), (-2, 2)], n=2, p=2)
    hole = BoundaryMesh.polygon(SQUARE, n=1, p=2)
    hole = BoundaryMesh.from_segments(hole.nodes, hole.elements[:, ::-1], p=2)
    yield "annulus", LaplaceBEM(BoundaryMesh.join(outer, hole))


OPS = dict(ops())


@pytest.fixture(params=list(OPS))
def op(request):
    return OPS[request.param]


def test_V_symmetric_positive_definite(op):
    V = op.V
    assert np.abs(V - V.T).max() <= 1e-14 * np.abs(V).max()
    assert np.linalg.eigvalsh(V).min() > 0


def test_W_symmetric_semidefinite_constants_in_kernel(op):
    W = op.W
    assert np.abs(W - W.T).max() <= 1e-14 * np.abs(W).max()
    lam = np.linalg.eigvalsh(W)
    assert lam.min() > -1e-12 * lam.max()
    # one constant per closed curve (the annulus has two)
    assert np.sum(lam < 1e-10 * lam.max()) == op.mesh.n_curves
    assert np.abs(W @ np.ones(W.shape[0])).max() < 1e-12 * np.abs(W).max()


def test_double_layer_of_constant(op):
    """Interior Calderon identity: (K + 1/2) 1 = 0, i.e. K 1 = -1/2 on Gamma."""
    B1 = op.B @ np.ones(op.V_space.ndof)
    assert np.abs(B1).max() < 1e-13


def test_S_hat_symmetric_kernel_constants(op):
    S = op.S_hat
    assert np.abs(S - S.T).max() == 0.0
    assert np.abs(S @ np.ones(S.shape[0])).max() < 1e-11 * np.abs(S).max()
    lam = np.linalg.eigvalsh(S)
    assert lam.min() > -1e-11 * lam.max()


@pytest.mark.parametrize("factor", [0.6, 3.0, 100.0])
def test_S_hat_independent_of_kernel_scale(op, factor):
    """S_hat (zero-flux form) does not change with the kernel's length scale R (any R
    above the log capacity of Gamma, which is at most diam/2)."""
    other = LaplaceBEM(op.mesh, scale=factor * op.mesh.diameter)
    S0, S1 = op.S_hat, other.S_hat
    assert np.abs(S1 - S0).max() <= 1e-10 * np.abs(S0).max()
    U = op.V_space.interpolate(lambda x: x[:, 0] ** 2 - x[:, 1] ** 2 + x[:, 0])
    assert np.allclose(op.Psi(U), other.Psi(U), atol=1e-10 * np.abs(op.Psi(U)).max())


def test_too_small_scale_is_reported():
    """Below the capacity (unit square: ~0.59) V is indefinite: a clear error, not a
    wrong S_hat."""
    op = LaplaceBEM(BoundaryMesh.polygon(SQUARE, n=4, p=2), scale=0.3)
    with pytest.raises(np.linalg.LinAlgError, match="scale"):
        op.S_hat
    with pytest.raises(ValueError, match="scale"):
        LaplaceBEM(op.mesh, scale=-1.0)


def test_thesis_S_hat_depends_on_scale_by_a_rank_one_term_that_vanishes_with_refinement():
    """The thesis's S_hat = W + B^T V^-1 B (zero_flux=False) changes with R by the
    rank-one term -c b b^T / (1 + c m^T V^-1 m), b = B^T V^-1 m, c = log(R_b/R_a)/(2 pi):
    a discretisation error that decreases under h- and p-refinement."""
    rel = {}
    for n, p in [(2, 1), (4, 1), (8, 1), (4, 2), (4, 4)]:
        mesh = BoundaryMesh.polygon(SQUARE, n=n, p=p)
        a = LaplaceBEM(mesh, scale=2.0, zero_flux=False)
        b = LaplaceBEM(mesh, scale=10.0, zero_flux=False)
        dS = b.S_hat - a.S_hat
        c = np.log(10.0 / 2.0) / (2 * np.pi)          # V_b = V_a + c m m^T
        w = np.linalg.solve(a.V, a.m)
        bb = a.B.T @ w
        predicted = -c * np.outer(bb, bb) / (1 + c * a.m @ w)
        assert np.abs(dS - predicted).max() <= 1e-10 * np.abs(a.S_hat).max()
        rel[n, p] = np.abs(dS).max() / np.abs(a.S_hat).max()
    assert rel[2, 1] > rel[4, 1] > rel[8, 1]
    assert rel[4, 1] > rel[4, 2] > rel[4, 4]
    assert rel[2, 1] > 1e-6   # not a rounding effect: the thesis's form really depends on R
