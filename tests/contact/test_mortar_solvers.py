"""Uzawa (Algorithm 4.4) and Dirichlet-to-Neumann (Algorithm 4.3) for the hp-mortar BEM
model problem of Section 4.3.4 (coarse meshes to stay fast)."""

import numpy as np
import pytest

from hpfebe.scenes import ModelProblem, model_problem
from hpfebe.solvers import (DtNSettings, GlobalUzawaSettings, SemismoothSettings,
                            UzawaSettings)


@pytest.fixture(scope="module")
def coarse():
    return model_problem(ModelProblem(n1=8, n2=6, p1=2, p2=1))


@pytest.fixture(scope="module")
def sticky():
    # friction bound comparable to the contact pressure: stick and slip zones
    return model_problem(ModelProblem(n1=8, n2=6, p1=2, p2=2, F=4000.0))


def test_uzawa_fixed_point_satisfies_tresca(sticky):
    pr = sticky
    x, lam, info = pr.uzawa(np.zeros(2 * pr.nc), UzawaSettings(tol=1e-10, max_iter=5000))
    assert info.converged, info.reason
    Qt = np.zeros(pr.nc)
    s = x[pr.nc:] - Qt
    scale = np.abs(s).max()
    assert np.all(np.abs(lam) <= 1.0)
    inner = np.abs(lam) < 1.0 - 1e-8
    assert inner.any() and (~inner).any()          # both stick and slip present
    assert np.abs(s[inner]).max() <= 1e-6 * scale   # stick where |lambda| < 1
    assert np.all(lam[~inner] * s[~inner] >= -1e-6 * scale)  # slip along lambda
    # normal contact: U_n <= g, contact force compressive where active
    assert np.all(x[:pr.nc] <= pr.gap + 1e-12)


def test_dtn_converges_and_satisfies_conditions(coarse):
    pr = coarse
    sol = pr.dtn(DtNSettings(0.5, 0.5, tol=1e-8))
    assert sol.info.converged, sol.info.reason
    assert sol.info.iterations == len(sol.info.steps)
    assert all(s.converged for s in sol.info.steps)
    r = pr.tresca_residual(sol)
    assert r["lam_excess"] <= 0 and r["stick_slip"] <= 1e-6 * r["slip_scale"]
    # action = reaction: traction transferred to body 2 balances the contact force on 1
    R1 = pr.body1.reaction(pr.R.T @ sol.x)
    P = pr.mortar.adjoint(R1)
    assert np.linalg.norm(P - sol.P) <= 1e-6 * np.linalg.norm(P)
    # total vertical force on body 1 from contact is upward (compression)
    assert R1.reshape(-1, 2)[:, 1].sum() > 0


def test_dtn_nonconvergence_detected(coarse):
    sol = coarse.dtn(DtNSettings(1.0, 1.0, max_iter=60))
    assert not sol.info.converged
    assert sol.info.reason == "max_iter" or sol.info.reason.startswith("diverged")
    sol = coarse.dtn(DtNSettings(0.5, 0.5, max_iter=3))
    assert not sol.info.converged and sol.info.reason == "max_iter"


def test_bad_input(coarse):
    with pytest.raises(ValueError, match="omega_D"):
        DtNSettings(0.0, 0.5)
    with pytest.raises(ValueError, match="omega_N"):
        DtNSettings(0.5, 1.5)
    with pytest.raises(ValueError, match="rho"):
        DtNSettings(0.5, 0.5, uzawa=UzawaSettings(rho=0.0))
    with pytest.raises(ValueError, match="rho"):
        coarse.uzawa(np.zeros(2 * coarse.nc), UzawaSettings(rho=-1.0))
    with pytest.raises(ValueError, match="F"):
        model_problem(ModelProblem(n1=4, n2=3, p1=1, p2=1, F=-1.0))
    with pytest.raises(ValueError, match="friction"):
        coarse.dtn(DtNSettings(0.5, 0.5), friction="stick")


