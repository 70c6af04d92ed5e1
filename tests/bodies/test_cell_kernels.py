"""The fused cell return map of the plastic BE body's inner Newton and the
mixed-precision dense solves of its cell-strain Jacobians (hpfebe.bodies.cell_kernels,
hpfebe.bodies.refined_lu)."""

import numpy as np
import pytest

from hpfebe.bodies.cell_kernels import _cell_return_kernel
from hpfebe.bodies.plastic_be import _tau_strain_blocks
from hpfebe.bodies.refined_lu import RefinedLU
from hpfebe.constitutive.j2 import J2Material, J2State, return_map
from hpfebe.fem.newton_potential import initial_stress


@pytest.mark.parametrize("theta", [1.0, 0.0, 0.4])
def test_cell_return_kernel_is_the_return_map(theta):
    """tau, D, the state and the plastic flags of the fused kernel equal return_map,
    initial_stress and the D blocks of C - C_alg (by the tensor selection) to
    round-off, on a committed plastic history with elastic and plastic cells."""
    mat = J2Material(266926.0, 0.29, 4.0, 450.0, theta)
    rng = np.random.default_rng(1)
    nc = 40
    st = J2State.zeros(nc)
    e0 = np.geomspace(2e-6, 1e-4, nc)[:, None] * rng.standard_normal((nc, 3))
    back = np.where(np.arange(nc)[:, None] % 2 == 0, 1.5, -0.3)      # reload / reverse
    for E3 in (e0, back * e0):
        eps = np.zeros((nc, 3, 3))
        eps[:, 0, 0], eps[:, 1, 1] = E3[:, 0], E3[:, 1]
        eps[:, 0, 1] = eps[:, 1, 0] = 0.5 * E3[:, 2]
        rm = return_map(mat, eps, st, "algorithmic")
        got = _cell_return_kernel(E3, st.eps_p, st.alpha, st.beta, mat.mu, mat.kappa,
                                  mat.lam, mat.H, mat.theta, mat.sigma_Y)
        tau, D, plastic, sigma, eps_p, alpha, beta = got[:7]
        assert 0 < plastic.sum() < nc and np.array_equal(plastic, rm.plastic)
        want_tau = initial_stress(rm.state.eps_p, mat.E, mat.nu)
        np.testing.assert_allclose(tau, want_tau, rtol=0, atol=1e-12 * np.abs(want_tau).max())
        want_D = np.zeros((nc, 3, 3))
        want_D[plastic] = _tau_strain_blocks(mat.elastic_tangent()[None]
                                             - rm.tangent[plastic])
        # the einsum form loses ~eps kappa to the cancellation of the kappa terms
        np.testing.assert_allclose(D, want_D, rtol=0, atol=1e-10 * mat.E)
        assert np.abs(D[~plastic]).max() == 0.0
        for a, b in ((sigma, rm.sigma), (eps_p, rm.state.eps_p), (alpha, rm.state.alpha),
                     (beta, rm.state.beta)):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * max(np.abs(b).max(), 1e-30))
        st = J2State(eps_p, alpha, beta)


def _matrix(n, rng, cond):
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return (Q1 * np.geomspace(1.0, 1.0 / cond, n)) @ Q2


def test_refined_lu_is_backward_stable_as_a_double_lu():
    """A single-precision LU refined in double solves J x = b (vector and matrix
    right-hand sides) to the backward error of a double LU, also at cond(J) = 1e5;
    its factors serve a nearby matrix J' (relative change 1e-4) and refuse a far one
    (None: the caller factorises anew)."""
    rng = np.random.default_rng(0)
    n = 120
    for cond in (1e2, 1e5):
        J = _matrix(n, rng, cond)
        b = rng.standard_normal((n, 3))
        f = RefinedLU(J)
        for rhs in (b[:, 0], b):
            x = f.solve(rhs)
            assert x is not None
            ref = np.linalg.solve(J, rhs)
            berr = np.abs(J @ x - rhs).max() / (np.linalg.norm(J, np.inf) * np.abs(x).max())
            assert berr < 5 * n * np.finfo(float).eps
            assert np.abs(x - ref).max() < 1e-15 * cond * np.abs(ref).max() * n
        x32 = f._solve32(b[:, 0])                        # unrefined: far less accurate
        assert np.abs(J @ x32 - b[:, 0]).max() > 1e3 * np.abs(J @ f.solve(b[:, 0]) - b[:, 0]).max()
    J = _matrix(n, rng, 1e2)
    f = RefinedLU(J)
    near = J * (1.0 + 1e-4 * rng.standard_normal(J.shape))
    x = f.solve(b[:, 0], near, max_refine=8, min_rate=0.25)
    assert x is not None and np.abs(near @ x - b[:, 0]).max() < 1e-12
    far = _matrix(n, rng, 1e2)
    assert f.solve(b[:, 0], far, max_refine=8, min_rate=0.25) is None
    assert RefinedLU(np.zeros((4, 4))).solve(np.ones(4)) is None      # zero pivot
    with pytest.raises(ValueError, match="square"):
        RefinedLU(np.ones((3, 4)))
