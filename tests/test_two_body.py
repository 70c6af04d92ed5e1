"""Tests of two elastic FE bodies in frictional penalty contact on non-matching meshes
(hpfebe.contact.two_body, Chapter 4, Section 4.2; FE part hpfebe.fem.elasticity).

Scene: master (lower) block [0, 2] x [-1, 0] with 5 cells across, slave (upper) block
[0, 2] x [0, 1] with 4 cells across (non-matching interface y = 0), E = 266926, nu = 0.29,
plane strain unless stated.  Master normal n_m = (0, 1), tangent t_m = (1, 0).

Why the tolerances are tight: in the patch and uniform-shear tests the exact solution is
a uniform stress state, i.e. linear displacements in each body (plus a constant penalty
offset eps * traction across the interface).  P1/Q1 reproduce linear fields, the
segment-split contact quadrature integrates the (piecewise linear) traces exactly and
the penalty law is exact for a constant gap, so the discrete solution equals the exact
one up to rounding (measured ~1e-14); 1e-9 leaves room for conditioning
(1/eps = 1e6 against E / h ~ 1e6).
"""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe.contact.two_body import OPEN, SLIP, STICK, TwoBodyContact, project_onto_polyline
from hpfebe.fem.elasticity import ElasticBody, rectangle_mesh

E, NU = 266926.0, 0.29
Q = 100.0          # applied pressure
MU = 0.3
EPS = 1e-6
TOL = 1e-9


def blocks(kind="quad", plane="strain", mu_f=0.0, split=True, nx=(4, 5)):
    upper = ElasticBody(rectangle_mesh(0, 2, 0, 1, nx[0], 3, kind), E, NU, plane)
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, nx[1], 3, kind), E, NU, plane)
    return TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS, eps_t=EPS, mu_f=mu_f,
                          split=split)


def uniaxial_strains(plane):
    """(eps_xx, eps_yy) of sigma = diag(0, -Q)."""
    if plane == "strain":
        return Q * NU * (1 + NU) / E, -Q * (1 - NU ** 2) / E
    return Q * NU / E, -Q / E


def patch_solve(pr):
    f = pr.traction_load("slave", "top", (0.0, -Q))
    fixed = np.concatenate([pr.dofs_on("master", "bottom", 1), pr.dofs_at("master", (0, -1), 0),
                            pr.dofs_at("slave", (0, 1), 0)])
    return pr.solve(f, fixed, None, load_factors=[0.5, 1.0])


# ---------------------------------------------------------------- patch test
@pytest.mark.parametrize("kind,plane", [("quad", "strain"), ("tri", "strain"), ("quad", "stress")])
def test_contact_patch_test(kind, plane):
    pr = blocks(kind, plane)
    res = patch_solve(pr)
    assert res.converged, res.reason
    assert np.all(res.state != OPEN)
    # uniform pressure = applied pressure
    assert np.max(np.abs(res.p_n / Q - 1)) < TOL
    # total contact force = applied force
    assert abs(np.sum(res.weights * res.p_n) / (2 * Q) - 1) < TOL
    # exact uniaxial displacements, slave shifted by the penalty penetration eps_n * Q
    exx, eyy = uniaxial_strains(plane)
    for body, shift in (("master", eyy), ("slave", eyy - EPS * Q)):
        b = pr._body(body)
        u = b.nodal_displacement(res.u_slave if body == "slave" else res.u_master)
        x, y = b.mesh.p
        ux = exx * x
        uy = eyy * (y + 1) if body == "master" else eyy * y + shift
        scale = max(np.abs(ux).max(), np.abs(uy).max())
        assert np.max(np.abs(u[0] - ux)) < TOL * scale
        assert np.max(np.abs(u[1] - uy)) < TOL * scale


def test_patch_test_needs_segment_split():
    """Plain Gauss-point-to-segment integration (no split at master vertices) fails the
    patch test at the percent level: the split is what makes it exact."""
    res = patch_solve(blocks(split=False))
    assert res.converged
    assert np.max(np.abs(res.p_n / Q - 1)) > 1e-2


