"""Mortar projection (4.87) and Polyak's projected CG (Section 4.3.3)."""

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import lsq_linear

from hpfebe.solvers import projected_cg
from hpfebe.coupling.mortar import MortarProjection
from hpfebe.geometry import BoundaryMesh
from hpfebe.scenes import model_meshes
from hpfebe.spaces import ContinuousSpace


def _meshes(n1, n2, p1, p2):
    """The arc body and the box of the model problem of Section 4.3.4 (Gamma^1_C the
    arc's polygon, n1 elements of degree p1; Gamma^2_C straight, n2 of degree p2)."""
    return model_meshes(n1, n2, p1, p2)[:2]


def _shifted_box(n, p, x0, x1):
    return BoundaryMesh.polygon([(x0, -2), (x1, -2), (x1, 0), (x0, 0)], n=[3, 3, n, 3],
                                labels=["D", "D", "C", "D"], p=p)


@pytest.mark.parametrize("p1,p2,n1,n2", [(1, 1, 7, 5), (2, 1, 16, 12), (2, 2, 16, 12),
                                         (3, 2, 5, 9), (4, 3, 6, 4)])
def test_reproduces_polynomials(p1, p2, n1, n2):
    """Polynomials in x of degree <= min(p1, p2) are reproduced on non-matching meshes
    (arc polygon vs straight line, paired by the x-coordinate)."""
    m = MortarProjection(*_meshes(n1, n2, p1, p2))
    s1, s2 = m.space1, m.space2
    for deg in range(min(p1, p2) + 1):
        coef = np.arange(1, deg + 2) * (-0.7) ** np.arange(deg + 1)
        f = lambda x: np.polyval(coef, x[:, 0])  # noqa: E731
        phi2 = s2.interpolate(f)[m.dofs2]
        phi1 = s1.interpolate(f)[m.dofs1]
        assert np.max(np.abs(m.project(phi2) - phi1)) < 1e-12 * max(1, np.abs(phi1).max())
    # vector (interleaved) version: component by component
    v2 = np.column_stack([np.ones(m.dofs2.size), 2 * np.ones(m.dofs2.size)]).ravel()
    assert np.allclose(m.project(v2).reshape(-1, 2), [1.0, 2.0], atol=1e-13)


def test_defining_identity_and_adjoint():
    m = MortarProjection(*_meshes(9, 7, 2, 3))
    rng = np.random.default_rng(0)
    phi2 = rng.standard_normal(m.dofs2.size)
    psi1 = rng.standard_normal(m.dofs1.size)
    # (4.87): int pi(Phi2) Psi1 = int Phi2 Psi1 for all Psi1 in M^1
    assert abs(psi1 @ (m.D @ m.project(phi2)) - psi1 @ (m.B @ phi2)) < 1e-12 * np.abs(
        m.B).sum()
    # adjoint identity <pi Phi2, R1> = <Phi2, pi* R1> (coefficients x functional values)
    r1 = rng.standard_normal(m.dofs1.size)
    lhs, rhs = m.project(phi2) @ r1, phi2 @ m.adjoint(r1)
    assert abs(lhs - rhs) <= 1e-12 * max(1.0, abs(lhs))
    v2, w1 = rng.standard_normal(2 * m.dofs2.size), rng.standard_normal(2 * m.dofs1.size)
    assert abs(m.project(v2) @ w1 - v2 @ m.adjoint(w1)) <= 1e-12 * max(1, abs(v2 @ m.adjoint(w1)))
    # D is the mass matrix of the arc polygon: total length
    one = np.ones(m.dofs1.size)
    assert one @ (m.D @ one) == pytest.approx(np.sum(m.mesh1.lengths[m.mesh1.labels == "C"]),
                                              rel=1e-13)


def test_bad_input():
    a, b = _meshes(4, 3, 1, 1)
    with pytest.raises(ValueError, match="overlap"):
        MortarProjection(a, _shifted_box(3, 1, 3.0, 5.0))
    with pytest.raises(ValueError, match="label1"):
        MortarProjection(a, b, label1="X")
    with pytest.raises(ValueError, match="axis"):
        MortarProjection(a, b, axis=(0.0, 0.0))
    with pytest.raises(ValueError, match="space2"):
        MortarProjection(a, b, space2=ContinuousSpace(a))
    m = MortarProjection(a, b)
    with pytest.raises(ValueError, match="entries"):
        m.project(np.ones(m.dofs2.size + 1))


