"""Tests of penalty contact with Tresca / Coulomb friction (hpfebe.contact.friction),
Sections 3.3.1 and 4.2.1-4.2.5.

Scene: the thesis's block [-1, 1]^2 (E = 266926, nu = 0.29, plane strain), Gamma_D the
top (U = 0), Gamma_C the bottom (n = (0, -1), tangent t = (1, 0)); the rigid plane
y = -1 is pushed into the body by d (gap g = -d) and slides by w along +x
(``obstacle_slip``).  Small w: the whole contact sticks; large w: it slips.
"""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem.lame import LameBEM
from hpfebe.bodies import BEBody, RigidObstacle
from hpfebe.constitutive import SLIP, STICK
from hpfebe.contact import FrictionSettings, TwoBodyContact, solve_friction, solve_penalty
from hpfebe.quadrature import gauss_legendre
from hpfebe.spaces import lagrange_values


def _solve(bem, eps_n, eps_t, gap, obstacle_slip=None, load=None, S=None, initial=None,
           **law):
    """:func:`solve_friction` with the law and solver keywords ``law`` of
    :class:`FrictionSettings`."""
    return solve_friction(bem, gap, FrictionSettings(eps_n, eps_t, **law),
                          obstacle_slip=obstacle_slip, load=load, S=S, initial=initial)

E, NU, D = 266926.0, 0.29, 2e-4
EPS_N = EPS_T = 1e-5
MU, FT = 0.3, 20.0


@pytest.fixture(scope="module")
def body():
    mesh = BoundaryMesh.polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)], n=6, p=2,
                                labels=["C", "N", "D", "N"])
    return LameBEM(mesh, E, NU, plane="strain")


def _independent_residual(bem, U, law, w, bound, eps_n=EPS_N, eps_t=EPS_T):
    """S_hat U + int p_n v_n + int t_t v_t over the free dofs, with the traces, the
    penalty law and the one-step return map t_t = clamp((U_t - w)/eps_t, s) coded here
    independently (own Gauss rule with p + 1 points per element)."""
    mesh, Vs = bem.mesh, bem.V_space
    Fv = bem.S_hat @ U
    for e in np.flatnonzero(mesh.where("C")):
        p = int(mesh.degrees[e])
        xq, wq = gauss_legendre(p + 1)
        wt = wq * mesh.lengths[e] / 2
        phi = lagrange_values(p, xq)
        d = Vs.elem_dofs[e, :p + 1]
        n = mesh.normals[e]
        tg = mesh.tangents[e]
        ux, uy = phi @ U[2 * d], phi @ U[2 * d + 1]
        pn = np.maximum(ux * n[0] + uy * n[1] + D, 0.0) / eps_n
        s = bound if law == "tresca" else MU * pn
        tt = np.clip((ux * tg[0] + uy * tg[1] - w) / eps_t, -s, s)
        for c in range(2):
            Fv[2 * d + c] += phi.T @ (wt * (pn * n[c] + tt * tg[c]))
    free = np.ones(len(U), bool)
    Dd = Vs.dofs_on("D")
    free[2 * Dd] = free[2 * Dd + 1] = False
    return Fv[free]


def _check_equation(bem, res, law, w, bound=None):
    r = _independent_residual(bem, res.U, law, w, bound)
    assert np.abs(r).max() <= 1e-9 * np.abs(bem.S_hat @ res.U).max()


def test_coulomb_stick_below_threshold(body):
    w = 5e-5
    res = _solve(body, EPS_N, EPS_T, -D, friction="coulomb", mu_f=MU,
                         obstacle_slip=w)
    assert res.converged and res.reason == "converged", res.reason
    assert np.all(res.state == STICK)
    assert np.all(res.p_n > 0)
    assert np.max(np.abs(res.t_t) / (MU * res.p_n)) < 0.9       # strictly inside the cone
    _check_equation(body, res, "coulomb", w)
    # stick = bonded contact: the linear problem with both penalty springs, assembled here
    U = res.U
    mesh, Vs = body.mesh, body.V_space
    ndof = len(U)
    A = body.S_hat.copy()
    b = np.zeros(ndof)
    for e in np.flatnonzero(mesh.where("C")):
        p = int(mesh.degrees[e])
        xq, wq = gauss_legendre(p + 3)            # exact for the bonded (polynomial) terms
        wt = wq * mesh.lengths[e] / 2
        phi = lagrange_values(p, xq)
        d = Vs.elem_dofs[e, :p + 1]
        for vec, c0, eps in ((mesh.normals[e], D, EPS_N), (mesh.tangents[e], -w, EPS_T)):
            Nl = np.zeros((len(xq), ndof))
            Nl[:, 2 * d] = phi * vec[0]
            Nl[:, 2 * d + 1] = phi * vec[1]
            A += Nl.T @ (wt[:, None] * Nl) / eps
            b -= Nl.T @ (wt * c0) / eps
    free = np.ones(ndof, bool)
    Dd = Vs.dofs_on("D")
    free[2 * Dd] = free[2 * Dd + 1] = False
    Ub = np.zeros(ndof)
    Ub[free] = np.linalg.solve(A[np.ix_(free, free)], b[free])
    assert np.abs(Ub - U).max() <= 1e-10 * np.abs(Ub).max()