def test_global_uzawa_agrees_with_dtn_tresca(coarse):
    """Algorithm 4.5 with Tresca friction solves the discrete problem of DtN."""
    pr = coarse
    d = pr.dtn(DtNSettings(0.7, 0.5, tol=1e-10,
                           uzawa=UzawaSettings(tol=1e-9, max_iter=20000)))
    g = pr.global_uzawa(GlobalUzawaSettings(rho=1.9, friction="tresca", tol=1e-10,
                                            max_iter=20000))
    assert d.info.converged and g.info.converged, (d.info.reason, g.info.reason)
    for a, b in ((d.U1, g.U1), (d.U2, g.U2)):
        assert np.abs(a - b).max() <= 1e-6 * np.abs(a).max()


def test_global_uzawa_coulomb_conditions(coarse):
    pr = coarse
    s = pr.global_uzawa(GlobalUzawaSettings(rho=1.9, friction="coulomb", mu_f=0.3, tol=1e-10,
                                            max_iter=20000))
    assert s.info.converged, s.info.reason
    pn, pt = s.extra["pn"], s.extra["pt"]
    d = pr.R @ (s.U1[pr.c1] - s.Q)
    dn, dt = d[:pr.nc] - np.where(np.isfinite(pr.gap), pr.gap, 0), d[pr.nc:]
    scale = np.abs(d).max()
    assert np.all(pn >= 0) and np.all(np.abs(pt) <= 0.3 * pn + 1e-12)
    assert np.all(dn[np.isfinite(pr.gap)] <= 1e-6 * scale)        # no penetration
    assert np.abs(pn * dn).max() <= 1e-6 * scale * pn.max()        # complementarity
    stick = np.abs(pt) < 0.3 * pn * (1 - 1e-6)
    assert np.max(np.abs(dt[stick & (pn > 0)]), initial=0.0) <= 1e-6 * scale
    with pytest.raises(ValueError, match="friction"):
        GlobalUzawaSettings(friction="coloumb")
    with pytest.raises(ValueError, match="rho"):
        GlobalUzawaSettings(rho=0.0)


def test_indicators_and_hp_refine(coarse):
    from hpfebe.adaptivity import hp_refine, mortar_indicators

    pr = coarse
    sol = pr.global_uzawa(GlobalUzawaSettings(rho=1.5, friction="coulomb", mu_f=0.1, tol=1e-8,
                                              max_iter=20000))
    (e1, e2), parts = mortar_indicators(pr, sol, return_parts=True)
    m1 = pr.bem1.mesh
    assert e1.shape == (m1.n_elements,) and e2.shape == (pr.bem2.mesh.n_elements,)
    assert np.all(np.isfinite(e1)) and np.all(e1 >= 0) and np.all(e2 >= 0)
    # the jump terms live on Gamma^1_C only
    off = m1.labels != "C"
    assert np.all(parts["jump_P"][off] == 0) and np.all(parts["penetration"][off] == 0)
    eta = np.linspace(0.0, 1.0, m1.n_elements)
    marked = eta >= 0.85
    new = hp_refine(m1, marked, eta, 0.9)
    nh = int(np.sum(eta >= 0.9))
    assert new.n_elements == m1.n_elements + nh
    assert int(np.sum(new.degrees > m1.degrees.max())) == int(marked.sum()) - nh
    with pytest.raises(ValueError, match="h_fraction"):
        hp_refine(m1, marked, eta, 0.0)
    with pytest.raises(ValueError, match="marked"):
        hp_refine(m1, marked[:-1], eta, 0.9)


def test_default_normals_and_aitken(coarse):
    from hpfebe.contact import MortarContact

    pr = MortarContact(coarse.bem1, coarse.bem2, ("D", (0.0, -0.09)), ("D", (0.0, 0.0)), 0.1)
    assert np.allclose(np.linalg.norm(pr.n, axis=1), 1.0)
    assert np.all(pr.n[:, 1] < 0)                  # outward normal of body 1: downward
    plain = pr.dtn(DtNSettings(0.7, 0.5))
    ait = pr.dtn(DtNSettings(0.7, 0.5, aitken=True))
    assert plain.info.converged and ait.info.converged
    assert np.abs(plain.U1 - ait.U1).max() <= 1e-4 * np.abs(plain.U1).max()
    # Aitken converges where fixed full damping cycles
    assert pr.dtn(DtNSettings(1.0, 1.0, aitken=True, max_iter=60)).info.converged