@pytest.mark.parametrize("seed", range(6))
def test_projected_cg_kkt_against_scipy(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 40))
    M = rng.standard_normal((n, n))
    A = M @ M.T + 0.5 * np.eye(n)
    b = rng.standard_normal(n) * 3
    u = rng.standard_normal(n)
    u[rng.random(n) < 0.3] = np.inf
    x, info = projected_cg(A, b, u, tol=1e-12)
    assert info.converged, info.reason
    g = A @ x - b
    assert np.all(x <= u + 1e-14)
    at = x >= u
    assert np.all(g[at] <= 1e-9 * np.linalg.norm(b))            # multipliers >= 0
    assert np.linalg.norm(g[~at]) <= 1e-9 * np.linalg.norm(b)   # stationary on the free set
    L = sla.cholesky(A, lower=True)
    ref = lsq_linear(L.T, sla.solve_triangular(L, b, lower=True), bounds=(-np.inf, u),
                     tol=1e-14, lsmr_tol="auto", max_iter=10000).x
    assert np.linalg.norm(x - ref) <= 1e-6 * max(1.0, np.linalg.norm(ref))


def test_projected_cg_bad_input():
    with pytest.raises(ValueError, match="tol"):
        projected_cg(np.eye(2), np.ones(2), np.ones(2), tol=0.0)
    with pytest.raises(ValueError, match="upper"):
        projected_cg(np.eye(2), np.ones(2), np.ones(3))
    with pytest.raises(ValueError, match="x0"):
        projected_cg(np.eye(2), np.ones(2), np.ones(2), x0=np.zeros(3))
    x, info = projected_cg(np.eye(2), np.ones(2), np.full(2, 0.5))
    assert info.converged and np.allclose(x, 0.5) and info.counts["active"] == 2


def _projected_cg_numpy(A, b, u, tol, max_iter):
    """The numpy formulation that the compiled kernel replaced (reference)."""
    x = np.minimum(np.zeros(b.size), u)
    g = A @ x - b
    steps, res = 0, []

    def thr(x):
        return tol * max(np.linalg.norm(b), np.linalg.norm(A @ x), 1e-300)

    while steps < max_iter:
        pg = np.where(x >= u, np.maximum(g, 0.0), g)
        res.append(np.linalg.norm(pg))
        if res[-1] <= thr(x):
            return x, steps, res
        free = ~((x >= u) & (g <= 0.0))
        p = np.where(free, -g, 0.0)
        rr = p @ p
        while steps < max_iter:
            steps += 1
            Ap = A @ p
            alpha = rr / (p @ Ap)
            up = free & (p > 0)
            afeas = np.min((u[up] - x[up]) / p[up]) if np.any(up) else np.inf
            if afeas < alpha:
                x = x + afeas * p
                with np.errstate(invalid="ignore"):
                    hit = up & (x >= u - 1e-14 * np.maximum(np.abs(u), 1.0))
                x[hit] = u[hit]
                g = A @ x - b
                break
            x = x + alpha * p
            g = g + alpha * Ap
            gf = np.where(free, g, 0.0)
            if np.linalg.norm(gf) <= thr(x):
                g = A @ x - b
                break
            rr_new = gf @ gf
            p = -gf + (rr_new / rr) * p
            rr = rr_new
    return x, steps, res


@pytest.mark.parametrize("seed", range(6))
def test_projected_cg_compiled_matches_numpy_formulation(seed):
    """The compiled kernel takes the same steps as the numpy formulation (same active
    sets, same CG steps, same KKT residuals; the stopping threshold's A x is skipped
    only where a norm bound decides)."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(5, 60))
    M = rng.standard_normal((n, n))
    A = M @ M.T + 1e-3 * n * np.eye(n)
    b = rng.standard_normal(n) * 10.0 ** rng.integers(-3, 4)
    u = np.where(rng.random(n) < 0.3, np.inf, rng.standard_normal(n))
    x, info = projected_cg(A, b, u, tol=1e-11)
    xr, steps, res = _projected_cg_numpy(A, b, u, 1e-11, 20 * n + 100)
    assert info.converged and info.iterations == steps
    assert len(info.residuals) == len(res)
    np.testing.assert_allclose(info.residuals, res, rtol=1e-10, atol=0)
    np.testing.assert_allclose(x, xr, rtol=1e-12, atol=1e-14 * np.abs(xr).max())
