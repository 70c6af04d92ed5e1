"""The elastoplastic BE body (hpfebe.bodies.plastic_be, thesis Section 4.2.4, Algorithm 4.2):
the uniform initial-strain problem solved exactly, a homogeneous plastic state against the
material point, a punch with a plastic zone against the plastic FE body (B-bar Q1), the
step-size sensitivity of the forward Euler update, bad input."""

import numpy as np
import pytest

from hpfebe.bem.lame import LameBEM
from hpfebe.fem.elasticity import rectangle_mesh
from hpfebe.fem.newton_potential import CellComplex
from hpfebe.fem.plastic_body import DisplacementSteps, ElastoPlasticFE
from hpfebe.constitutive.j2 import J2Material, J2State, return_map, tensor_norm
from hpfebe.geometry import BoundaryMesh
from hpfebe.solvers import load_path
from hpfebe.bodies.plastic_be import DirichletSolver, ElastoPlasticBE, staggered_path

MAT = J2Material(1000.0, 0.3, 1.0, 200.0, 1.0)
N = 4


@pytest.fixture(scope="module")
def punch_bodies():
    """[-1, 1] x [0, 1], 2N x N quadrilaterals; the BE body's cells are the FE cells."""
    fem = rectangle_mesh(-1, 1, 0, 1, 2 * N, N, "quad")
    bm = BoundaryMesh.polygon([(-1, 0), (1, 0), (1, 1), (-1, 1)], n=[2 * N, N, 2 * N, N])
    be = ElastoPlasticBE(LameBEM(bm, MAT.E, MAT.nu), CellComplex(fem.p.T, fem.t.T), MAT)
    return fem, be


def fresh(be):
    """A copy of the BE body with a zero history (the operators are shared)."""
    b = ElastoPlasticBE.__new__(ElastoPlasticBE)
    b.__dict__.update(be.__dict__)
    b.committed = J2State.zeros(be.cells.ncells)
    return b


def rigid_free(X, d):
    R = np.zeros((d.size, 3))
    R[0::2, 0], R[1::2, 1], R[0::2, 2], R[1::2, 2] = 1, 1, -X[:, 1], X[:, 0]
    return d - R @ np.linalg.lstsq(R, d, rcond=None)[0]


@pytest.mark.parametrize("e33", [0.0, -0.5e-3])
def test_uniform_plastic_strain_traction_free_is_exact(punch_bodies, e33):
    """Uniform eps_p, traction-free: u = eps_hat x, in-plane stress 0 (eps_hat = eps_p in
    the plane, plus lam eps_p33 / (2 lam + 2 mu) 1 from the plane-strain constraint)."""
    _, be = punch_bodies
    be = fresh(be)
    a22 = -1e-3 - e33
    ep = np.array([[1e-3, 0.4e-3, 0], [0.4e-3, a22, 0], [0, 0, e33]])
    be.committed.eps_p[:] = ep
    lam, mu = MAT.lam, MAT.mu
    eh = ep[:2, :2] + lam * e33 / (2 * lam + 2 * mu) * np.eye(2)
    X = be.bem.mesh.nodes
    u_ex = (X @ eh.T).ravel()
    f = be.plastic_force()
    assert np.abs(be.S @ u_ex - f).max() < 1e-12 * np.abs(f).max()
    u = np.linalg.lstsq(be.S, f, rcond=None)[0]
    assert np.abs(rigid_free(X, u - u_ex)).max() < 1e-12 * np.abs(u_ex).max()
    eps = be.strain(u_ex)
    assert np.abs(eps[:, :2, :2] - eh).max() < 1e-8 * np.abs(eh).max()
    sig = be.update(u_ex).sigma
    assert np.abs(sig[:, :2, :2]).max() < 1e-8 * 2 * mu * 1e-3