def test_partial_lift_off_equilibrium():
    """Frictionless, load Q on the left quarter x < 0.5 of the slave's top only: the
    right part of the interface opens.  Open points carry nothing and have g_n > 0,
    active ones p_n > 0; the contact forces balance the applied force and moment
    exactly (rigid motions of the slave against its equation; the one horizontal
    support carries no moment-producing reaction since all forces are vertical)."""
    pr = blocks("quad", nx=(8, 10))
    f = pr.traction_load("slave", "top", lambda x, y: (0 * x, -Q * (x < 0.5)))
    fixed = np.concatenate([pr.dofs_on("master", "bottom", 1), pr.dofs_at("master", (0, -1), 0),
                            pr.dofs_at("slave", (0, 1), 0)])
    res = pr.solve(f, fixed, None, load_factors=[0.5, 1.0])
    assert res.converged, res.reason
    open_, act = res.state == OPEN, res.state == SLIP      # frictionless: active = slip
    assert open_.sum() >= 5 and act.sum() >= 5 and np.all(open_ | act)
    assert np.all(res.g_n[open_] > 0) and np.all(res.p_n[open_] == 0)
    assert np.all(res.p_n[act] > 0)
    force = np.sum(res.weights * res.p_n)
    moment = np.sum(res.weights * res.p_n * res.points[:, 0])
    assert abs(force / (0.5 * Q) - 1) < 1e-10
    assert abs(moment / (0.5 * Q * 0.25) - 1) < 1e-10


# ---------------------------------------------------------------- friction, uniform shear
def shear_loads(pr, tau, top_traction):
    """Tractions of the uniform state sigma = [[0, tau], [tau, -Q]] on the sides of both
    bodies, the top of the slave (``top_traction``) and (x part) the master bottom."""
    f = np.zeros(pr.ndofs)
    for body in ("slave", "master"):
        f += pr.traction_load(body, "left", (0.0, -tau)) + pr.traction_load(body, "right", (0.0, tau))
    f += pr.traction_load("master", "bottom", (-tau, 0.0))
    f += pr.traction_load("slave", "top", top_traction)
    return f


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_stick_below_coulomb_bound(kind):
    """tau = 0.5 mu Q applied on the slave's top: every point sticks and transmits the
    traction exactly, t_t = tau < mu p_n; relative slip = eps_t tau."""
    pr = blocks(kind, mu_f=MU)
    tau = 0.5 * MU * Q
    fixed = np.concatenate([pr.dofs_on("master", "bottom", 1), pr.dofs_at("master", (0, -1), 0)])
    res = pr.solve(shear_loads(pr, tau, (tau, -Q)), fixed, None, load_factors=[0.25, 0.5, 0.75, 1.0])
    assert res.converged, res.reason
    assert np.all(res.state == STICK)
    assert np.max(np.abs(res.p_n / Q - 1)) < TOL
    assert np.max(np.abs(res.t_t / tau - 1)) < TOL
    assert np.all(np.abs(res.t_t) < MU * res.p_n)
    assert np.max(np.abs(res.g_t / (EPS * tau) - 1)) < 1e-6
    assert np.max(np.abs(res.slip)) < 1e-9 * EPS * tau


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_slip_at_coulomb_bound(kind):
    """The slave's top is dragged by c (u_x = eps_xx x + c) under pressure Q: every point
    slips with t_t = mu_f p_n = mu Q exactly; the accumulated slip is the relative
    tangential displacement minus the elastic part eps_t t_t."""
    pr = blocks(kind, mu_f=MU)
    tau, c = MU * Q, 2e-3
    exx, _ = uniaxial_strains("strain")
    top = pr.dofs_on("slave", "top", 0)
    base = np.concatenate([pr.dofs_on("master", "bottom", 1), pr.dofs_at("master", (0, -1), 0)])
    fixed = np.concatenate([base, top])
    vals = np.concatenate([np.zeros(base.size), exx * pr.dof_coordinates()[top, 0] + c])
    res = pr.solve(shear_loads(pr, tau, (0.0, -Q)), fixed, vals, load_factors=[0.25, 0.5, 0.75, 1.0])
    assert res.converged, res.reason
    assert np.all(res.state == SLIP)
    assert np.max(np.abs(res.p_n / Q - 1)) < TOL
    assert np.max(np.abs(res.t_t / (MU * res.p_n) - 1)) < TOL
    assert np.allclose(res.slip, res.g_t - EPS * res.t_t, rtol=0, atol=1e-12 * c)
    # relative slide: c minus the shear gamma = tau / G of each unit-height body
    gamma = tau / pr.slave.mu
    assert np.max(np.abs(res.g_t / (c - 2 * gamma) - 1)) < TOL


