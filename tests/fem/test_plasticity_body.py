"""The elastoplastic FE body (hpfebe.fem.plastic_body): elastic limit = ElasticBody,
tangent = derivative of the internal force, patch test with homogeneous plastic flow =
material point, quadratic Newton convergence in a punch problem (load_path), a failed
load step leaves the committed state untouched, bad input."""

import numpy as np
import pytest

from hpfebe.bodies import as_body
from hpfebe.fem.elasticity import rectangle_mesh
from hpfebe.bodies import PlasticFEBody
from hpfebe.fem.plastic_body import DisplacementSteps, ElastoPlasticFE
from hpfebe.constitutive.j2 import J2Material, J2State, return_map
from hpfebe.solvers import load_path

MAT = J2Material(266926.0, 0.29, 4.0, 450.0, 1.0)


def punch(fe, depth=4.3e-3):
    """Bottom fixed, the top's middle third pushed down by ``depth`` (y only)."""
    b = fe.elastic
    bottom = b.dofs_on("bottom")
    xy = b.dof_coordinates()
    top = b.dofs_on("top", 1)
    top = top[np.abs(xy[top, 0]) < 0.5]
    return DisplacementSteps(fe, np.concatenate([bottom, top]),
                             np.concatenate([np.zeros(bottom.size), -depth * np.ones(top.size)]))


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_full_integration_elastic_stiffness_is_elasticbody(kind):
    fe = ElastoPlasticFE(rectangle_mesh(0, 2, 0, 1, 4, 2, kind), MAT, "full")
    assert abs(fe.K - fe.elastic.K).max() < 1e-12 * abs(fe.K).max()
    u = np.random.default_rng(0).normal(scale=1e-7, size=fe.ndofs)   # stays elastic
    f, T = fe.internal_force(u)
    np.testing.assert_allclose(f, fe.K @ u, atol=1e-10 * np.abs(f).max())


@pytest.mark.parametrize("formulation", ["bbar", "full"])
@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_tangent_is_derivative_of_internal_force(kind, formulation):
    m = rectangle_mesh(-2, 2, -3, -1, 4, 2, kind)
    fe = ElastoPlasticFE(m, MAT, formulation)
    ds = punch(fe, 1e-3)
    _, info = load_path(ds, [0.5], np.zeros(fe.ndofs), tol=1e-10, max_iter=40)
    assert info.converged
    rng = np.random.default_rng(3)
    u = ds.start(np.zeros(fe.ndofs), 0.8) + rng.normal(scale=1e-5, size=fe.ndofs)
    f, T = fe.internal_force(u)
    _, _, rm = fe.response(u)
    assert rm.plastic.mean() > 0.3
    v = rng.normal(size=fe.ndofs)
    h = 1e-10
    fd = (fe.internal_force(u + h * v)[0] - fe.internal_force(u - h * v)[0]) / (2 * h)
    assert np.linalg.norm(fd - T @ v) < 1e-6 * np.linalg.norm(T @ v)


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_patch_homogeneous_flow_equals_material_point(kind):
    """u = G(lam) x on the whole boundary: the FE solution is homogeneous and every
    quadrature point follows the material point along the same strain path
    (loading, partial unloading with reverse yield, reloading)."""
    m = rectangle_mesh(0, 1, 0, 1, 3, 3, kind)
    fe = ElastoPlasticFE(m, MAT, "bbar")
    G = np.array([[2e-4, 6e-5], [0.0, -1e-4]])
    b = fe.elastic
    bd = b.dofs_on(["left", "right", "bottom", "top"])
    xy = b.dof_coordinates()
    comp = np.where(np.isin(bd, b.nodal_dofs[0]), 0, 1)
    vals = np.einsum("nj,nj->n", G[comp], xy[bd])
    path = [0.25, 0.5, 1.0, 0.2, -0.3, 0.6]
    st = J2State.zeros(1)
    u = np.zeros(fe.ndofs)
    for lam in path:
        ds = DisplacementSteps(fe, bd, vals)     # one step from the committed state
        it, info = load_path(ds, [lam], u, tol=1e-11, max_iter=30)
        assert info.converged, info.reason
        u = it.x
        eps = np.zeros((1, 3, 3))
        eps[0, :2, :2] = lam * 0.5 * (G + G.T)
        rm = return_map(MAT, eps, st)
        st = rm.state
        assert rm.plastic[0] or lam == 0.2
        np.testing.assert_allclose(fe.sigma, np.broadcast_to(rm.sigma, fe.sigma.shape),
                                   atol=1e-8 * MAT.sigma_Y)
        np.testing.assert_allclose(fe.committed.eps_p,
                                   np.broadcast_to(st.eps_p, fe.committed.eps_p.shape),
                                   atol=1e-14)
    assert abs(fe.committed.eps_p[0, 2, 2]) > 1e-6          # out of plane plastic strain


