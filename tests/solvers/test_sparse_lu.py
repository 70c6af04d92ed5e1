"""The symmetric-mode sparse LU of hpfebe.solvers.sparse_lu: it solves SPD and indefinite
symmetric systems, falls back to partial pivoting on a vanishing diagonal pivot, and the
checked solve returns a solution with a small residual and names its LU."""

import numpy as np
import pytest
import scipy.sparse as sp

from hpfebe.solvers.sparse_lu import solve_checked, symmetric_lu


def spd(n=30, seed=1):
    A = sp.random(n, n, 0.2, random_state=seed)
    return (A @ A.T + sp.eye(n)).tocsc()


@pytest.mark.parametrize("thresh", [0.0, 0.1])
def test_symmetric_mode_solves_spd(thresh):
    A, b = spd(), np.arange(30.0)
    lu, kind = symmetric_lu(A, diag_pivot_thresh=thresh)
    assert kind == "symmetric"
    np.testing.assert_allclose(A @ lu.solve(b), b, atol=1e-12 * np.abs(b).max())


def test_zero_diagonal_pivot_falls_back():
    swap = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0]]))
    lu, kind = symmetric_lu(swap, diag_pivot_thresh=0.0)
    np.testing.assert_allclose(lu.solve(np.array([1.0, 2.0])), [2.0, 1.0])
    x, res, kind = solve_checked(swap, np.array([1.0, 2.0]))
    np.testing.assert_allclose(x, [2.0, 1.0])
    assert res < 1e-14


def test_checked_solve_of_an_indefinite_saddle_point_matrix():
    """[[A, B], [B^T, -eps I]]: symmetric, indefinite, with small diagonal entries in the
    second block; the returned solution's residual is below rtol whichever LU gave it."""
    A, B = spd(20), sp.random(20, 8, 0.3, random_state=3)
    M = sp.bmat([[A, B], [B.T, -1e-12 * sp.eye(8)]]).tocsc()
    b = np.random.default_rng(0).standard_normal(28)
    x, res, kind = solve_checked(M, b, rtol=1e-10)
    assert kind in ("symmetric", "partial pivoting")
    assert res == pytest.approx(np.linalg.norm(M @ x - b) / np.linalg.norm(b))
    assert res < 1e-10


def test_singular_matrix_raises():
    with pytest.raises(RuntimeError):
        solve_checked(sp.csc_matrix((3, 3)), np.ones(3))