# ---------------------------------------------------------------- Newton
def punch():
    """Slave punch [0.5, 1.5] x [0, 1] (7 x 7 quads) on a master block (10 x 5 x 2
    triangles), top of the punch pressed down by d, then dragged by s; master bottom
    clamped.  Stick everywhere at first, a stick-slip front, then full slip."""
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, 10, 5, "tri"), E, NU)
    upper = ElasticBody(rectangle_mesh(0.5, 1.5, 0, 1, 7, 7, "quad"), E, NU)
    pr = TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS, eps_t=EPS, mu_f=MU)
    d, s = 1e-3, 1.5e-3
    tx, ty = pr.dofs_on("slave", "top", 0), pr.dofs_on("slave", "top", 1)
    clamp = pr.dofs_on("master", "bottom")
    fixed = np.concatenate([clamp, tx, ty])

    def values(lam):  # press (0 < lam <= 1), then shear (1 < lam <= 2)
        return np.concatenate([np.zeros(clamp.size), np.full(tx.size, s * max(lam - 1, 0)),
                               np.full(ty.size, -d * min(lam, 1))])

    return pr, fixed, values


def quadratic_last_step(residuals, C=1.0):
    r = np.asarray(residuals) / residuals[0]
    return len(r) >= 3 and r[-1] <= C * r[-2] ** 2


def test_newton_converges_quadratically_with_stick_slip():
    pr, fixed, values = punch()
    res = pr.solve(None, fixed, values, load_factors=np.linspace(0.25, 2.0, 8))
    assert res.converged, res.reason
    assert all(st.converged for st in res.steps)
    assert max(res.iterations) <= 4
    # the shear phase goes through mixed stick/slip into full slip
    assert any(st.n_stick > 0 and st.n_slip > 0 for st in res.steps)
    assert np.all(res.state == SLIP)
    assert np.max(np.abs(np.abs(res.t_t) - MU * res.p_n)) <= 1e-9 * MU * res.p_n.max()
    # every step that needs more than one Newton iteration ends quadratically
    multi = [st.residuals for st in res.steps if st.iterations >= 2]
    assert multi
    assert all(quadratic_last_step(r) for r in multi)
    for st in res.steps:
        assert st.residuals[-1] <= 1e-10 * st.residuals[0]


def test_inconsistent_tangent_is_detected_by_the_newton_test():
    """Negative control: without the slip coupling d t_t / d g_n (Section 4.2.5) Newton
    loses its quadratic convergence on the same problem and the test above would fail."""

    class NoCoupling(TwoBodyContact):
        def tangent(self, cs):
            cs = dict(cs, ktn=np.zeros_like(cs["ktn"]))
            return super().tangent(cs)

    pr, fixed, values = punch()
    pr.__class__ = NoCoupling
    res = pr.solve(None, fixed, values, load_factors=np.linspace(0.25, 2.0, 8), max_iter=60)
    multi = [st.residuals for st in res.steps if st.iterations >= 2]
    # measured: 9 and 10 iterations in the shear steps, linear rate ~0.1
    assert (not res.converged) or (max(res.iterations) > 4 and not all(
        quadratic_last_step(r) for r in multi))