def test_homogeneous_plastic_state_matches_material_point(punch_bodies):
    """u = eps_bar x on the whole boundary (Dirichlet): every cell follows the material
    point (return map), in 3 load steps with the iterated update."""
    _, be = punch_bodies
    be = fresh(be)
    eb = np.array([[2e-3, 1e-3], [1e-3, -1.5e-3]])
    X = be.bem.mesh.nodes
    sol = DirichletSolver(be, np.arange(be.ndofs), (X @ eb.T).ravel())
    lams = [0.4, 0.7, 1.0]
    _, infos = staggered_path(be, sol, lams, tol=1e-7, max_iter=50)
    assert all(i.converged for i in infos)
    st = J2State.zeros(1)
    for lam in lams:
        rm = return_map(MAT, (lam * eb)[None], st, None)
        st = rm.state
    assert rm.plastic[0] and be.plastic.all()
    np.testing.assert_allclose(be.committed.eps_p, np.broadcast_to(st.eps_p, be.committed.eps_p.shape),
                               atol=1e-6 * np.abs(st.eps_p).max())
    np.testing.assert_allclose(be.sigma, np.broadcast_to(rm.sigma, be.sigma.shape),
                               atol=1e-6 * np.abs(rm.sigma).max())


@pytest.mark.parametrize("theta", [1.0, 0.0])
def test_implicit_reversed_path_follows_material_point(punch_bodies, theta):
    """Isotropic (theta = 1) and kinematic (theta = 0) hardening, backward Euler cell
    strains (scheme "implicit"), u = lam eps_bar x on Gamma along a loading-reversal
    path: every cell follows the material point (return map), and the two hardening
    rules part on the reversal (Bauschinger effect)."""
    _, be = punch_bodies
    mat = J2Material(MAT.E, MAT.nu, MAT.sigma_Y, MAT.H, theta)
    be = fresh(be)
    be.material, be.scheme, be._icache, be._ilast = mat, "implicit", None, None
    eb = np.array([[2e-3, 1e-3], [1e-3, -1.5e-3]])
    X = be.bem.mesh.nodes
    st, other = J2State.zeros(1), J2State.zeros(1)
    mat_other = J2Material(MAT.E, MAT.nu, MAT.sigma_Y, MAT.H, 1.0 - theta)
    for lam in (0.5, 1.0, 0.0, -1.0):
        u = lam * (X @ eb.T).ravel()
        be.implicit_response(u)
        assert be.inner_info.converged
        be.commit(u)
        rm = return_map(mat, (lam * eb)[None], st, None)
        st = rm.state
        ro = return_map(mat_other, (lam * eb)[None], other, None)
        other = ro.state
        scale = np.abs(rm.sigma).max()
        np.testing.assert_allclose(be.sigma, np.broadcast_to(rm.sigma, be.sigma.shape),
                                   atol=1e-6 * scale)
        np.testing.assert_allclose(be.committed.beta,
                                   np.broadcast_to(st.beta, be.committed.beta.shape),
                                   atol=1e-6 * scale)
    assert rm.plastic[0]
    assert np.abs(rm.sigma - ro.sigma).max() > 1e-3 * scale     # the rules differ


def punch_fe(fem, depth, lams):
    R, fe = punch_fe_mat(fem, MAT, depth, lams)
    eps_p = fe.committed.eps_p.reshape(fe.nel, fe.nq, 3, 3).mean(axis=1)
    return R, tensor_norm(eps_p)


def punch_be(be, depth, lams, max_iter):
    X = be.bem.mesh.nodes
    bot = np.flatnonzero(np.abs(X[:, 1]) < 1e-12)
    top = np.flatnonzero((np.abs(X[:, 1] - 1) < 1e-12) & (np.abs(X[:, 0]) < 0.5 + 1e-9))
    fixed = np.concatenate([2 * bot, 2 * bot + 1, 2 * top + 1])
    vals = np.concatenate([np.zeros(2 * bot.size), -depth * np.ones(top.size)])
    be = fresh(be)
    u, infos = staggered_path(be, DirichletSolver(be, fixed, vals), lams, tol=1e-7,
                              max_iter=max_iter)
    assert all(i.converged for i in infos)
    R = (be.S @ u - be.plastic_force())[2 * top + 1].sum()
    return R, tensor_norm(be.committed.eps_p), infos


