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

import dataclasses

import numpy as np
import pytest

from hpfebe.constitutive import OPEN, SLIP, STICK
from hpfebe.contact import ContactSettings, TwoBodyContact
from hpfebe.contact.points import project_onto_polyline
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


def supports(pr, slave_x=True):
    """The supports of the two-block scenes: the master's bottom in y, its corner
    (0, -1) in x and, with ``slave_x``, the slave's corner (0, 1) in x (the rigid
    sliding of a slave without friction or tangential load)."""
    dofs = [pr.dofs_on("master", "bottom", 1), pr.dofs_at("master", (0, -1), 0)]
    if slave_x:
        dofs.append(pr.dofs_at("slave", (0, 1), 0))
    return np.concatenate(dofs)


def patch_solve(pr, check=True):
    """The patch test: pressure Q on the slave's top, two load steps; ``check``: the
    contact is closed everywhere and carries Q exactly (pointwise and in total)."""
    f = pr.traction_load("slave", "top", (0.0, -Q))
    res = pr.solve(f, supports(pr), None, load_factors=[0.5, 1.0])
    if check:
        assert res.converged, res.reason
        assert np.all(res.state != OPEN)
        assert np.max(np.abs(res.p_n / Q - 1)) < TOL              # uniform pressure Q
        assert abs(np.sum(res.weights * res.p_n) / (2 * Q) - 1) < TOL   # total force
    return res


# ---------------------------------------------------------------- patch test
@pytest.mark.parametrize("kind,plane", [("quad", "strain"), ("tri", "strain"), ("quad", "stress")])
def test_contact_patch_test(kind, plane):
    pr = blocks(kind, plane)
    res = patch_solve(pr)
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
    res = patch_solve(blocks(split=False), check=False)
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
    res = pr.solve(f, supports(pr), None, load_factors=[0.5, 1.0])
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


def check_stick(pr, load_factors):
    """tau = 0.5 mu Q applied on the slave's top: every point sticks and transmits the
    traction exactly, t_t = tau < mu p_n; relative slip = eps_t tau, no slip committed."""
    tau = 0.5 * MU * Q
    res = pr.solve(shear_loads(pr, tau, (tau, -Q)), supports(pr, slave_x=False), None,
                   load_factors=load_factors)
    assert res.converged, res.reason
    assert np.all(res.state == STICK)
    assert np.max(np.abs(res.p_n / Q - 1)) < TOL
    assert np.max(np.abs(res.t_t / tau - 1)) < TOL
    assert np.all(np.abs(res.t_t) < MU * res.p_n)
    assert np.max(np.abs(res.g_t / (EPS * tau) - 1)) < 1e-6
    assert np.max(np.abs(res.slip)) < 1e-9 * EPS * tau


def check_slip(pr, load_factors):
    """The slave's top is dragged by c (u_x = eps_xx x + c) under pressure Q: every point
    slips with t_t = mu_f p_n = mu Q exactly; the accumulated slip is the relative
    tangential displacement minus the elastic part eps_t t_t."""
    tau, c = MU * Q, 2e-3
    exx, _ = uniaxial_strains("strain")
    top = pr.dofs_on("slave", "top", 0)
    base = supports(pr, slave_x=False)
    fixed = np.concatenate([base, top])
    vals = np.concatenate([np.zeros(base.size), exx * pr.dof_coordinates()[top, 0] + c])
    res = pr.solve(shear_loads(pr, tau, (0.0, -Q)), fixed, vals, load_factors=load_factors)
    assert res.converged, res.reason
    assert np.all(res.state == SLIP)
    assert np.max(np.abs(res.p_n / Q - 1)) < TOL
    assert np.max(np.abs(res.t_t / (MU * res.p_n) - 1)) < TOL
    assert np.allclose(res.slip, res.g_t - EPS * res.t_t, rtol=0, atol=1e-12 * c)
    # relative slide: c minus the shear gamma = tau / G of each unit-height body
    gamma = tau / (E / (2 * (1 + NU)))
    assert np.max(np.abs(res.g_t / (c - 2 * gamma) - 1)) < TOL


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_stick_below_coulomb_bound(kind):
    check_stick(blocks(kind, mu_f=MU), [0.25, 0.5, 0.75, 1.0])


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_slip_at_coulomb_bound(kind):
    check_slip(blocks(kind, mu_f=MU), [0.25, 0.5, 0.75, 1.0])