def test_tangent_matches_finite_differences():
    """The Newton matrix is the derivative of the internal force (mixed stick/slip/open
    state with a nonzero slip history), checked by central differences."""
    pr, fixed, values = punch()
    rng = np.random.default_rng(1)
    res = pr.solve(None, fixed, values, load_factors=[0.5, 1.0, 1.5])
    U = res.U + 2e-5 * rng.standard_normal(pr.ndofs)
    slip = res.slip
    f0, cs = pr.internal_force(U, slip)
    states = set(np.unique(cs["state"]))
    assert {STICK, SLIP} <= states
    A = pr.tangent(cs)
    h = 1e-10
    for _ in range(3):
        v = rng.standard_normal(pr.ndofs)
        fp, csp = pr.internal_force(U + h * v, slip)
        fm, csm = pr.internal_force(U - h * v, slip)
        assert np.array_equal(csp["state"], cs["state"]) and np.array_equal(csm["state"], cs["state"])
        fd = (fp - fm) / (2 * h)
        assert np.linalg.norm(fd - A @ v) <= 1e-6 * np.linalg.norm(A @ v)


# ---------------------------------------------------------------- failures and projection
def test_failure_is_reported_not_silent():
    pr, fixed, values = punch()
    res = pr.solve(None, fixed, values, load_factors=[1.0, 2.0], max_iter=1)
    assert not res.converged and "max_iter" in res.reason
    assert not res.steps[-1].converged
    # a floating slave that does not touch the master: singular Newton matrix
    upper = ElasticBody(rectangle_mesh(0, 2, 0.01, 1, 4, 3), E, NU)
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, 5, 3), E, NU)
    pr = TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS)
    fixed = np.concatenate([pr.dofs_on("master", "bottom", 1), pr.dofs_at("master", (0, -1), 0),
                            pr.dofs_at("slave", (0, 1), 0)])
    res = pr.solve(pr.traction_load("slave", "top", (0.0, -Q)), fixed)
    assert not res.converged and "singular" in res.reason


def test_projection_corners_and_ends():
    # master polyline (0,0) -> (1,0) -> (2,1): a corner at (1,0)
    a = np.array([[0.0, 0.0], [1.0, 0.0]])
    b = np.array([[1.0, 0.0], [2.0, 1.0]])
    pts = np.array([[0.5, 0.3], [1.5, 0.2], [1.0, 0.0], [1.2, -0.5], [-0.5, 0.1]])
    seg, s, excess, dist = project_onto_polyline(pts, a, b)
    assert seg[0] == 0 and np.isclose(s[0], 0.5) and excess[0] == 0
    assert seg[1] == 1 and excess[1] == 0 and np.isclose(dist[1], 0.3 / np.sqrt(2))
    # exactly on the corner vertex: distance 0, a segment with zero excess
    assert dist[2] == 0 and excess[2] == 0
    # in the exterior cone of the corner: both segments end at the vertex (equal
    # distance), the one with the smaller excess (segment 1: 0.15 < 0.2) wins
    assert seg[3] == 1 and s[3] == 0 and np.isclose(excess[3], 0.15)
    # beyond the start of the polyline: clipped with an excess (flagged outside)
    assert seg[4] == 0 and s[4] == 0 and np.isclose(excess[4], 0.5)


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("kw,name", [
    (dict(eps_n=0.0), "eps_n"), (dict(eps_n=-1.0), "eps_n"), (dict(eps_t=0.0), "eps_t"),
    (dict(mu_f=-0.1), "mu_f"), (dict(mu_f=np.nan), "mu_f"), (dict(nq=0), "nq"),
])
def test_bad_contact_parameters(kw, name):
    upper = ElasticBody(rectangle_mesh(0, 2, 0, 1, 2, 1), E, NU)
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, 3, 1), E, NU)
    args = dict(eps_n=EPS, eps_t=EPS, mu_f=MU)
    args.update(kw)
    with pytest.raises(ValueError, match=name):
        TwoBodyContact(upper, lower, "bottom", "top", **args)