def test_punch_with_plastic_zone_matches_fe_body(punch_bodies):
    """Bottom fixed, the middle half of the top pushed down by 3e-3 (plastic zone under
    the punch): the BE body with the iterated Algorithm 4.2 against the B-bar Q1 body on
    the same cells.  Measured reaction differences BE vs FE for N = 4 / 8 / 12:
    3.7 / 2.0 / 1.5 % (elastic, depth 1e-4: 3.0 / 1.8 / 1.25 % - the discretisation
    error, shrinking alike); the same plastic cells at N = 4 (28) and 12 (232);
    ||eps_p|| relative l2 difference 10.5 / 10.7 / 9.2 %."""
    fem, be = punch_bodies
    lams = np.linspace(0.1, 1.0, 10)
    R_fe, ep_fe = punch_fe(fem, 3e-3, lams)
    R_be, ep_be, infos = punch_be(be, 3e-3, lams, 300)
    assert abs(R_be - R_fe) < 0.05 * abs(R_fe)
    assert np.array_equal(ep_be > 0, ep_fe > 0)
    assert np.linalg.norm(ep_be - ep_fe) < 0.15 * np.linalg.norm(ep_fe)
    assert max(i.iterations for i in infos) > 5         # plastic steps needed iterations


def test_forward_euler_step_size_sensitivity(punch_bodies):
    """The one-pass forward Euler update (thesis Algorithm 4.2 with eps_p lagged one
    step): its distance to the iterated (implicit) solution shrinks with the step size,
    like 1/steps (first order; measured 12.6 / 7.1 / 3.8 / 1.9 % in the reaction for
    5 / 10 / 20 / 40 steps at N = 4, the same at N = 8 and 12)."""
    _, be = punch_bodies
    R_impl, _, _ = punch_be(be, 3e-3, np.linspace(0.1, 1.0, 10), 300)
    errs = []
    for n in (5, 10, 20, 40):
        R, _, _ = punch_be(be, 3e-3, np.linspace(1.0 / n, 1.0, n), 1)
        errs.append(abs(R - R_impl) / abs(R_impl))
    assert all(e1 < e0 for e0, e1 in zip(errs, errs[1:]))
    assert errs[-1] < 0.35 * errs[1] and errs[-1] < 0.03


def test_bad_input(punch_bodies):
    fem, be = punch_bodies
    cx = be.cells
    with pytest.raises(ValueError, match="material"):
        ElastoPlasticBE(be.bem, cx, J2Material(2000.0, 0.3, 1.0, 1.0))
    with pytest.raises(ValueError, match="cells"):
        ElastoPlasticBE(be.bem, fem, MAT)
    with pytest.raises(ValueError, match="bem"):
        ElastoPlasticBE(be, cx, MAT)
    with pytest.raises(ValueError, match="u must"):
        be.strain(np.zeros(3))
    with pytest.raises(ValueError, match="fixed"):
        DirichletSolver(be, [], [])
    with pytest.raises(ValueError, match="factors"):
        staggered_path(be, DirichletSolver(be, [0, 1, 3], 0.0), [])