# ---------------------------------------------------------------- Newton
def punch():
    """Slave punch [0.5, 1.5] x [0, 1] (7 x 7 quads) on a master block (10 x 5 x 2
    triangles), top of the punch pressed down by d, then dragged by s; master bottom
    clamped.  Stick everywhere at first, a stick-slip front, then full slip."""
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, 10, 5, "tri"), E, NU)
    upper = ElasticBody(rectangle_mesh(0.5, 1.5, 0, 1, 7, 7, "quad"), E, NU)
    return press_and_drag(TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS,
                                         eps_t=EPS, mu_f=MU))


def press_and_drag(pr, d=1e-3, s=1.5e-3):
    """(pr, fixed, values) of the punch scenes: the master's bottom clamped, the top of
    the slave punch pressed down by d (0 < lam <= 1), then dragged by s (1 < lam <= 2)."""
    tx, ty = pr.dofs_on("slave", "top", 0), pr.dofs_on("slave", "top", 1)
    clamp = pr.dofs_on("master", "bottom")
    fixed = np.concatenate([clamp, tx, ty])

    def values(lam):
        return np.concatenate([np.zeros(clamp.size), np.full(tx.size, s * max(lam - 1, 0)),
                               np.full(ty.size, -d * min(lam, 1))])

    return pr, fixed, values


def quadratic_last_step(residuals, C=1.0):
    r = np.asarray(residuals) / residuals[0]
    return len(r) >= 3 and r[-1] <= C * r[-2] ** 2


def check_quadratic_press_and_drag(pr, fixed, values, last=1e-10):
    """The punch pressed and dragged (8 load steps): at most 4 Newton iterations a step;
    the shear phase goes through mixed stick/slip into full slip at the Coulomb bound;
    every step that needs more than one iteration ends quadratically, at a residual
    below ``last`` times its first."""
    res = pr.solve(None, fixed, values, load_factors=np.linspace(0.25, 2.0, 8))
    assert res.converged, res.reason
    assert all(st.converged for st in res.steps)
    assert max(res.iterations) <= 4
    assert any(st.counts["stick"] > 0 and st.counts["slip"] > 0 for st in res.steps)
    assert np.all(res.state == SLIP)
    assert np.max(np.abs(np.abs(res.t_t) - MU * res.p_n)) <= 1e-9 * MU * res.p_n.max()
    multi = [st.residuals for st in res.steps if st.iterations >= 2]
    assert multi and all(quadratic_last_step(r) for r in multi)
    for st in res.steps:
        assert st.residuals[-1] <= last * st.residuals[0]


def test_newton_converges_quadratically_with_stick_slip():
    check_quadratic_press_and_drag(*punch())


def test_inconsistent_tangent_is_detected_by_the_newton_test():
    """Negative control: without the slip coupling d t_t / d g_n (Section 4.2.5) Newton
    loses its quadratic convergence on the same problem and the test above would fail."""

    class NoCoupling(TwoBodyContact):
        def tangent(self, cs):
            law = cs["law"]
            cs = dict(cs, law=dataclasses.replace(law, dt_n=np.zeros_like(law.dt_n)))
            return super().tangent(cs)

    pr, fixed, values = punch()
    pr.__class__ = NoCoupling
    res = pr.solve(None, fixed, values, load_factors=np.linspace(0.25, 2.0, 8), settings=ContactSettings(max_iter=60))
    multi = [st.residuals for st in res.steps if st.iterations >= 2]
    # measured: 9 and 10 iterations in the shear steps, linear rate ~0.1
    assert (not res.converged) or (max(res.iterations) > 4 and not all(
        quadratic_last_step(r) for r in multi))