def test_coulomb_full_slip_above_threshold(body):
    w = 1e-3
    res = _solve(body, EPS_N, EPS_T, -D, friction="coulomb", mu_f=MU,
                         obstacle_slip=w, predictor=False)
    assert res.converged, res.reason
    assert np.all(res.state == SLIP) and np.all(res.p_n > 0)
    # t_t = mu_f p_n pointwise, opposing the obstacle's motion (t_t < 0: the obstacle
    # drags the body along +x)
    assert np.all(res.t_t < 0)
    assert np.allclose(-res.t_t, MU * res.p_n, rtol=1e-8, atol=0)
    Fn, Ft = res.total_forces()
    assert abs(-Ft - MU * Fn) <= 1e-8 * MU * Fn
    _check_equation(body, res, "coulomb", w)
    # full slip is linear once the state is known: with the consistent linearisation
    # (including d p_n / dU in the slip term) Newton needs exactly one step from U = 0
    assert res.iterations == [1] and not res.steps[0].predictor_used
    # monotone loading in 4 increments: the same end state (path independent in full slip)
    res4 = _solve(body, EPS_N, EPS_T, -D, friction="coulomb", mu_f=MU,
                          obstacle_slip=w, load_steps=4)
    assert res4.converged and len(res4.steps) == 4
    assert [s.load_factor for s in res4.steps] == [0.25, 0.5, 0.75, 1.0]
    assert np.abs(res4.U - res.U).max() <= 1e-10 * np.abs(res.U).max()


def test_tresca_stick_partial_and_full_slip(body):
    stick = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                           obstacle_slip=1e-5)
    assert stick.converged and np.all(stick.state == STICK)
    assert np.abs(stick.t_t).max() < 0.5 * FT
    _check_equation(body, stick, "tresca", 1e-5, FT)

    part = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                          obstacle_slip=1e-3)
    assert part.converged, part.reason
    sl = part.state == SLIP
    assert 0 < sl.sum() < len(sl)                       # a genuine stick/slip split
    assert np.allclose(np.abs(part.t_t[sl]), FT, rtol=1e-12, atol=0)
    assert np.all(np.abs(part.t_t[~sl]) <= FT * (1 + 1e-12))
    assert np.all(part.t_t[sl] < 0)
    _check_equation(body, part, "tresca", 1e-3, FT)
    # the slip variable is consistent with the return map: g_p = U_t - w - eps_t t_t,
    # zero on the stick zone
    assert np.abs(part.slip[~sl]).max() <= 1e-12 * np.abs(part.slip).max()
    assert np.all(part.slip[sl] < 0)

    full = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                          obstacle_slip=1e-2)
    assert full.converged and np.all(full.state == SLIP)
    assert np.allclose(full.t_t, -FT, rtol=1e-12, atol=0)
    _check_equation(body, full, "tresca", 1e-2, FT)


def test_newton_converges_quadratically(body):
    """The residual is piecewise linear in U (state at fixed Gauss points) and the Newton
    matrix is its exact generalised derivative: once the stick/slip/contact sets are
    found the next step solves to round-off.  Plain Newton from U = 0 (no predictor).
    Assert the superlinear end: normalised residuals satisfy r_{k+1} <= C r_k^2 in the
    last two steps (C = 50; measured <= 25), a final drop below 1e-12, few iterations."""
    for law, kw, w in (("tresca", {"F": FT}, 1e-3), ("coulomb", {"mu_f": MU}, 1e-4),
                       ("tresca", {"F": 10.0}, 3e-4), ("coulomb", {"mu_f": MU}, 1.8e-4)):
        res = _solve(body, EPS_N, EPS_T, -D, friction=law, obstacle_slip=w,
                             predictor=False, **kw)
        assert res.converged, (law, res.reason)
        r = np.array(res.residuals[0]) / res.residuals[0][0]
        assert 2 <= len(r) - 1 <= 8, (law, r)
        assert r[-1] <= 1e-12
        assert np.all(r[2:][-2:] <= 50.0 * r[1:-1][-2:] ** 2), (law, r)