def test_implicit_scheme_tangent_and_solution(punch_bodies):
    """scheme="implicit" (beyond the thesis): the consistent tangent equals a finite
    difference of the force (measured 6.5e-10), Newton takes <= 3 iterations per load
    step and reaches the fixed point of the iterated Algorithm 4.2 (measured reaction
    -2.8680720 vs -2.8680720, 7e-9 relative)."""
    _, be0 = punch_bodies
    be = ElastoPlasticBE(be0.bem, be0.cells, MAT, scheme="implicit")
    X = be.bem.mesh.nodes
    bot = np.flatnonzero(np.abs(X[:, 1]) < 1e-12)
    top = np.flatnonzero((np.abs(X[:, 1] - 1) < 1e-12) & (np.abs(X[:, 0]) < 0.5 + 1e-9))
    fixed = np.concatenate([2 * bot, 2 * bot + 1, 2 * top + 1])
    vals = np.concatenate([np.zeros(2 * bot.size), -3e-3 * np.ones(top.size)])
    free = np.setdiff1d(np.arange(be.ndofs), fixed)
    u = np.zeros(be.ndofs)
    u[fixed] = 0.5 * vals
    u[free] = np.linalg.solve(be.S[np.ix_(free, free)], -be.S[np.ix_(free, fixed)] @ u[fixed])
    f, KT = be.internal_force(u)
    assert be.implicit_response(u)[1].plastic.sum() > 5
    d = np.random.default_rng(0).normal(size=be.ndofs) * 1e-8
    fd = 0.5 * (be.internal_force(u + d)[0] - be.internal_force(u - d)[0])
    assert np.abs(fd - KT @ d).max() < 1e-6 * np.abs(KT @ d).max()
    lams = np.linspace(0.1, 1.0, 10)
    it, info = load_path(DisplacementSteps(be, fixed, vals), lams, np.zeros(be.ndofs),
                         tol=1e-10, max_iter=30)
    assert info.converged and max(s.iterations for s in info.steps) <= 4
    R = be.internal_force(it.x)[0][2 * top + 1].sum()
    R_it, _, _ = punch_be(be0, 3e-3, lams, 300)
    assert abs(R - R_it) < 1e-6 * abs(R_it)


def test_contact_body_protocol(punch_bodies):
    """PlasticBEBody: kind "BE", internal_force = S_hat u - G(eps_p committed) with the
    dense S_hat (explicit), commit updates the plastic strain."""
    from hpfebe.bodies.plastic_be import PlasticBEBody
    _, be0 = punch_bodies
    body = PlasticBEBody(fresh(be0))
    assert body.kind == "BE" and not body.linear and body.ndofs == be0.ndofs
    X = be0.bem.mesh.nodes
    u = (X @ np.array([[3e-3, 0.0], [0.0, -3e-3]]).T).ravel()
    f, T = body.internal_force(u)
    assert isinstance(T, np.ndarray) and np.allclose(f, be0.S @ u)
    body.commit(u)
    assert body.plastic.plastic.all()
    f2, _ = body.internal_force(u)
    assert np.abs(f2 - f).max() > 1e-3 * np.abs(f).max()
    with pytest.raises(ValueError, match="be must"):
        PlasticBEBody(be0.bem)
    with pytest.raises(ValueError, match="scheme"):
        ElastoPlasticBE(be0.bem, be0.cells, MAT, scheme="euler")


def test_rectangle_work_piece_in_two_body_contact():
    """An elastic BE stamp pressed onto a BE work piece (Example 2 geometry, coarse,
    moderate hardening) with TwoBodyContact: converges, the plastic zone is under the
    stamp, the bottom reaction is in equilibrium with the contact force."""
    from hpfebe.contact import ContactSettings, TwoBodyContact
    from hpfebe.scenes import stamp_body
    from hpfebe.bodies.plastic_be import PlasticBEBody, rectangle_work_piece
    mat = J2Material(1000.0, 0.3, 1.0, 200.0, 1.0)
    be = rectangle_work_piece((-2, 2, -3, -1), 4, 2, mat)
    stamp = stamp_body("BE", (-1, 1, -1, 0), 1.0, mat.E, mat.nu)
    body = PlasticBEBody(be)
    pr = TwoBodyContact(stamp, body, "bottom", "top", eps_n=1 / (10 * mat.E),
                        eps_t=1 / (5 * mat.E), mu_f=0.2)
    fixed, is_y = pr.stamp_dofs()
    res = pr.solve(None, fixed, 4e-3 * is_y, load_factors=np.linspace(0.25, 1, 4), settings=ContactSettings(rtol=1e-8, max_iter=40, line_search=True))
    assert res.converged
    assert be.plastic.any()
    assert be.cells.centroids[be.plastic][:, 1].max() > -1.6     # near the contact
    with pytest.raises(ValueError, match="nx"):
        rectangle_work_piece((-2, 2, -3, -1), 0, 2, mat)


THESIS = J2Material(266926.0, 0.29, 4.0, 450.0, 1.0)