@pytest.mark.parametrize("friction", ["tresca", "coulomb"])
def test_semismooth_newton_agrees(coarse, friction):
    pr = coarse
    n = pr.semismooth_newton(SemismoothSettings(friction=friction, mu_f=0.3))
    u = pr.global_uzawa(GlobalUzawaSettings(rho=1.5, friction=friction, mu_f=0.3, tol=1e-11,
                                            max_iter=50000))
    assert n.info.converged and u.info.converged, (n.info.reason, u.info.reason)
    assert n.info.iterations <= 20
    assert np.abs(n.U1 - u.U1).max() <= 1e-7 * np.abs(u.U1).max()
    assert np.abs(n.U2 - u.U2).max() <= 1e-7 * np.abs(u.U2).max()
    if friction == "tresca":
        d = pr.dtn(DtNSettings(0.7, 0.5, tol=1e-10,
                               uzawa=UzawaSettings(tol=1e-9, max_iter=20000)))
        assert np.abs(n.U1 - d.U1).max() <= 1e-7 * np.abs(d.U1).max()


def _numpy_uzawa(pr, Q, rho, bound, tol, max_iter):
    """Algorithm 4.4 in its numpy formulation (projected_cg + the clip), by fixed_point."""
    from hpfebe.solvers import projected_cg
    from hpfebe.solvers import fixed_point

    nc = pr.nc
    F = pr.F if bound is None else bound
    Fw, upper = pr._qp_data(Q, bound)
    _, Qt = pr.frame(Q)
    st = {"x": None}

    def update(lam):
        rhs = np.array(pr.b, dtype=float)
        rhs[nc:] -= Fw * lam
        x, inner = projected_cg(pr.A, rhs, upper, st["x"], tol=1e-11,
                                max_iter=20 * rhs.size + 100)
        st["x"] = x
        return np.minimum(np.maximum(lam + rho * F * (x[nc:] - Qt), -1.0), 1.0), inner

    return fixed_point(update, np.zeros(nc), tol, max_iter, norm=2)


def test_compiled_uzawa_step_is_the_numpy_iteration(sticky):
    """uzawa's compiled iteration (solvers.uzawa._uzawa_step) gives the numpy formulation of Algorithm
    4.4: projected CG on b - (0, F w lambda), then the clip to [-1, 1].  To round-off,
    not bit for bit: the numpy side's products go through BLAS, whose summation order
    (and use of fused multiply-adds) depends on the CPU; the iteration counts may then
    differ by one where a residual lands on the stopping threshold."""
    pr, nc = sticky, sticky.nc
    rng = np.random.default_rng(3)
    Q = 1e-4 * rng.standard_normal(2 * nc)
    rho = pr.rho_step(1.0, True)
    for bound in (None, np.abs(rng.standard_normal(nc)) * pr.F):
        uz = UzawaSettings(rho=rho, tol=1e-9, max_iter=300, relative=False)
        _, lam, info = pr.uzawa(Q, uz, bound=bound)
        lam_ref, info_ref = _numpy_uzawa(pr, Q, rho, bound, 1e-9, 300)
        assert info.converged == info_ref.converged
        assert abs(info.iterations - info_ref.iterations) <= 1
        np.testing.assert_allclose(lam, lam_ref, rtol=0, atol=1e-9 * np.abs(lam_ref).max())
        assert info.steps == [] and info.counts["qp_solves"] == info.iterations
        n = min(len(info.residuals), len(info_ref.residuals))
        np.testing.assert_allclose(info.residuals[:n - 1], info_ref.residuals[:n - 1],
                                   rtol=1e-6)
    # the compiled loop's cap: fixed_point's "max_iter" outcome, one increment per step
    _, lam3, info3 = pr.uzawa(Q, UzawaSettings(rho=rho, tol=1e-12, max_iter=3,
                                                relative=False))
    lam3_ref, info3_ref = _numpy_uzawa(pr, Q, rho, None, 1e-12, 3)
    assert (info3.converged, info3.reason, info3.iterations) == (False, "max_iter", 3)
    assert info3_ref.reason == "max_iter" and len(info3.residuals) == 3
    np.testing.assert_allclose(lam3, lam3_ref, rtol=0, atol=1e-9 * np.abs(lam3_ref).max())
    with pytest.raises(ValueError, match="lam0"):
        pr.uzawa(Q, lam0=np.zeros(nc + 1))
    with pytest.raises(ValueError, match="x0"):
        pr.uzawa(Q, x0=np.zeros(3))