def test_linearisation_is_consistent(body):
    """Finite differences of the residual along random directions reproduce the Newton
    matrix (Coulomb: stick, slip with the d p_n/dU coupling, open points)."""
    gap = lambda p: -D + 3e-4 * (p[:, 0] + 1)            # tilted obstacle: open points
    motion = lambda p: 2e-4 * (1 + p[:, 0])
    rng = np.random.default_rng(0)
    res = _solve(body, EPS_N, EPS_T, gap, friction="coulomb", mu_f=MU,
                         obstacle_slip=motion)
    assert res.converged, res.reason
    U = res.U
    pr = TwoBodyContact(BEBody(body), RigidObstacle(gap, motion), "C", eps_n=EPS_N,
                        eps_t=EPS_T, mu_f=MU, nq=None)
    slip = np.zeros(len(pr.points))
    _, st = pr.internal_force(U, slip)
    assert np.allclose(st["t_t"], res.t_t, rtol=0, atol=1e-12 * np.abs(res.t_t).max())
    states = set(st["state"].tolist())
    assert states == {0, 1, 2}, states
    J = pr.tangent(st)
    for _ in range(3):
        v = rng.standard_normal(len(U)) * np.abs(U).max()
        h = 1e-6
        Fp = pr.internal_force(U + h * v, slip)[0]
        Fm = pr.internal_force(U - h * v, slip)[0]
        fd = (Fp - Fm) / (2 * h)
        assert np.abs(fd - J @ v).max() <= 1e-6 * np.abs(J @ v).max()
    assert not np.allclose(J, J.T)                        # Coulomb: non-symmetric


def test_frictionless_limit_matches_penalty(body):
    """F = 0 (Tresca) and mu_f = 0 (Coulomb) reduce to the frictionless solver of
    penalty.py (full contact: no kink inside elements, both integrations exact)."""
    ref = solve_penalty(body, EPS_N, -D)
    for kw in ({"friction": "tresca", "F": 0.0}, {"friction": "coulomb", "mu_f": 0.0}):
        res = _solve(body, EPS_N, EPS_T, -D, obstacle_slip=1e-4, **kw)
        assert res.converged
        assert np.abs(res.U - ref.U).max() <= 1e-10 * np.abs(ref.U).max()
        assert np.all(res.t_t == 0)


@pytest.mark.parametrize("kw, name", [
    ({"eps_n": 0.0}, "eps_n"), ({"eps_n": -1.0}, "eps_n"), ({"eps_n": np.nan}, "eps_n"),
    ({"eps_t": 0.0}, "eps_t"), ({"eps_t": -1e-5}, "eps_t"),
    ({"friction": "coulomb", "mu_f": -0.1, "F": None}, "mu_f"),
    ({"friction": "coulomb", "F": None}, "mu_f"),
    ({"F": -1.0}, "F"), ({"F": None}, "F"), ({"F": lambda x: -1 + 0 * x[:, 0]}, "F"),
    ({"friction": "amontons"}, "friction"), ({"friction": None}, "friction"),
    ({"load_steps": 0}, "load_steps"), ({"max_iter": 0}, "max_iter"),
    ({"max_iter": None}, "max_iter"), ({"load_steps": 1.5}, "load_steps"),
    ({"tol": 0.0}, "tol"), ({"S": np.zeros((3, 3))}, "S"),
    ({"contact_label": "X"}, "contact_label"), ({"load": np.zeros(3)}, "load"),
    ({"obstacle_slip": lambda x: np.nan + x[:, 0]}, "obstacle_slip"),
])
def test_bad_input(body, kw, name):
    args = dict(eps_n=EPS_N, eps_t=EPS_T, gap=-D, friction="tresca", F=FT)
    args.update(kw)
    with pytest.raises(ValueError, match=name):
        _solve(body, **args)