def check_tangent(pr, fixed, values, seed):
    """The Newton matrix is the derivative of the internal force (mixed stick/slip/open
    state with a nonzero slip history), checked by central differences."""
    rng = np.random.default_rng(seed)
    res = pr.solve(None, fixed, values, load_factors=[0.5, 1.0, 1.5])
    U = res.U + 2e-5 * rng.standard_normal(pr.ndofs)
    _, cs = pr.internal_force(U, res.slip)
    assert {STICK, SLIP} <= set(np.unique(cs["state"]))
    A = pr.tangent(cs)
    h = 1e-10
    for _ in range(3):
        v = rng.standard_normal(pr.ndofs)
        fp, csp = pr.internal_force(U + h * v, res.slip)
        fm, csm = pr.internal_force(U - h * v, res.slip)
        assert np.array_equal(csp["state"], cs["state"]) and np.array_equal(csm["state"], cs["state"])
        assert np.linalg.norm((fp - fm) / (2 * h) - A @ v) <= 1e-6 * np.linalg.norm(A @ v)


def test_tangent_matches_finite_differences():
    check_tangent(*punch(), seed=1)


# ---------------------------------------------------------------- failures and projection
def test_failure_is_reported_not_silent():
    pr, fixed, values = punch()
    res = pr.solve(None, fixed, values, load_factors=[1.0, 2.0], settings=ContactSettings(max_iter=1))
    assert not res.converged and "max_iter" in res.reason
    assert not res.steps[-1].converged
    # a floating slave that does not touch the master: singular Newton matrix
    upper = ElasticBody(rectangle_mesh(0, 2, 0.01, 1, 4, 3), E, NU)
    lower = ElasticBody(rectangle_mesh(0, 2, -1, 0, 5, 3), E, NU)
    pr = TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS)
    res = pr.solve(pr.traction_load("slave", "top", (0.0, -Q)), supports(pr))
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
        pr.solve(settings=ContactSettings(max_iter=0))
    with pytest.raises(ValueError, match="settings"):
        pr.solve(settings={"max_iter": 5})
    with pytest.raises(ValueError, match="load_factors"):
        pr.solve(load_factors=[])
    with pytest.raises(ValueError, match="fixed_dofs"):
        pr.solve(fixed_dofs=[pr.ndofs])
    with pytest.raises(ValueError, match="f_ext"):
        pr.solve(f_ext=np.zeros(3))
    with pytest.raises(ValueError, match="body"):
        pr.dofs_on("third", "top")


def figure_4_13_supports(pr, lift=5e-4):
    """(fixed, values) of the Figure 4.13 scenes: the slave's top fixed, the master's
    bottom lifted by ``lift``."""
    top = pr.dofs_on("slave", "top")
    bx, by = pr.dofs_on("master", "bottom", 0), pr.dofs_on("master", "bottom", 1)
    fixed = np.concatenate([top, bx, by])
    return fixed, np.concatenate([np.zeros(top.size + bx.size), np.full(by.size, lift)])


def check_figure_4_13(pr, res, tol=1e-9):
    """Coulomb's bound |t_t| <= 0.1 p_n, and the slave's vertical equilibrium: the
    reaction at its top equals the contact force (to ``tol`` relative)."""
    assert np.all(np.abs(res.t_t) <= 0.1 * res.p_n * (1 + 1e-12))
    fint, _ = pr.internal_force(res.U, res.slip)
    ty = pr.dofs_on("slave", "top", 1)
    force = np.sum(res.weights * (res.p_n * pr.normals[:, 1] - res.t_t * pr.tangents[:, 1]))
    assert force > 0 and abs(np.sum(fint[ty]) + force) <= tol * force


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
    fixed, vals = figure_4_13_supports(pr)
    res = pr.solve(None, fixed, vals, load_factors=np.linspace(0.2, 1.0, 5))
    assert res.converged, res.reason
    assert max(res.iterations) <= 4
    last = res.steps[-1]
    assert last.counts["stick"] > 0 and last.counts["slip"] > 0 and last.counts["open"] > 0
    # slave side points (x = +-1/2, y > 0) are open
    side = np.abs(np.abs(res.points[:, 0]) - 0.5) < 1e-12
    assert np.all(res.state[side] == OPEN)
    check_figure_4_13(pr, res)


# ================================================================ boundary element bodies
# A body may be a Galerkin BE body (hpfebe.bem.lame.LameBEM): its unknowns are the
# boundary displacement in V_hp^2, its stiffness the dense S_hat inside the sparse
# Newton matrix ((4.27) FE/BE, (4.33) BE/BE), its contact traces the GLL Lagrange basis.
# S_hat reproduces a uniform stress state exactly (linear displacement, piecewise
# constant traction in W_hp), so the tolerances of the FE tests apply unchanged
# (measured: pressure and displacement errors 1e-15..4e-15 for p = 1, 2).