def test_condensed_solve_and_adjoint_match_scipy(coarse):
    """CondensedBody.solve (LAPACK potrs directly) and MortarProjection.adjoint (B^T
    formed once) give the numbers of scipy's cho_solve / B.T @ ... bit for bit."""
    import scipy.linalg as sla

    pr = coarse
    b1 = pr.body1
    load = np.linspace(-1.0, 1.0, b1.b.size)
    assert np.array_equal(b1.solve(load), sla.cho_solve(sla.cho_factor(b1.A), b1.b + load))
    with pytest.raises(ValueError, match="load_c"):
        b1.solve(np.full(b1.b.size, np.nan))
    m = pr.mortar
    r = np.linspace(0.5, 2.0, 2 * m.dofs1.size)
    ref = (m.B.T @ m._lu.solve(r.reshape(-1, 2), trans="T")).ravel()
    assert np.array_equal(m.adjoint(r), ref)
    assert np.array_equal(m.adjoint(r), ref)           # the cached transpose


def test_model_problem_bem_cache():
    """A shared bem_cache reuses body 2 across body-1 degrees, with the same numbers as
    a fresh set-up."""
    cache = {}
    a = model_problem(ModelProblem(n1=4, n2=3, p1=1, p2=1), bem_cache=cache)
    b = model_problem(ModelProblem(n1=4, n2=3, p1=2, p2=1), bem_cache=cache)
    assert b.bem2 is a.bem2 and b.bem1 is not a.bem1 and len(cache) == 3
    fresh = model_problem(ModelProblem(n1=4, n2=3, p1=2, p2=1))
    assert np.array_equal(b.A, fresh.A) and np.array_equal(b.body2.A, fresh.body2.A)


def test_dtn_solver_hook_and_relaxation_forms(coarse):
    """hpfebe.solvers.dtn on the BE problem: the hook sees every iterate (P_k, P_k+1,
    the reaction), may name the inner SolverInfo and set the friction bound of the next
    step 4; the printed (convex) and the increment form of step 6 agree to round-off."""
    from hpfebe.solvers import SolverInfo, dtn

    pr, seen = coarse, []

    def hook(st):
        seen.append((st.k, st.P.copy(), st.P_new.copy(), st.R1 is not None, st.bound))
        st.bound = np.full(pr.nc, pr.F)              # = F: the same problem
        return SolverInfo(True, "ok", st.contact_info.iterations)

    P, info, st = dtn(pr, DtNSettings(0.7, 0.5, relaxation="convex"), hook)
    assert info.converged and [s[0] for s in seen] == list(range(1, info.iterations + 1))
    assert seen[0][4] is None and all(s[4] is not None for s in seen[1:])
    assert all(s[3] for s in seen) and np.array_equal(seen[-1][2], P)
    assert all(s.reason == "ok" for s in info.steps)
    ref = pr.dtn(DtNSettings(0.7, 0.5))
    assert abs(ref.info.iterations - info.iterations) <= 1
    assert np.abs(ref.P - P).max() <= 1e-6 * np.abs(P).max()
    with pytest.raises(ValueError, match="relaxation"):
        DtNSettings(0.7, 0.5, relaxation="convex", aitken=True)


def test_one_return_map_for_penalty_and_mortar():
    """The Tresca return map of constitutive.laws: compiled (tresca_return), on arrays
    (friction_projection) and inside penalty_friction, the same numbers."""
    from hpfebe.constitutive.laws import friction_projection, penalty_friction, tresca_return

    rng = np.random.default_rng(1)
    trial, bound = 3 * rng.standard_normal(200), np.abs(rng.standard_normal(200))
    bound[:20] = 0.0
    fp = friction_projection(trial, bound)
    assert np.array_equal(fp, [tresca_return(t, b) for t, b in zip(trial, bound)])
    assert np.array_equal(fp, np.clip(trial, -bound, bound))
    law = penalty_friction(np.ones(200), trial, 0.0, 1.0, 1.0, F=bound)
    assert np.array_equal(law.t_t, fp)
    assert np.isnan(tresca_return(np.nan, 1.0))
