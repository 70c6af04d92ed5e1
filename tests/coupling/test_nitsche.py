"""hp-Nitsche FE/BE coupling (Chapter 2): meshes, interface quadrature, reproduction of the
thesis's numbers, convergence rates, lambda_Nit and the coercivity threshold.

All checks come from real solves at reduced sizes.  The first test that touches the BEM
compiles its numba kernels (about a minute on 2 cores when the cache misses).
"""

import numpy as np
import pandas as pd
import pytest

from hpfebe.analysis.rates import observed_rates
from hpfebe.coupling import NitscheFEBE
from hpfebe.coupling.coercivity import (coercivity_threshold, inverse_constant,
                                        lemma_2_2_3_bound)
from hpfebe.coupling.errors import (_graded_corner_rule, be_domain_errors, be_solution_at,
                                    be_trace_energy_error, boundary_values, fe_errors)
from hpfebe.coupling.interface import common_refinement, interface_rule
from hpfebe.scenes.interface import SINGULAR, SMOOTH, lambda_sweep, problem
from hpfebe.fem import PoissonFE, block_grid

PUBLISHED = "report/published/"


def solve(pb, fh, bh, p, lambda_nit=10.0, **kw):
    model = NitscheFEBE(pb, fh, bh, p, **kw)
    sol = model.solve(lambda_nit)
    return model, sol, fe_errors(model, sol), be_domain_errors(model, sol)


def published(name):
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    return pd.read_csv(root / PUBLISHED / name, comment="#")


# ----------------------------------------------------------------------- FE and meshes
def test_thesis_fe_mesh_has_75_elements_and_resolves_interface():
    d = SMOOTH.fe_domain(5)
    assert d.n_elements == 75                      # "75 finite elements" (Section 2.2.5)
    assert SMOOTH.fe_domain(5).facets["I"].size == 15
    np.testing.assert_allclose(d.facet_length(d.facets["I"]), 0.2)
    ys = block_grid([-1, -0.5, 0.5, 1], 5)
    assert len(ys) - 1 == 10 and np.isclose(ys, -0.5).any() and np.isclose(ys, 0.5).any()
    assert len(block_grid([-1, -0.5, 0.5, 1], 5, rounding="ceil")) - 1 == 11
    assert SINGULAR.fe_domain(4).n_elements == 36


@pytest.mark.parametrize("p", [3, 4])
def test_fe_space_is_h1_conforming(p):
    d = SMOOTH.fe_domain(5)
    fe = PoissonFE(d, p)
    m = d.mesh
    inner = np.flatnonzero(m.f2t[1] >= 0)
    s = np.random.default_rng(0).random(inner.size)
    P = m.p[:, m.facets[:, inner]]
    x = (P[:, 0] + s * (P[:, 1] - P[:, 0])).T
    U = np.random.default_rng(1).random(fe.ndof)
    v0 = fe.eval_matrices(x, m.f2t[0, inner])[0] @ U
    v1 = fe.eval_matrices(x, m.f2t[1, inner])[0] @ U
    assert np.abs(v0 - v1).max() < 1e-12


def test_bad_input_raises():
    with pytest.raises(ValueError, match="h_inv"):
        block_grid([0, 1], -1)
    with pytest.raises(ValueError, match="p"):
        PoissonFE(SMOOTH.fe_domain(2), 0)
    with pytest.raises(ValueError, match="problem"):
        problem("square")
    d, be = SMOOTH.fe_domain(2), SMOOTH.be_mesh(3, 1)
    with pytest.raises(ValueError, match="h_def"):
        interface_rule(d, be, 2, h_def="radius")


# ----------------------------------------------------------------------- interface
def test_common_refinement_of_nonmatching_meshes():
    d, be = SMOOTH.fe_domain(5), SMOOTH.be_mesh(6, 2)
    P0, P1, f, e = common_refinement(d, be)
    # each of the 3 interface sides: 5 FE and 6 BE elements share only the side ends
    assert len(P0) == 3 * (5 + 6 - 1)
    assert np.isclose(np.linalg.norm(P1 - P0, axis=1).sum(), 3.0)
    rule = interface_rule(d, be, 3)
    assert np.isclose(rule.w.sum(), 3.0)
    with pytest.raises(ValueError, match="same Gamma_I"):
        common_refinement(SMOOTH.fe_domain(5), SINGULAR.be_mesh(6, 1))