from hpfebe.bem.lame import LameBEM  # noqa: E402
from hpfebe.bodies import BEBody, FEBody  # noqa: E402
from hpfebe.geometry import BoundaryMesh  # noqa: E402

SIDES = ["bottom", "right", "top", "left"]


def be_rect(x0, x1, y0, y1, n, p, plane="strain"):
    """BE body on the rectangle, sides labelled like rectangle_mesh; n elements per side."""
    mesh = BoundaryMesh.polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], n=n, labels=SIDES, p=p)
    return LameBEM(mesh, E, NU, plane)


def fe_rect(x0, x1, y0, y1, nx, ny, kind="quad"):
    return ElasticBody(rectangle_mesh(x0, x1, y0, y1, nx, ny, kind), E, NU)


def mixed_blocks(combo, p, mu_f=0.0):
    """Slave [0, 2] x [0, 1], master [0, 2] x [-1, 0]; BE bodies with 4 (slave) and 5
    (master) elements along the interface (non-matching), 2 on the short sides."""
    up = be_rect(0, 2, 0, 1, [4, 2, 4, 2], p) if combo[0] == "BE" else fe_rect(0, 2, 0, 1, 4, 3)
    lo = be_rect(0, 2, -1, 0, [5, 2, 5, 2], p) if combo[1] == "BE" else fe_rect(0, 2, -1, 0, 5, 3)
    return TwoBodyContact(up, lo, "bottom", "top", eps_n=EPS, eps_t=EPS, mu_f=mu_f)


def exact_uniaxial(pr, plane="strain"):
    """The exact global dof vector of the patch test (slave shifted by eps_n Q)."""
    exx, eyy = uniaxial_strains(plane)
    X = pr.dof_coordinates()
    u = np.zeros(pr.ndofs)
    for body, off in (("slave", 0), ("master", pr.offset)):
        ad = pr._contact_body(body)
        if isinstance(ad, FEBody):
            nd = ad.body.nodal_dofs + off
            dx, dy = nd[0], nd[1]
        else:
            dx = np.arange(off, off + ad.ndofs, 2)
            dy = dx + 1
        u[dx] = exx * X[dx, 0]
        u[dy] = eyy * X[dy, 1] + (eyy - EPS * Q if body == "slave" else eyy)
    return u


@pytest.mark.parametrize("combo,p", [(("BE", "FE"), 1), (("BE", "FE"), 2), (("FE", "BE"), 1),
                                     (("FE", "BE"), 2), (("BE", "BE"), 1), (("BE", "BE"), 2)])
def test_contact_patch_test_with_boundary_elements(combo, p):
    pr = mixed_blocks(combo, p)
    # one sparse matrix with the BE block inside; BE/BE stays dense
    assert isinstance(pr.K, np.ndarray if combo == ("BE", "BE") else type(pr.Gn))
    res = patch_solve(pr)
    uex = exact_uniaxial(pr)
    assert np.max(np.abs(res.U - uex)) < TOL * np.abs(uex).max()
    # the second load step (same active set) is solved by one Newton step to rounding
    assert res.steps[-1].iterations == 1 and res.steps[-1].residuals[-1] < 1e-12 * res.steps[-1].residuals[0]
    # contact traces evaluated through the adapter: slave above master by eps_n Q
    us = pr.displacement_at("slave", res.U, "bottom", [0.0, 0.3, 1.0])
    exx, eyy = uniaxial_strains("strain")
    assert np.allclose(us[:, 1], eyy - EPS * Q, rtol=0, atol=TOL * EPS * Q)
    # interior stress of a BE body from the Somigliana identity: sigma = diag(0, -Q)
    for body in ("slave", "master"):
        b = pr._body(body)
        if isinstance(b, LameBEM):
            u = res.U[pr.global_dofs(body, np.arange(2 * b.V_space.ndof))]
            y = 0.5 if body == "slave" else -0.5
            sig = b.stress([(1.0, y), (0.7, y)], u, b.Psi(u))
            assert np.allclose(sig, [[0, 0], [0, -Q]], rtol=0, atol=1e-6 * Q)