def _thesis_punch(N, cells):
    """Punch of test_punch_with_plastic_zone_matches_fe_body with the thesis material
    (E / sigma_Y = 66700, H = 450: near-perfect plasticity), depth 5e-4 (~30 yield
    strains), backward Euler BE body through nonlinear.load_path."""
    from hpfebe.bodies.plastic_be import crossed_cells
    fem = rectangle_mesh(-1, 1, 0, 1, 2 * N, N, "quad")
    cx = crossed_cells(fem.p.T, fem.t.T) if cells == "crossed" else CellComplex(fem.p.T, fem.t.T)
    bm = BoundaryMesh.polygon([(-1, 0), (1, 0), (1, 1), (-1, 1)], n=[2 * N, N, 2 * N, N])
    be = ElastoPlasticBE(LameBEM(bm, THESIS.E, THESIS.nu), cx, THESIS, scheme="implicit")
    X = bm.nodes
    bot = np.flatnonzero(np.abs(X[:, 1]) < 1e-12)
    top = np.flatnonzero((np.abs(X[:, 1] - 1) < 1e-12) & (np.abs(X[:, 0]) < 0.5 + 1e-9))
    fixed = np.concatenate([2 * bot, 2 * bot + 1, 2 * top + 1])
    vals = np.concatenate([np.zeros(2 * bot.size), -5e-4 * np.ones(top.size)])
    it, info = load_path(DisplacementSteps(be, fixed, vals), np.linspace(0.1, 1, 10),
                         np.zeros(be.ndofs), tol=1e-10, max_iter=30)
    assert info.converged, info.reason
    return be.internal_force(it.x)[0][2 * top + 1].sum(), be


def test_crossed_cells_do_not_lock_on_thesis_material():
    """Near-perfect plasticity: constant plastic strain on axis-parallel squares locks
    (compatible isochoric fields are grid-line shears only; the punch mechanism runs at
    45 degrees), four crossed triangles per square do not.  Measured (N = 2, 32 cells
    both): FE B-bar Q1 9.578, crossed triangles 9.792 (+2.2 %), squares of N = 4 14.71
    (+54 %); squares at N = 4 / 8 / 16 are 65 / 33 / 18 % too stiff (first order, the
    discretisation, not a bug)."""
    fem = rectangle_mesh(-1, 1, 0, 1, 4, 2, "quad")
    R_fe, _ = punch_fe_mat(fem, THESIS, 5e-4)
    R_x, be = _thesis_punch(2, "crossed")
    R_q, _ = _thesis_punch(4, "quad")
    assert abs(R_x - R_fe) < 0.05 * abs(R_fe)
    assert abs(R_q - R_fe) > 0.4 * abs(R_fe)
    assert be.inner_info.converged and be.plastic.sum() > 0


def punch_fe_mat(fem, mat, depth, lams=None):
    """The FE punch (B-bar Q1): bottom fixed, the top's |x| <= 1/2 pressed down by
    ``depth`` along ``lams`` (default ten equal steps); (reaction on the punch, the body)."""
    lams = np.linspace(0.1, 1, 10) if lams is None else lams
    fe = ElastoPlasticFE(fem, mat)
    b = fe.elastic
    xy = b.dof_coordinates()
    bottom = b.dofs_on("bottom")
    top = b.dofs_on("top", 1)
    top = top[np.abs(xy[top, 0]) < 0.5 + 1e-9]
    ds = DisplacementSteps(fe, np.concatenate([bottom, top]),
                           np.concatenate([np.zeros(bottom.size), -depth * np.ones(top.size)]))
    _, info = load_path(ds, lams, np.zeros(fe.ndofs), tol=1e-10, max_iter=40)
    assert info.converged
    return fe.committed_force()[top].sum(), fe