def test_penalty_vanishes_on_continuous_linears_and_system_is_symmetric():
    model = NitscheFEBE(SMOOTH, 5, 6, 2)
    # linear, zero on Gamma_D = {x = -1}: in both trace spaces, so the jump vanishes
    lin = lambda x, y: 0.7 * (x + 1.0)  # noqa: E731
    fe_dofs = model.fe.basis.project(lambda x: lin(x[0], x[1]))
    U1 = fe_dofs[model.free1]
    U2 = model.bem.V_space.interpolate(lambda X: lin(X[:, 0], X[:, 1]))[model.free2]
    jump_energy = (U1 @ model.P11 @ U1 - 2 * U1 @ model.P12 @ U2 + U2 @ model.P22 @ U2)
    assert abs(jump_energy) < 1e-12 * (U1 @ model.P11 @ U1)
    K = model.matrix(10.0)
    assert abs(K - K.T).max() < 1e-12 * abs(K).max()


# ----------------------------------------------------------------------- reproduction
@pytest.mark.parametrize("p", [1, 2, 3])
def test_reproduces_thesis_tables_2_1_and_2_2_on_coarsest_mesh(p):
    """FE h^-1 = 2, BE h^-1 = 3: alpha = 0, h1 = edge length, equidistant Q_p post-
    processing of the BE part reproduce the printed digits."""
    _, _, fe, be = solve(SMOOTH, 2, 3, p)
    t1 = published("table_2_1_nitsche_smooth_h_BE.csv")
    t2 = published("table_2_2_nitsche_smooth_h_FE.csv")
    r1 = t1[(t1.h_inv == 3) & (t1.p == p)].iloc[0]
    r2 = t2[(t2.h_inv == 2) & (t2.p == p)].iloc[0]
    assert fe["l2"] == pytest.approx(r2.l2_error, rel=2e-3)
    assert fe["h1"] == pytest.approx(r2.h1_error, rel=2e-3)
    assert be["l2"] == pytest.approx(r1.l2_error, rel=3e-2)
    assert be["h1"] == pytest.approx(r1.h1_error, rel=3e-2)


# ----------------------------------------------------------------------- smooth example
@pytest.mark.parametrize("p", [1, 2, 3])
def test_smooth_h_version_fe_rates(p):
    """Nested non-matching meshes FE h^-1 = 4, 8, 16 / BE h^-1 = 5, 10, 20 (the thesis's
    2, 5, 11, 23 sequence is not nested and its rates scatter by 0.2-0.4);
    lambda_Nit = 20 (above the coercivity threshold for p <= 3, see below)."""
    errs = [solve(SMOOTH, fh, bh, p, lambda_nit=20.0)[2] for fh, bh in [(4, 5), (8, 10), (16, 20)]]
    h = np.array([1 / 4, 1 / 8, 1 / 16])
    r_l2 = observed_rates(h, np.array([e["l2"] for e in errs]))
    r_h1 = observed_rates(h, np.array([e["h1"] for e in errs]))
    assert abs(r_h1[-1] - p) <= 0.15, r_h1
    assert abs(r_l2[-1] - (p + 1)) <= 0.15, r_l2


def test_smooth_p_version_converges_geometrically():
    """Fixed meshes FE h = 1/5, BE h = 1/6 (Figure 2.2), p1 = p2 = 1..6."""
    e = np.array([[v for v in solve(SMOOTH, 5, 6, p)[2].values()] for p in range(1, 7)])
    ratios = e[1:] / e[:-1]
    assert np.all(ratios < 0.35), ratios          # each degree gains a fixed factor
    # log-linear in p: the last error is below the geometric extrapolation of the first
    assert np.all(e[-1] < e[0] * 0.35 ** 5)


# ----------------------------------------------------------------------- singular example
def test_singular_h_version_rates():
    """Table 2.3/2.4 meshes FE h^-1 = 4, 8, 16, BE h^-1 = 8, 12, 20, p = 1."""
    runs = [solve(SINGULAR, fh, bh, 1) for fh, bh in [(4, 8), (8, 12), (16, 20)]]
    h_be = 1 / np.array([8.0, 12.0, 20.0])
    h_fe = 1 / np.array([4.0, 8.0, 16.0])
    be_rate = observed_rates(h_be, np.array([r[3]["h1"] for r in runs]))
    fe_rate = observed_rates(h_fe, np.array([r[2]["h1"] for r in runs]))
    assert np.all(np.abs(be_rate[1:] - 2 / 3) <= 0.08), be_rate
    assert np.all(np.abs(fe_rate[1:] - 1.0) <= 0.1), fe_rate
    # and the printed errors (Table 2.3 h-version, Table 2.4 h-version)
    t4 = published("table_2_4_nitsche_singular_FE.csv")
    for (fh, _), r in zip([(4, 8), (8, 12), (16, 20)], runs):
        ref = t4[(t4.series == "h") & (t4.h_inv == fh)].iloc[0]
        assert r[2]["h1"] == pytest.approx(ref.h1_error, rel=2e-3)