def test_non_convergence_is_reported(body):
    res = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                         obstacle_slip=1e-3, max_iter=2, predictor=False)
    assert not res.converged
    assert res.reason == "load step 1/1: max_iter"
    assert res.steps[0].iterations == 2 and len(res.residuals[0]) == 3
    # a multi-step run stops at the failing step and says which
    res = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                         obstacle_slip=4e-3, load_steps=4, max_iter=1, predictor=False)
    assert not res.converged and res.reason.startswith("load step ")
    assert len(res.steps) < 4 or not res.steps[-1].converged
    # a singular Newton matrix (no elastic stiffness, no contact) is detected
    zero = np.zeros_like(body.S_hat)
    res = _solve(body, EPS_N, EPS_T, +1e-3, friction="tresca", F=FT,
                         obstacle_slip=1e-6, S=zero)
    assert not res.converged and "singular" in res.reason


# --------------------------------------------------------------------------------------
# Neumann scene: no Dirichlet side; the top carries the traction (q_x, -q_y), the body is
# held by the obstacle (pushed in by d) and friction alone.  Testing (*) with the rigid
# translations gives global equilibrium: int p_n = 2 q_y and int t_t = 2 q_x; the
# friction capacity is 2 F (Tresca) or mu_f * 2 q_y (Coulomb).
QY = 10.0


@pytest.fixture(scope="module")
def free_body():
    mesh = BoundaryMesh.polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)], n=6, p=2,
                                labels=["C", "N", "T", "N"])
    return LameBEM(mesh, E, NU, plane="strain")


def _top_load(bem, qx, qy):
    """L(v) = int_top (qx, qy) . v ds on V_hp^2."""
    mesh, Vs = bem.mesh, bem.V_space
    f = np.zeros(2 * Vs.ndof)
    for e in np.flatnonzero(mesh.where("T")):
        p = int(mesh.degrees[e])
        xq, wq = gauss_legendre(p + 1)
        wt = wq * mesh.lengths[e] / 2
        phi = lagrange_values(p, xq)
        d = Vs.elem_dofs[e, :p + 1]
        f[2 * d] += phi.T @ wt * qx
        f[2 * d + 1] += phi.T @ wt * qy
    return f


@pytest.mark.parametrize("law, kw", [("coulomb", {"mu_f": MU}), ("tresca", {"F": 3.0})])
def test_neumann_load_equilibrium_stick_and_partial_slip(free_body, law, kw):
    for qx, steps in ((0.5, 1), (2.9, 1), (2.9, 3)):
        res = _solve(free_body, EPS_N, EPS_T, -D, friction=law,
                             load=_top_load(free_body, qx, -QY), load_steps=steps, **kw)
        assert res.converged, (law, qx, res.reason)
        Fn, Ft = res.total_forces()
        assert abs(Fn - 2 * QY) <= 1e-9 * 2 * QY
        assert abs(Ft - 2 * qx) <= 1e-9 * 2 * QY
        if qx == 0.5:
            assert np.all(res.state == STICK)
        else:
            sl = res.state == SLIP
            assert sl.any() and not sl.all()
            assert np.allclose(np.abs(res.t_t[sl]), res.bound[sl], rtol=1e-10, atol=0)
            assert np.all(np.abs(res.t_t) <= res.bound * (1 + 1e-12))
            assert np.all(res.t_t[sl] > 0)      # the body is pushed along +x


@pytest.mark.parametrize("law, kw", [("coulomb", {"mu_f": MU}), ("tresca", {"F": 3.0})])
def test_shear_beyond_friction_capacity_is_reported(free_body, law, kw):
    """2 q_x = 7 > capacity 6: no equilibrium exists; Newton must not claim convergence
    (the full-slip Newton matrix has the tangential translation in its kernel)."""
    res = _solve(free_body, EPS_N, EPS_T, -D, friction=law,
                         load=_top_load(free_body, 3.5, -QY), **kw)
    assert not res.converged
    assert res.reason.startswith("load step 1/1: ")
    assert "singular" in res.reason or "diverged" in res.reason or "max_iter" in res.reason


def test_history_unloading_is_elastic_then_reverse_slip(body):
    """Non-proportional loading through ``initial=``: slide the obstacle by w = 1e-2
    (full slip, t_t = -F), then move it back.  A small return (1e-6) unloads elastically:
    every point sticks, the accumulated slip g_t^p is unchanged and |t_t| < F.  Returning
    all the way to w = 0 makes the whole contact slip backwards (t_t = +F) - unlike the
    virgin solution at w = 0, which sticks: the slip history is carried."""
    a = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT, obstacle_slip=1e-2)
    assert a.converged and np.all(a.state == SLIP)
    b = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                       obstacle_slip=1e-2 - 1e-6, initial=a)
    assert b.converged, b.reason
    assert np.all(b.state == STICK)
    assert np.all((b.t_t > -FT) & (b.t_t < -FT + 0.5 * FT))
    assert np.abs(b.slip - a.slip).max() <= 1e-12 * np.abs(a.slip).max()
    c = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT,
                       obstacle_slip=0.0, initial=b, load_steps=2)
    assert c.converged and np.all(c.state == SLIP)
    assert np.allclose(c.t_t, FT, rtol=1e-12, atol=0)
    virgin = _solve(body, EPS_N, EPS_T, -D, friction="tresca", F=FT)
    assert np.all(virgin.state == STICK) and np.abs(virgin.t_t).max() < 0.2 * FT
    with pytest.raises(ValueError, match="initial"):
        _solve(body, EPS_N, EPS_T, -D, friction="coulomb", mu_f=MU, initial=a)