def test_node_displacements_and_cell_lookup():
    """Uniform eps_p, traction free: the representation formula gives u = eps_hat x at
    every cell node (interior ones included); cells_at / value_at find the cells."""
    from hpfebe.bodies.plastic_be import crossed_cells
    fem = rectangle_mesh(-1, 1, 0, 1, 4, 2, "quad")
    bm = BoundaryMesh.polygon([(-1, 0), (1, 0), (1, 1), (-1, 1)], n=[4, 2, 4, 2])
    be = ElastoPlasticBE(LameBEM(bm, MAT.E, MAT.nu), crossed_cells(fem.p.T, fem.t.T), MAT)
    ep = np.array([[1e-3, 0.4e-3, 0], [0.4e-3, -1e-3, 0], [0, 0, 0]])
    be.committed.eps_p[:] = ep
    u = (be.bem.mesh.nodes @ ep[:2, :2].T).ravel()
    ex = be.cells.nodes @ ep[:2, :2].T
    got = be.node_displacements(u)
    assert np.abs(got - ex).max() < 1e-8 * np.abs(ex).max()
    assert be.cells_at((0.1, 0.3)).size == 1 and be.cells_at((0.0, 0.5)).size == 8
    be.sigma[:] = 0.0
    assert be.value_at("eps_p_norm", (0.1, 0.3)) == pytest.approx(tensor_norm(ep[None])[0])
    with pytest.raises(ValueError, match="point"):
        be.cells_at((5.0, 5.0))
    with pytest.raises(ValueError, match="key"):
        be.value_at("nope", (0.1, 0.3))
    from hpfebe.bodies.plastic_be import rectangle_work_piece
    with pytest.raises(ValueError, match="cells"):
        rectangle_work_piece((-2, 2, -3, -1), 4, 2, MAT, cells="hex")
    with pytest.raises(ValueError, match="cell_rows"):
        rectangle_work_piece((-2, 2, -3, -1), 4, 2, MAT, cell_rows=3)


def test_times_blocks_is_the_batched_matmul():
    """A @ blockdiag(D) of the cell-strain Jacobian: the loop kernel agrees with
    np.matmul's small-matrix products to the rounding bound of a 3-term dot product,
    |fl(a.d) - a.d| <= gamma_3 |a|.|d| with gamma_3 = 3u / (1 - 3u), for each of the two
    (the difference of two such results is within twice the bound).  Bitwise equality is
    not asserted: np.matmul may use fused multiply-adds on one CPU and not on another."""
    from hpfebe.bodies.plastic_be import _times_blocks
    rng = np.random.default_rng(4)
    M = rng.standard_normal((90, 120))
    p3 = np.sort(rng.choice(120, 60, replace=False))
    D = rng.standard_normal((20, 3, 3))
    A = M[:, p3]
    blocks = lambda X, Y: np.matmul(np.ascontiguousarray(X).reshape(90, 20, 1, 3),
                                    Y[None]).reshape(90, 60)
    ref = blocks(A, D)
    u = np.finfo(float).eps / 2
    bound = 2 * 3 * u / (1 - 3 * u) * blocks(np.abs(A), np.abs(D))
    got = _times_blocks(A, D)             # a strided column selection goes in as it is
    assert np.all(np.abs(got - ref) <= bound)
    # and not a looser agreement: one block's product transposed is far outside it
    wrong = _times_blocks(A, np.swapaxes(D, 1, 2))
    assert not np.all(np.abs(wrong - ref) <= bound)