def _singular_p_runs(degrees=(3, 4, 5)):
    return [solve(SINGULAR, 4, 6, p)[:2] for p in degrees]


def _singular_p_rates():
    e = np.array([be_domain_errors(m, s)["h1"] for m, s in _singular_p_runs()])
    return observed_rates(1.0 / np.array([3.0, 4.0, 5.0]), e)


def test_singular_p_version_be_rate_between_theory_bounds():
    """Table 2.3 prints ~0.8 for the p-version BE energy rate; with the post-processing
    that reproduces Table 2.1, the h-version of Table 2.3 and the exact FE p-version
    errors of Table 2.4 we measure 1.0-1.1 (p = 3..5): the rate of the Q_p interpolation
    of r^(2/3) on the fixed mesh (next test), reported as "differs (explained)" by
    experiments/ch2_convergence.py.  What holds: at least the 5/6 of Theorem 2.2.3, at
    most the 4/3 of the optimal p-BEM (Stephan and Suri) plus 0.1."""
    r = _singular_p_rates()[-1]
    assert 5 / 6 <= r <= 4 / 3 + 0.1, r


def test_singular_p_version_omega2_error_is_the_interpolation_error_of_the_corner():
    """Why Table 2.3's p-version rate is not a rate of the BE solution: the H1 error in
    Omega2 equals that of the same Q_p interpolant of the exact u (to 1 %), while the
    trace energy error |u - U2|_W converges at more than twice the 5/6 of Theorem 2.2.3
    (u = 0 on both Gamma_D sides of the singular corner: the trace is smooth)."""
    runs = _singular_p_runs()
    for m, s in runs:
        assert be_domain_errors(m, s)["h1"] == pytest.approx(
            be_domain_errors(m, s, interpolate_exact=True)["h1"], rel=1e-2)
    e = np.array([be_trace_energy_error(m, s) for m, s in runs])
    r = observed_rates(1.0 / np.array([3.0, 4.0, 5.0]), e)
    assert r[-1] > 2 * 5 / 6, r


def test_graded_corner_rule_integrates_the_corner_singularity():
    """int over [0,1]^2 of r^(-2/3) = (3/2) int_0^(pi/4) sec(t)^(4/3) dt, and the BE-part
    error of Example 2 does not depend on the number of Gauss points any more."""
    from scipy.integrate import quad
    exact = 1.5 * quad(lambda t: np.cos(t) ** (-4.0 / 3.0), 0.0, np.pi / 4, epsabs=1e-14)[0]
    xi, eta, w = _graded_corner_rule(8)
    assert w.sum() == pytest.approx(4.0, rel=1e-14)
    x, y = 0.5 * (xi + 1.0), 0.5 * (eta + 1.0)
    assert (0.25 * w * np.hypot(x, y) ** (-2.0 / 3.0)).sum() == pytest.approx(exact, rel=1e-10)
    m, s = solve(SINGULAR, 4, 6, 6)[:2]
    a, b = be_domain_errors(m, s), be_domain_errors(m, s, n_gauss=30)
    assert a["h1"] == pytest.approx(b["h1"], rel=1e-8)
    assert a["l2"] == pytest.approx(b["l2"], rel=1e-8)


# ----------------------------------------------------------------------- lambda_Nit
def test_lambda_below_threshold_breaks_convergence_above_it_does_not_matter():
    """p = 1: lambda = 1 is below lambda* (about 1.1); lambda = 10 and 20 are above."""
    meshes = [(4, 5), (8, 10), (16, 20)]
    e1 = np.array([solve(SMOOTH, fh, bh, 1, lambda_nit=1.0)[2]["h1"] for fh, bh in meshes])
    e10 = np.array([solve(SMOOTH, fh, bh, 1, lambda_nit=10.0)[2]["h1"] for fh, bh in meshes])
    e20 = np.array([solve(SMOOTH, fh, bh, 1, lambda_nit=20.0)[2]["h1"] for fh, bh in meshes])
    r1 = observed_rates(1 / np.array([4.0, 8.0, 16.0]), e1)
    assert r1[-1] < 0.5 or np.all(e1 > 2 * e10), (r1, e1 / e10)
    np.testing.assert_allclose(e10, e20, rtol=0.05)