@pytest.mark.parametrize("combo", [("BE", "FE"), ("FE", "BE")])
def test_stick_below_coulomb_bound_fe_be(combo):
    check_stick(mixed_blocks(combo, 2, mu_f=MU), [0.5, 1.0])


@pytest.mark.parametrize("combo", [("BE", "FE"), ("FE", "BE"), ("BE", "BE")])
def test_slip_at_coulomb_bound_fe_be(combo):
    check_slip(mixed_blocks(combo, 1, mu_f=MU), [0.5, 1.0])


def be_punch(master="FE", p=2):
    """The punch scene of :func:`punch` with a BE slave punch (6 elements along the
    contact side, 4 on the others, degree p) on the FE master, or on a BE master."""
    lower = (ElasticBody(rectangle_mesh(0, 2, -1, 0, 10, 5, "tri"), E, NU) if master == "FE"
             else be_rect(0, 2, -1, 0, [10, 5, 10, 5], p))
    upper = be_rect(0.5, 1.5, 0, 1, [6, 4, 6, 4], p)
    return press_and_drag(TwoBodyContact(upper, lower, "bottom", "top", eps_n=EPS,
                                         eps_t=EPS, mu_f=MU))


@pytest.mark.parametrize("master", ["FE", "BE"])
def test_newton_converges_quadratically_be_punch(master):
    """BE punch pressed and dragged: stick, a stick-slip front, full slip.  Measured
    (FE master, p = 2): 1 iteration per pressing step (residual 1e2 -> 1e-13), 3 in the
    shear steps, e.g. 9.9e1, 1.4e0, 3.7e-1, 2.2e-13 (active/stick sets found, then the
    piecewise linear problem is solved exactly); BE master: 9.9e1, 4.2e-1, 1.7e-1, 1.6e-13."""
    check_quadratic_press_and_drag(*be_punch(master), last=1e-12)


def test_tangent_matches_finite_differences_be():
    """Consistent Newton matrix with a dense BE block (BE slave on a BE master)."""
    check_tangent(*be_punch("BE", p=2), seed=2)


def test_be_adapter_bad_input():
    up, lo = be_rect(0, 2, 0, 1, 2, 1), fe_rect(0, 2, -1, 0, 3, 1)
    with pytest.raises(ValueError, match="boundary label"):
        TwoBodyContact(up, lo, "botom", "top", eps_n=EPS)
    with pytest.raises(ValueError, match="slave"):
        TwoBodyContact(up.mesh, lo, "bottom", "top", eps_n=EPS)
    pr = TwoBodyContact(up, lo, "bottom", "top", eps_n=EPS)
    assert isinstance(pr.bodies["slave"], BEBody)
    with pytest.raises(ValueError, match="point"):
        pr.dofs_at("slave", (0.3, 0.3))
    with pytest.raises(ValueError, match="component"):
        pr.dofs_on("slave", "top", 2)
    with pytest.raises(ValueError, match="traction"):
        pr.traction_load("slave", "top", (1.0, 2.0, 3.0))


# ---------------------------------------------------------------- globalisation
def figure_4_13_coarse():
    """The Figure 4.13 scene on the initial mesh h = 1/2 (P1 triangles: slave 2 x 4 cells,
    master 8 x 4 cells), 1/eps_n = 10 E, 1/eps_t = 5 E, mu_f = 0.1."""
    slave = ElasticBody(rectangle_mesh(-0.5, 0.5, 0, 2, 2, 4, "tri"), E, NU)
    master = ElasticBody(rectangle_mesh(-2, 2, -2, 0, 8, 4, "tri"), E, NU)
    pr = TwoBodyContact(slave, master, ["bottom", "left", "right"], ["top", "left", "right"],
                        eps_n=1 / (10 * E), eps_t=1 / (5 * E), mu_f=0.1)
    fixed, vals = figure_4_13_supports(pr)
    return pr, fixed, vals