def test_newton_converges_quadratically():
    fe = ElastoPlasticFE(rectangle_mesh(-2, 2, -3, -1, 16, 8, "quad"), MAT, "bbar")
    ds = punch(fe)
    it, info = load_path(ds, np.linspace(0.1, 1, 10), np.zeros(fe.ndofs), tol=1e-10,
                         max_iter=40)
    assert info.converged
    assert fe.fields()["alpha"].max() > 0
    iters = [s.iterations for s in info.steps]
    assert max(iters[1:]) <= 6, iters                       # with the secant predictor
    r = np.array(info.steps[-1].residuals) / it.scale
    # last iterations: r_{k+1} <= C r_k^2
    assert r[-1] < 1e-12 and r[-2] < 1e-8
    assert r[-2] <= 1e3 * r[-3] ** 2 and r[-1] <= 1e3 * max(r[-2] ** 2, 1e-16)


def test_failed_step_leaves_state_untouched():
    fe = ElastoPlasticFE(rectangle_mesh(-2, 2, -3, -1, 8, 4, "quad"), MAT, "bbar")
    ds = punch(fe)
    _, info = load_path(ds, [0.2], np.zeros(fe.ndofs), tol=1e-10, max_iter=40)
    assert info.converged
    before = fe.committed.copy()
    _, info = load_path(ds, [0.4, 1.0], ds._last[1][0], tol=1e-10, max_iter=2, lam0=0.2)
    assert not info.converged and "load step 1/2: max_iter" in info.reason
    np.testing.assert_array_equal(fe.committed.eps_p, before.eps_p)
    np.testing.assert_array_equal(fe.committed.alpha, before.alpha)


def test_contact_body_protocol():
    fe = ElastoPlasticFE(rectangle_mesh(-2, 2, -3, -1, 4, 2, "quad"), MAT)
    body = PlasticFEBody(fe)
    assert as_body(body) is body and body.kind == "FE" and not body.linear
    assert body.ndofs == fe.ndofs and body.K.shape == (fe.ndofs, fe.ndofs)
    seg = body.segments("top")
    assert seg["ids"].size == 4
    u = np.zeros(fe.ndofs)
    u[body.dofs_on("top", 1)] = -1e-3
    f, T = body.internal_force(u)
    assert np.abs(f).max() > 0 and T.shape == body.K.shape
    body.commit(u)
    assert fe.fields()["eps_p_norm"].max() > 0
    assert fe.value_at("dev_sigma_norm", (1.0, -1.1)) > 0
    assert fe.elements_at((1.0, -1.1)).size == 2 and fe.elements_at((0.5, -1.1)).size == 1


def test_bad_input():
    m = rectangle_mesh(0, 1, 0, 1, 2, 2)
    with pytest.raises(ValueError, match="formulation"):
        ElastoPlasticFE(m, MAT, "fbar")
    with pytest.raises(ValueError, match="tangent"):
        ElastoPlasticFE(m, MAT, tangent="tangential")   # ("secant" is a body tangent)
    assert ElastoPlasticFE(m, MAT, tangent="secant").tangent == "secant"
    with pytest.raises(ValueError, match="material"):
        ElastoPlasticFE(m, {"E": 1.0})
    with pytest.raises(ValueError, match="mesh"):
        ElastoPlasticFE(None, MAT)
    fe = ElastoPlasticFE(m, MAT)
    with pytest.raises(ValueError, match="u must"):
        fe.internal_force(np.zeros(3))
    with pytest.raises(ValueError, match="point"):
        fe.elements_at((5.0, 5.0))
    with pytest.raises(ValueError, match="key"):
        fe.value_at("sigma", (0.5, 0.5))
    with pytest.raises(ValueError, match="fixed"):
        DisplacementSteps(fe, [10 ** 6], [0.0])
    with pytest.raises(ValueError, match="f_ext"):
        DisplacementSteps(fe, [0], [0.0], f_ext=np.zeros(2))
    with pytest.raises(ValueError, match="fe"):
        PlasticFEBody(fe.elastic)