@pytest.mark.parametrize("law, kw, w", [("tresca", {"F": FT}, 5e-5),
                                        ("tresca", {"F": FT}, 1.8e-4),
                                        ("coulomb", {"mu_f": MU}, 1.8e-4)])
def test_stiff_penalty_bonded_predictor(body, law, kw, w):
    """eps = 1e-7 h (the thesis's stiffest Table 3.1 penalty): plain Newton from U = 0
    needs > 15 iterations (it starts in full slip and crawls into the stick band of width
    eps_t s), with the bonded predictor <= 4; both reach the same solution, and it solves
    the equation (independent residual, to the conditioning ~ 1/eps)."""
    eps = 1e-7 / 6
    plain = _solve(body, eps, eps, -D, friction=law, obstacle_slip=w,
                           predictor=False, **kw)
    pred = _solve(body, eps, eps, -D, friction=law, obstacle_slip=w, **kw)
    assert plain.converged and pred.converged, (plain.reason, pred.reason)
    assert plain.iterations[0] > 15
    assert pred.iterations[0] <= 4 and pred.steps[0].predictor_used
    assert np.abs(plain.U - pred.U).max() <= 1e-9 * np.abs(pred.U).max()
    assert np.array_equal(plain.state, pred.state)
    assert (pred.state == STICK).sum() >= 12                  # mostly sticking
    r = _independent_residual(body, pred.U, law, w, kw.get("F"), eps, eps)
    assert np.abs(r).max() <= 1e-7 * np.abs(body.S_hat @ pred.U).max()


def test_settings_are_a_frozen_validated_object(body):
    """solve_friction takes a FrictionSettings (not loose keywords); the settings are
    validated when created and cannot be changed afterwards."""
    st = FrictionSettings(EPS_N, EPS_T, "Coulomb", mu_f=MU)
    assert st.friction == "coulomb" and st.bound == {"mu_f": MU}
    with pytest.raises(AttributeError):
        st.max_iter = 3
    with pytest.raises(TypeError, match="settings"):
        solve_friction(body, -D, dict(eps_n=EPS_N, eps_t=EPS_T, friction="coulomb",
                                      mu_f=MU))


@pytest.mark.parametrize("law", ["coulomb", "tresca"])
def test_trial_traction_on_the_bound_after_a_committed_slip_slips(law):
    """The start of a load step: a point that slipped has its slip committed
    (updated_slip), so its trial traction lies on the bound to rounding; the law calls
    it slipping in every case, not as the rounding falls (which decided the Newton path:
    constitutive.laws module doc)."""
    from hpfebe.constitutive.laws import penalty_friction, updated_slip

    rng = np.random.default_rng(3)
    n, eps_n, eps_t = 2000, 1.0 / 2.7e6, 1.0 / 1.3e6
    pen = rng.uniform(1e-7, 1e-4, n)
    g_t = rng.uniform(-1e-2, 1e-2, n) * 10.0 ** rng.uniform(-3, 0, n)
    kw = dict(mu_f=0.3) if law == "coulomb" else dict(F=rng.uniform(1.0, 50.0, n))
    # a slipping state: an old slip far from g_t
    first = penalty_friction(pen, g_t, g_t - np.sign(g_t) * 1e-3, eps_n, eps_t, **kw)
    assert np.all(first.state == SLIP)
    slip = updated_slip(g_t, first, eps_t)
    again = penalty_friction(pen, g_t, slip, eps_n, eps_t, **kw)
    assert np.all(again.state == SLIP)
    np.testing.assert_allclose(again.t_t, first.t_t, rtol=1e-9)
    # inside the bound by more than the rounding: stick, as before
    inside = penalty_friction(pen, g_t, g_t - 0.99 * eps_t * first.t_t, eps_n, eps_t, **kw)
    assert np.all(inside.state == STICK)