def test_bad_input_elsewhere():
    with pytest.raises(ValueError, match="nu"):
        ElasticBody(rectangle_mesh(0, 1, 0, 1, 1, 1), E, 0.5)
    with pytest.raises(ValueError, match="E"):
        ElasticBody(rectangle_mesh(0, 1, 0, 1, 1, 1), -1.0, NU)
    with pytest.raises(ValueError, match="kind"):
        rectangle_mesh(0, 1, 0, 1, 1, 1, "hex")
    with pytest.raises(ValueError, match="nx"):
        rectangle_mesh(0, 1, 0, 1, 0, 1)
    upper = ElasticBody(rectangle_mesh(0, 2, 0, 1, 2, 1), E, NU)
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, 3, 1), E, NU)
    with pytest.raises(ValueError, match="boundary label"):
        TwoBodyContact(upper, lower, "bottm", "top", eps_n=EPS)
    pr = TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS)
    with pytest.raises(ValueError, match="max_iter"):
        pr.solve(max_iter=0)
    with pytest.raises(ValueError, match="load_factors"):
        pr.solve(load_factors=[])
    with pytest.raises(ValueError, match="fixed_dofs"):
        pr.solve(fixed_dofs=[pr.ndofs])
    with pytest.raises(ValueError, match="f_ext"):
        pr.solve(f_ext=np.zeros(3))
    with pytest.raises(ValueError, match="body"):
        pr.dofs_on("third", "top")


def test_figure_4_13_setup_smoke():
    """The scene of Figures 4.13-4.16 (uniform mesh only, no adaptivity): slave
    [-1/2, 1/2] x [0, 2] (top fixed), master [-2, 2] x [-2, 0] (bottom lifted by 5e-4),
    mu_f = 0.1, all other sides possible contact (the slave's sides stay open).  Measured:
    3 Newton iterations per load step, a sticking centre and slipping edges; the contact
    force equals the reaction at the slave's top."""
    slave = ElasticBody(rectangle_mesh(-0.5, 0.5, 0, 2, 4, 8), E, NU)
    master = ElasticBody(rectangle_mesh(-2, 2, -2, 0, 16, 8), E, NU)
    h = 0.25
    pr = TwoBodyContact(slave, master, ["bottom", "left", "right"], ["top", "left", "right"],
                        eps_n=1e-5 * h, eps_t=1e-5 * h, mu_f=0.1)
    top = pr.dofs_on("slave", "top")
    bx, by = pr.dofs_on("master", "bottom", 0), pr.dofs_on("master", "bottom", 1)
    fixed = np.concatenate([top, bx, by])
    vals = np.concatenate([np.zeros(top.size + bx.size), np.full(by.size, 5e-4)])
    res = pr.solve(None, fixed, vals, load_factors=np.linspace(0.2, 1.0, 5))
    assert res.converged, res.reason
    assert max(res.iterations) <= 4
    last = res.steps[-1]
    assert last.n_stick > 0 and last.n_slip > 0 and last.n_open > 0
    # slave side points (x = +-1/2, y > 0) are open
    side = np.abs(np.abs(res.points[:, 0]) - 0.5) < 1e-12
    assert np.all(res.state[side] == OPEN)
    # vertical equilibrium of the slave: reaction at its top = contact force
    fint, _ = pr.internal_force(res.U, res.slip)
    ty = pr.dofs_on("slave", "top", 1)
    force = np.sum(res.weights * (res.p_n * pr.normals[:, 1] - res.t_t * pr.tangents[:, 1]))
    assert force > 0
    assert abs(np.sum(fint[ty]) + force) <= 1e-9 * force
    assert np.all(np.abs(res.t_t) <= 0.1 * res.p_n * (1 + 1e-12))