def test_coercivity_threshold_grows_like_p_squared_for_alpha_0():
    star = [coercivity_threshold(NitscheFEBE(SMOOTH, 5, 6, p)) for p in (1, 2, 3)]
    assert star[0] < star[1] < star[2]
    assert 1.0 < star[0] < 5.0 and 5.0 < star[2]   # the thesis's lambda = 1 / 5 observations
    # alpha only rescales the penalty: lambda*(alpha) = lambda*(0) p^-alpha
    star2 = coercivity_threshold(NitscheFEBE(SMOOTH, 5, 6, 3, alpha=2.0))
    assert star2 == pytest.approx(star[2] / 9.0, rel=1e-8)
    # the computed threshold respects the sufficient condition of Lemma 2.2.3
    model = NitscheFEBE(SMOOTH, 5, 6, 3)
    C = inverse_constant(model)
    assert star[2] <= C * 9 * (1 + 1e-8) < lemma_2_2_3_bound(3, 0.0, C)


def test_lambda_sweep_rows_equal_separate_solves():
    rows = lambda_sweep("smooth", 2, 3, 2, [5.0, 20.0], companions=True)
    assert [r["lambda_nit"] for r in rows] == [5.0, 20.0]
    for r in rows:
        model, sol, fe, be = solve(SMOOTH, 2, 3, 2, lambda_nit=r["lambda_nit"])
        assert (r["fe_l2"], r["fe_h1"], r["be_l2"], r["be_h1"]) == (
            fe["l2"], fe["h1"], be["l2"], be["h1"])
        assert r["dof"] == model.ndof and r["residual"] < 1e-12
        assert r["be_energy"] == be_trace_energy_error(model, sol)
        assert r["wall_time_s"] == r["assembly_s"] + r["solve_s"]
    assert "be_energy" not in lambda_sweep(SMOOTH, 2, 3, 1, 10.0)[0]
    with pytest.raises(ValueError, match="lambda_Nit"):
        lambda_sweep("smooth", 2, 3, 1, [-1.0])
    with pytest.raises(ValueError, match="lambdas"):
        lambda_sweep("smooth", 2, 3, 1, [])


def test_be_solution_on_the_boundary_is_U2_inside_the_representation():
    model, sol = solve(SMOOTH, 5, 6, 2)[:2]
    mesh = model.be_mesh
    on = mesh.points(np.arange(mesh.n_elements), np.full(mesh.n_elements, 0.3))
    inside = np.array([[-0.5, 0.0], [-0.25, 0.1]])                 # points of Omega2
    v = boundary_values(model, sol.U2, np.vstack([on, inside]))
    np.testing.assert_allclose(
        v[:len(on)], model.bem.V_space.evaluate(sol.U2, np.arange(mesh.n_elements),
                                                np.full(mesh.n_elements, 0.3)),
        rtol=1e-14, atol=1e-16)
    assert np.isnan(v[len(on):]).all()
    u = be_solution_at(model, sol.U2, inside)
    np.testing.assert_allclose(u, SMOOTH.u(inside[:, 0], inside[:, 1]), rtol=2e-3)


def test_solver_reports_residual():
    model = NitscheFEBE(SMOOTH, 2, 3, 1)
    sol = model.solve(10.0)
    assert sol.info["residual"] < 1e-12
    with pytest.raises(ValueError, match="lambda_Nit"):
        model.solve(-1.0)


def test_solve_returns_solver_info():
    """The Nitsche solve reports through the one SolverInfo of hpfebe.solvers."""
    from hpfebe.scenes.interface import problem
    from hpfebe.coupling.nitsche import NitscheFEBE
    from hpfebe.solvers import SolverInfo

    sol = NitscheFEBE(problem("smooth"), 2, 3, 1).solve()
    assert isinstance(sol.solver, SolverInfo) and sol.solver.converged
    assert sol.solver.residuals[-1] == sol.info["residual"] <= 1e-10


def test_nitsche_lu_is_symmetric_mode_and_equals_partial_pivoting():
    """The coupled system is factorised by SuperLU in symmetric mode (reported), and its
    solution equals the one of the default LU (COLAMD, partial pivoting) to round-off,
    for lambda_nit above and below the coercivity threshold."""
    import scipy.sparse.linalg as spla

    model = NitscheFEBE(SMOOTH, 4, 6, 3)
    for lam in (10.0, 0.5):
        sol = model.solve(lam)
        assert sol.info["lu"] in ("symmetric", "partial pivoting")
        assert sol.info["lu"] in sol.solver.reason
        M = model.matrix(lam).tocsc()
        x = spla.splu(M).solve(np.concatenate([model.b1, model.b2]))
        U = np.concatenate([sol.U1[model.free1], sol.U2[model.free2]])
        assert np.linalg.norm(U - x) <= 1e-10 * np.linalg.norm(x)
    assert model.solve(10.0).info["lu"] == "symmetric"