def test_line_search_breaks_the_two_state_newton_cycle():
    """Plain semismooth Newton cycles between two stick/slip states in the first load
    step (measured residuals 9.6e1, 7.4e-1, 1.0e0, 1.667, 1.656, 1.667, 1.656, ...);
    the cycle is detected without a line search too and reported as "cycling" at the
    repeated contact state (before, it ran to max_iter).  With the Armijo backtracking on ||R_free|| (the residual is piecewise linear in U,
    so along the Newton direction of the current piece it decreases like (1 - alpha)
    for small alpha: the search always succeeds and the residual decreases monotonically,
    which excludes the cycle) it converges: measured 7 iterations, step lengths
    1, 1/4, 1/8, 1, 1/8, 1/16, 1 and a last full step to 5.5e-14 in the first step,
    then 4, 2, 2, 2 iterations."""
    pr, fixed, vals = figure_4_13_coarse()
    lf = np.linspace(0.2, 1.0, 5)
    plain = pr.solve(None, fixed, vals, load_factors=lf, settings=ContactSettings(max_iter=20))
    assert not plain.converged and "cycling" in plain.reason
    r = np.asarray(plain.steps[0].residuals)
    assert r.size < 20 and r[-1] > 1e-3 * r[0]               # stopped at the cycle
    res = pr.solve(None, fixed, vals, load_factors=lf, settings=ContactSettings(max_iter=20, line_search=True))
    assert res.converged, res.reason
    assert max(res.iterations) <= 10
    first = res.steps[0]
    assert min(first.step_lengths) < 1                         # damping was needed
    assert first.step_lengths[-1] == 1.0                       # ... not at the end
    assert all(np.all(np.diff(st.residuals) < 0) for st in res.steps)   # monotone
    for st in res.steps:
        assert st.residuals[-1] <= 1e-10 * st.residuals[0]
    last = res.steps[-1]
    assert last.counts["stick"] > 0 and last.counts["slip"] > 0
    check_figure_4_13(pr, res)


def test_line_search_keeps_full_steps_when_they_decrease_the_residual():
    pr, fixed, values = punch()
    a = pr.solve(None, fixed, values, load_factors=np.linspace(0.25, 2.0, 8))
    b = pr.solve(None, fixed, values, load_factors=np.linspace(0.25, 2.0, 8), settings=ContactSettings(line_search=True))
    assert b.converged and b.iterations == a.iterations
    assert all(l == 1.0 for st in b.steps for l in st.step_lengths)
    assert np.allclose(a.U, b.U, rtol=0, atol=1e-12 * np.abs(a.U).max())
    with pytest.raises(ValueError, match="min_step"):
        pr.solve(None, fixed, values, settings=ContactSettings(min_step=0.0))


def test_fixed_values_named_when_wrong():
    pr, fixed, _ = punch()
    with pytest.raises(ValueError, match=r"fixed_values must be a scalar or have shape"):
        pr.solve(None, fixed, np.zeros(3))          # was numpy's broadcasting error
    with pytest.raises(ValueError, match="fixed_values must be finite"):
        pr.solve(None, fixed, np.full(fixed.size, np.nan))
    with pytest.raises(ValueError, match="fixed_values must be finite"):
        pr.solve(None, fixed, lambda lam: np.full(fixed.size, np.inf))


@pytest.mark.parametrize("combo", [("BE", "FE"), ("FE", "BE"), ("BE", "BE")])
def test_figure_4_13_coarse_with_boundary_elements(combo):
    """The h = 1/2 scene with BE bodies (p = 1, elements of length 1/2; FE bodies P1
    triangles).  Measured: plain Newton hits max_iter for BE/FE (load step 5) and FE/BE
    (step 2); with the line search all three converge in a few iterations per step
    (e.g. FE/BE step 1: 2.8e1, 7.7e-1, 4.9e-1, 3.1e-1, 2.0e-14), one slave point sticks
    at the centre (BE/BE: none), the bottom corners slip, the slave's sides stay open.
    How many moves with round-off: points at the Coulomb bound flip between stick and
    slip.  BE/FE with the quadrature operators plus a random 1e-15 relative perturbation
    of V, K, W (8 seeds): at most 2, 3, 4, 6, 3, 2, 2, 2 per step; the closed-form p = 1
    operators: 6 (one OpenBLAS thread) or 3 (two)."""
    h = 0.5
    s = (be_rect(-0.5, 0.5, 0, 2, [2, 4, 2, 4], 1) if combo[0] == "BE"
         else fe_rect(-0.5, 0.5, 0, 2, 2, 4, "tri"))
    m = (be_rect(-2, 2, -2, 0, [8, 4, 8, 4], 1) if combo[1] == "BE"
         else fe_rect(-2, 2, -2, 0, 8, 4, "tri"))
    assert np.isclose(2 / 4, h)
    pr = TwoBodyContact(s, m, ["bottom", "left", "right"], ["top", "left", "right"],
                        eps_n=1 / (10 * E), eps_t=1 / (5 * E), mu_f=0.1)
    fixed, vals = figure_4_13_supports(pr)
    lf = np.linspace(0.2, 1.0, 5)
    # whether plain Newton cycles on this scene depends on round-off (it converged with
    # numpy 2.4 / OpenBLAS here, on the old and the new code alike): not asserted
    res = pr.solve(None, fixed, vals, load_factors=lf, settings=ContactSettings(max_iter=30, line_search=True))
    assert res.converged, res.reason
    assert max(res.iterations) <= 6
    assert all(np.all(np.diff(st.residuals) < 0) for st in res.steps)
    assert all(st.residuals[-1] <= 1e-10 * st.residuals[0] for st in res.steps)
    side = np.abs(np.abs(res.points[:, 0]) - 0.5) < 1e-12
    assert np.all(res.state[side] == OPEN) and np.any(res.state == SLIP)
    check_figure_4_13(pr, res, tol=1e-8)