def test_plastic_blocks_are_the_copies_they_replace():
    """The fused kernel of the cell-strain Jacobian gives the numbers of the copies it
    replaced bit for bit: MD = M[:, p] blockdiag(D[pl]) (the 3-term sums of
    _times_blocks) and J = I - MD[p]; and the D blocks by indexing equal the einsum over
    the selectors bit for bit (it adds only exact zeros)."""
    from hpfebe.bodies.plastic_be import (_EPS_SEL, _TAU_SEL, _plastic_blocks,
                                          _tau_strain_blocks, _times_blocks)
    rng = np.random.default_rng(7)
    nc = 30
    M = rng.standard_normal((3 * nc, 3 * nc))
    D = rng.standard_normal((nc, 3, 3))
    pl = np.sort(rng.choice(nc, 17, replace=False))
    p3 = (3 * pl[:, None] + np.arange(3)).ravel()
    MD, J = _plastic_blocks(M, pl, D)
    ref = _times_blocks(M[:, p3], D[pl])
    assert np.array_equal(MD, ref)
    assert np.array_equal(J, np.eye(p3.size) - ref[p3])
    rows = np.setdiff1d(np.arange(3 * nc), p3)            # the elastic rows (a step)
    MDe, Je = _plastic_blocks(M, pl, D, rows)
    assert np.array_equal(MDe, ref[rows]) and np.array_equal(Je, J)
    assert not np.array_equal(J, np.eye(p3.size) - _times_blocks(M[:, p3], D[pl[::-1]])[p3])
    X = rng.standard_normal((11, 3, 3, 3, 3))          # not symmetric: every entry counts
    want = np.einsum("aij,cijkl,bkl->cab", _TAU_SEL, X, _EPS_SEL)
    assert np.array_equal(_tau_strain_blocks(X), want)
    X[:, 0, 1, 1, 0] += 1.0
    assert not np.array_equal(_tau_strain_blocks(X), want)


def _plastic_punch(be):
    """A boundary displacement of the punch with plastic cells (a compressed top, a
    fixed bottom), and its fixed dofs."""
    xy = be.bem.mesh.nodes
    X = np.zeros((be.bem.V_space.ndof, 2))
    X[be.bem.V_space.elem_dofs[:, 0]] = xy[be.bem.mesh.elements[:, 0]]
    u = np.zeros(be.ndofs)
    u[1::2] = -0.02 * X[:, 1] * (np.abs(X[:, 0]) < 0.5)
    return u


def test_lazy_tangent_and_prediction_are_the_dense_ones(punch_bodies):
    """The tangent of implicit_response_lazy (LU at the inner solution, computed on its
    first call) equals K_T = S - G_p D_p (I - M_pp D_p)^-1 B_p by a dense solve, the lazy
    force equals internal_force's, and the next call's prediction (de/du) v through the
    same LU equals (B + M_p D_p X) v."""
    from hpfebe.bodies.plastic_be import _plastic_blocks, _times_blocks
    _, be0 = punch_bodies
    be = ElastoPlasticBE(be0.bem, be0.cells, MAT, scheme="implicit")
    u = _plastic_punch(be)
    tau, rm, tangent = be.implicit_response_lazy(u)
    pl = np.flatnonzero(rm.plastic)
    assert pl.size > 3
    M, B = be._strain_operators()
    p3 = (3 * pl[:, None] + np.arange(3)).ravel()
    e = be._ilast[1]
    D = _CellD(be, M, B @ u, e)
    MD, J = _plastic_blocks(M, pl, D)
    X = np.linalg.solve(J, B[p3])
    KT = be.S - _times_blocks(be.G[:, p3], D[pl]) @ X
    scale = np.abs(KT).max()
    assert np.abs(tangent() - KT).max() < 1e-12 * scale
    assert tangent() is tangent()                        # computed once
    f, lazy = be.internal_force_lazy(u)
    f2, K2 = be.internal_force(u)
    assert np.array_equal(f, f2) and np.abs(lazy().toarray() - KT).max() < 1e-12 * scale
    v = np.random.default_rng(3).standard_normal(be.ndofs)
    dE = B + MD @ X
    got = be._strain_derivative_times(be._ilast, v)
    assert np.abs(got - dE @ v).max() < 1e-12 * np.abs(dE @ v).max()


def _CellD(be, M, b, e):
    """The D blocks of the inner problem at the cell strains e."""
    from hpfebe.bodies.plastic_be import _CellStrainProblem
    return _CellStrainProblem(be, M, b).evaluate(e).data[2]