def test_continuum_tangent_converges_slower():
    """The thesis's continuum C^ep (Section 4.2.2) against the algorithmic tangent
    (4.42)-(4.43): same solution, linear instead of quadratic convergence."""
    m = rectangle_mesh(-2, 2, -3, -1, 8, 4, "quad")
    its, sol = {}, {}
    for tg in ("algorithmic", "continuum"):
        fe = ElastoPlasticFE(m, MAT, "bbar", tangent=tg)
        ds = punch(fe, 1e-4)
        it, info = load_path(ds, np.linspace(0.25, 1, 4), np.zeros(fe.ndofs), tol=1e-9,
                             max_iter=300)
        assert info.converged, (tg, info.reason)
        its[tg], sol[tg] = info.iterations, it.x
    assert its["continuum"] > 2 * its["algorithmic"], its
    np.testing.assert_allclose(sol["continuum"], sol["algorithmic"],
                               atol=1e-6 * np.abs(sol["algorithmic"]).max())


@pytest.mark.parametrize("formulation", ["bbar", "full"])
@pytest.mark.parametrize("tg", ["algorithmic", "continuum"])
def test_tangent_from_plastic_elements_equals_full_assembly(formulation, tg):
    """The tangent assembled from the plastic elements only (elastic element matrices
    elsewhere, the fused kernel of tr_i tr_j, G_ij, m_i m_j) and the lazy tangent are the
    full assembly of the pointwise tangent of return_map to round-off (64 eps of the
    largest entry; the same pattern, that of K); the strain and force kernels are the einsum
    contractions to the rounding bound of their sums, gamma_n sum |terms| with n the
    number of terms (einsum's summation order depends on the CPU's SIMD width)."""
    fe = ElastoPlasticFE(rectangle_mesh(-2, 2, -3, -1, 8, 4, "quad"), MAT, formulation,
                         tangent=tg)
    ds = punch(fe, 2e-3)
    u = ds.start(np.zeros(fe.ndofs), 1.0)
    u += np.random.default_rng(5).normal(scale=1e-6, size=fe.ndofs)
    f, T, rm = fe.response(u)
    pl = rm.plastic.reshape(fe.nel, fe.nq).any(axis=1)
    assert 0 < pl.sum() < fe.nel                     # some elements elastic, some not
    full = return_map(MAT, fe.strain(u), fe.committed, tg)
    ref = fe._assemble(full.tangent.reshape(fe.nel, fe.nq, 9, 9))
    for A in (T, fe.internal_force_lazy(u)[1]()):
        np.testing.assert_array_equal(A.indptr, ref.indptr)
        np.testing.assert_array_equal(A.indices, ref.indices)
        assert np.shares_memory(A.indices, fe.K.indices)        # the fixed pattern of K
        assert np.abs(A.data - ref.data).max() <= 64 * np.finfo(float).eps * \
            np.abs(ref.data).max()
    ue = u[fe.element_dofs].T
    u_r = np.finfo(float).eps / 2

    def gamma(n):                       # the bound of an n-term sum, both sides: 2 gamma_n
        return 2 * n * u_r / (1 - n * u_r)

    n_i = fe.B.shape[2]
    eps_ref = np.einsum("eqia,ei->eqa", fe.B, ue).reshape(-1, 3, 3)
    eps_abs = np.einsum("eqia,ei->eqa", np.abs(fe.B), np.abs(ue)).reshape(-1, 3, 3)
    assert np.all(np.abs(fe.strain(u) - eps_ref) <= gamma(n_i) * eps_abs)
    sig = full.sigma.reshape(fe.nel, fe.nq, 9)
    dofs = fe.element_dofs.T.ravel()
    f_ref = np.bincount(dofs, np.einsum("eqia,eqa,eq->ei", fe.B, sig, fe.dx).ravel(),
                        minlength=fe.ndofs)
    f_abs = np.bincount(dofs, np.einsum("eqia,eqa,eq->ei", np.abs(fe.B), np.abs(sig),
                                        fe.dx).ravel(), minlength=fe.ndofs)
    n_f = fe.nq * 9 + np.bincount(dofs).max()           # per element, then per dof
    assert np.all(np.abs(f - f_ref) <= gamma(n_f + 1) * f_abs)
    assert fe.tangent_matrix(return_map(MAT, 0 * fe.strain(u), fe.committed)) is fe.K