def test_plastic_tangent_is_lazy_and_lu_orderings_reuse():
    """A plastic body's tangent is assembled only when the Newton step asks for it;
    the reused column ordering of a sparsity pattern gives the factorisation SuperLU's
    default gives, bit for bit; lu_ordering="MMD_AT_PLUS_A" solves the same problem
    (other round-off)."""
    import scipy.sparse.linalg as spla
    from hpfebe.contact import loading
    from hpfebe.fem.plastic_body import ElastoPlasticFE
    from hpfebe.constitutive.j2 import J2Material

    def problem():
        stamp = ElasticBody(rectangle_mesh(-0.5, 0.5, 0, 1, 3, 3, "quad"), E, NU)
        work = ElastoPlasticFE(rectangle_mesh(-1, 1, -1, 0, 6, 3, "quad"),
                               J2Material(E, NU, 4.0, 450.0, 1.0))
        pr = TwoBodyContact(stamp, work, "bottom", "top", eps_n=1 / (10 * E),
                            eps_t=1 / (5 * E), mu_f=0.2)
        fixed = np.concatenate([pr.dofs_on("slave", "top"), pr.dofs_on("master", "bottom")])
        vals = np.where(np.isin(fixed, pr.dofs_on("master", "bottom", 1)), 2e-3, 0.0)
        return pr, fixed, vals

    pr, fixed, vals = problem()
    _, cs = pr.internal_force(np.zeros(pr.ndofs), np.zeros(len(pr.points)))
    assert "K_body" not in cs and cs["K_body"].shape == (pr.ndofs, pr.ndofs)
    res = pr.solve(None, fixed, vals, load_factors=[0.5, 1.0], settings=ContactSettings(rtol=1e-10, max_iter=40, line_search=True))
    assert res.converged, res.reason
    assert loading._ORDERS                              # orderings of the patterns seen
    steps = loading.LoadSteps(pr, None, fixed, vals, ContactSettings())
    A = pr.tangent(pr.internal_force(res.U, res.slip)[1])[steps.free][:, steps.free].tocsc()
    A.sort_indices()
    b = np.random.default_rng(0).standard_normal(A.shape[0])
    loading._ordered_splu(pr, A, "key")                  # a new pattern: COLAMD, kept
    lu = loading._ordered_splu(pr, A, "key")             # its ordering reused
    assert isinstance(lu, loading._PermutedLU)
    np.testing.assert_array_equal(lu.solve(b), spla.splu(A).solve(b))
    pr2, fixed, vals = problem()
    res2 = pr2.solve(None, fixed, vals, load_factors=[0.5, 1.0], settings=ContactSettings(rtol=1e-10, max_iter=40, line_search=True, lu_ordering="MMD_AT_PLUS_A"))
    assert res2.converged, res2.reason
    np.testing.assert_allclose(res2.U, res.U, atol=1e-8 * np.abs(res.U).max())
    with pytest.raises(ValueError, match="lu_ordering"):
        pr2.solve(None, fixed, vals, settings=ContactSettings(lu_ordering="AMD"))