def test_work_pieces_of_one_geometry_share_their_operators():
    """rectangle_work_piece with the same geometry and elastic constants (another theta)
    shares the LameBEM, the cells and the operators (read-only), and gives the forces of
    a work piece built anew bit for bit; another geometry builds its own."""
    from hpfebe.bodies import plastic_be, cell_operators
    from hpfebe.bodies.plastic_be import rectangle_work_piece
    box = (-2.0, 2.0, -3.0, -1.0)
    m1, m0 = (J2Material(1000.0, 0.3, 1.0, 20.0, th) for th in (1.0, 0.0))
    a = rectangle_work_piece(box, 4, 2, m1, scheme="implicit", cells="crossed")
    b = rectangle_work_piece(box, 4, 2, m0, scheme="implicit", cells="crossed")
    assert b.bem is a.bem and b.cells is a.cells and b.A_tau is a.A_tau and b.G is a.G
    assert not b.A_tau.flags.writeable and not a.A_u.flags.writeable
    c = rectangle_work_piece(box, 4, 3, m0, scheme="implicit", cells="crossed")
    assert c.bem is not a.bem
    plastic_be._WORK_PIECES.clear()
    cell_operators._SHARED.clear()
    fresh = rectangle_work_piece(box, 4, 2, m0, scheme="implicit", cells="crossed")
    assert fresh.bem is not a.bem
    for name in ("A_u", "A_tau", "G", "S"):
        assert np.array_equal(getattr(fresh, name), getattr(b, name))
    u = _plastic_punch(b)
    assert np.array_equal(b.internal_force(u)[0], fresh.internal_force(u)[0])


def test_potential_matrix_is_the_columns_of_evaluate_potential():
    """The double layer matrix of the cell operators (one pass over the point-element
    pairs) equals the potential of every unit density evaluated column by column bit for
    bit, near and far points (far tables, >= 32 points) alike; a point on Gamma is
    refused."""
    from hpfebe.bem.potentials import (POT_LAME_DL, PointOnBoundaryError,
                                       evaluate_potential, potential_matrix)
    bm = BoundaryMesh.polygon([(-1, 0), (1, 0), (1, 1), (-1, 1)], n=[8, 3, 8, 3])
    bem = LameBEM(bm, MAT.E, MAT.nu)
    rng = np.random.default_rng(5)
    Y = np.vstack([np.column_stack([rng.uniform(-0.99, 0.99, 60), rng.uniform(0.01, 0.99, 60)]),
                   [[0.0, 1e-4], [0.999, 0.5], [-0.3, 0.9999]]])
    n = 2 * bem.V_space.ndof
    cols = np.column_stack([evaluate_potential(POT_LAME_DL, bem.kp, 2, Y, bem.V_space,
                                               np.eye(n)[k]).ravel() for k in range(n)])
    A = potential_matrix(POT_LAME_DL, bem.kp, 2, Y, bem.V_space)
    assert A.shape == (2 * len(Y), n) and np.abs(A).max() > 0
    assert np.array_equal(A, cols)
    with pytest.raises(PointOnBoundaryError, match="points must lie off"):
        potential_matrix(POT_LAME_DL, bem.kp, 2, [[0.0, 0.0], [0.2, 0.5]], bem.V_space)


def test_recent_inner_solutions_are_reused_at_their_committed_state(punch_bodies):
    """A point met again among the last RECENT_SOLVES inner solves returns its solution
    (the same objects, its inner diagnostics) without a new solve; after a commit the
    kept solutions of the old history are never returned."""
    from hpfebe.bodies import plastic_be
    _, be0 = punch_bodies
    be = ElastoPlasticBE(be0.bem, be0.cells, MAT, scheme="implicit")
    u = _plastic_punch(be)
    first = be.implicit_response_lazy(u)
    info = be.inner_info
    assert info.iterations > 0 and first[1].plastic.sum() > 3
    for s in (0.9, 0.95):
        be.implicit_response_lazy(s * u)
    assert be.inner_info is not info
    again = be.implicit_response_lazy(u)
    assert again is first and be.inner_info is info
    for s in np.linspace(0.5, 0.8, plastic_be.RECENT_SOLVES):
        be.implicit_response_lazy(s * u)
    assert be.implicit_response_lazy(u) is not first        # dropped: recomputed
    be.commit(0.5 * u)
    after = be.implicit_response_lazy(u)
    assert after is not first
    assert not np.array_equal(after[0], first[0])           # another history
