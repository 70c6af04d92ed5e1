"""The Newton matrix of a plastic FE body in penalty contact on its fixed pattern
(:mod:`hpfebe.contact.newton_matrix`): the matrix of the scipy assembly K_body + C on
the free dofs to round-off, and its LU (PARDISO if installed, SuperLU) solving it."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from hpfebe.bodies import PlasticFEBody
from hpfebe.constitutive.j2 import J2Material
from hpfebe.contact import ContactSettings, TwoBodyContact
from hpfebe.contact.loading import LoadSteps
from hpfebe.contact.newton_matrix import FixedPatternLU, NewtonMatrix
from hpfebe.fem.elasticity import ElasticBody, rectangle_mesh
from hpfebe.fem.plastic_body import ElastoPlasticFE

E, NU = 266926.0, 0.29


def _plastic_iterate():
    """A small stamping problem (FE stamp on a plastic work piece, Coulomb friction)
    at its bonded predictor (plastic points, stick and slip), one contact dof fixed
    (an entry of the contact terms on a fixed dof)."""
    fe = ElastoPlasticFE(rectangle_mesh(-2, 2, -3, -1, 8, 4), J2Material(E, NU, 4.0, 450.0))
    stamp = ElasticBody(rectangle_mesh(-1, 1, -1, 0, 4, 2), E, NU)
    pr = TwoBodyContact(stamp, PlasticFEBody(fe), "bottom", "top", eps_n=1 / (10 * E),
                        eps_t=1 / (5 * E), mu_f=0.2)
    fixed, is_y = pr.stamp_dofs()
    corner = stamp.dofs_at((-1.0, -1.0), 0)
    fixed, is_y = np.concatenate([fixed, corner]), np.concatenate([is_y, [False]])
    steps = LoadSteps(pr, None, fixed, np.where(is_y, 2e-3, 0.0),
                      ContactSettings(rtol=1e-8, line_search=True))
    steps.problem(1.0)
    x = steps.bonded_predictor(steps.evaluate(steps.start(np.zeros(pr.ndofs), 1.0)))
    it = steps.evaluate(x)
    assert fe.state_at(x[pr.offset:])[1].plastic.any()
    return pr, steps, it


def test_newton_matrix_on_fixed_pattern_equals_scipy_assembly():
    pr, steps, it = _plastic_iterate()
    cs, law, w = it.data, it.data["law"], it.data["weights"]
    assert np.any(law.dt_n)                               # slipping points: unsymmetric
    ref = pr.tangent(cs)[steps.free][:, steps.free].toarray()
    nm = NewtonMatrix(cs["K_body"], cs["Gn"], cs["Gt"], steps.free)
    A = nm.assemble(cs["K_body"], w * law.dp_n, w * law.dt_t, w * law.dt_n)
    assert A.shape == ref.shape and A.nnz == nm.P.nnz      # the fixed pattern
    assert np.abs(A.toarray() - ref).max() <= 1e-13 * np.abs(ref).max()
    # the open-everywhere matrix (the body alone) on the same pattern
    z = np.zeros_like(w)
    A0 = nm.assemble(cs["K_body"], z, z, z)
    K0 = cs["K_body"][steps.free][:, steps.free].toarray()
    assert np.array_equal(A0.indices, A.indices) and np.abs(A0.toarray() - K0).max() == 0


@pytest.mark.parametrize("backend", ["default", "superlu"])
def test_fixed_pattern_lu_solves_the_newton_system(backend):
    pr, steps, it = _plastic_iterate()
    cs, law, w = it.data, it.data["law"], it.data["weights"]
    nm = NewtonMatrix(cs["K_body"], cs["Gn"], cs["Gt"], steps.free)
    lu = FixedPatternLU({})
    if backend == "superlu":
        lu.pardiso = None
    r = -it.residual
    for scale in (1.0, 0.5):                   # a second matrix: numeric phase only
        A = nm.assemble(cs["K_body"], scale * w * law.dp_n, w * law.dt_t, w * law.dt_n)
        d = lu.factor(A).solve(r)
        ref = spla.spsolve(A.tocsc(), r)
        assert np.linalg.norm(A @ d - r) <= 1e-10 * np.linalg.norm(r)
        assert np.linalg.norm(d - ref) <= 1e-8 * np.linalg.norm(ref)
    # the Newton step of the load steps is that solve
    dx = steps.step(it)
    A = nm.assemble(cs["K_body"], w * law.dp_n, w * law.dt_t, w * law.dt_n)
    assert np.linalg.norm(A @ dx[steps.free] - r) <= 1e-10 * np.linalg.norm(r)


def test_newton_matrix_sums_duplicate_entries_of_a_non_canonical_tangent():
    """A body tangent with duplicate (unsummed) entries takes the summing path of
    NewtonMatrix.assemble; a canonical one stores its entries: the same matrix."""
    import scipy.sparse as sp
    pr, steps, it = _plastic_iterate()
    cs, law, w = it.data, it.data["law"], it.data["weights"]
    K = sp.csr_matrix(cs["K_body"])
    coo = K.tocoo()
    half = 0.5 * coo.data                         # every entry split into two halves
    Kdup = sp.csr_matrix((np.concatenate([half, coo.data - half]),
                          (np.concatenate([coo.row, coo.row]),
                           np.concatenate([coo.col, coo.col]))), shape=K.shape)
    Kdup = sp.csr_matrix((Kdup.data, Kdup.indices, Kdup.indptr), shape=K.shape)
    nm = NewtonMatrix(K, cs["Gn"], cs["Gt"], steps.free)
    args = (w * law.dp_n, w * law.dt_t, w * law.dt_n)
    A = nm.assemble(K, *args)
    assert isinstance(nm._body_map(K)[1], tuple)          # the storing path
    ref = pr.tangent(cs)[steps.free][:, steps.free].toarray()
    coo_dup = sp.coo_matrix((np.concatenate([half, coo.data - half]),
                             (np.concatenate([coo.row, coo.row]),
                              np.concatenate([coo.col, coo.col]))), shape=K.shape)
    Kraw = sp.csr_matrix(coo_dup.shape)
    Kraw.indptr = np.concatenate([[0], np.cumsum(np.bincount(np.sort(coo_dup.row),
                                                             minlength=K.shape[0]))])
    order = np.argsort(coo_dup.row, kind="stable")
    Kraw.indices, Kraw.data = coo_dup.col[order].astype(K.indices.dtype), \
        coo_dup.data[order]
    assert Kraw.nnz == 2 * K.nnz and not Kraw.has_canonical_format
    nm2 = NewtonMatrix(K, cs["Gn"], cs["Gt"], steps.free)
    A2 = nm2.assemble(Kraw, *args)
    assert not isinstance(nm2._body_map(Kraw)[1], tuple)  # the summing path
    scale = np.abs(ref).max()
    assert np.abs(A.toarray() - ref).max() <= 1e-13 * scale
    assert np.abs(A2.toarray() - ref).max() <= 1e-13 * scale


def test_block_diagonal_of_plastic_tangents_reuses_its_pattern():
    """TwoBodyContact's block diagonal of the body tangents keeps its index arrays while
    the tangents keep their patterns (a plastic body's tangent at another state), with
    the values of the new tangents: scipy's block_diag of them."""
    import scipy.sparse as sp
    pr, steps, it = _plastic_iterate()
    K1 = it.data["K_body"]
    it2 = steps.evaluate(it.x * 1.5)
    K2 = it2.data["K_body"]
    assert np.shares_memory(K2.indices, K1.indices)                # the pattern reused
    assert np.shares_memory(K2.indptr, K1.indptr)
    master = pr.bodies["master"]
    _, rm = master.plastic.state_at(master.offset + it2.x[pr.offset:])
    assert rm.plastic.any()
    ref = sp.block_diag([pr.bodies["slave"].K, master.plastic.tangent_matrix(rm)],
                        format="csr")
    assert np.abs(K2 - K1).max() > 0                               # other values
    assert np.abs((K2 - ref).toarray()).max() == 0


def test_secant_tangent_maps_the_strain_to_the_stress_from_a_virgin_state():
    """From a virgin history sigma = kappa tr eps 1 + 2 mu theta_1 dev eps at every
    point, so f_int(u) = K_sec(u) u; the algorithmic tangent is softer (it does not)."""
    fe = ElastoPlasticFE(rectangle_mesh(-1, 1, -1, 0, 6, 3), J2Material(E, NU, 4.0, 450.0))
    rng = np.random.default_rng(1)
    u = 1e-4 * rng.standard_normal(fe.ndofs)
    f, rm = fe.state_at(u)
    assert rm.plastic.mean() > 0.5
    K_sec, K_alg = fe.tangent_matrix(rm, "secant"), fe.tangent_matrix(rm, "algorithmic")
    assert np.linalg.norm(K_sec @ u - f) <= 1e-12 * np.linalg.norm(f)
    assert np.linalg.norm(K_alg @ u - f) > 1e-3 * np.linalg.norm(f)
    with pytest.raises(ValueError, match="tangent"):
        fe.tangent_matrix(rm, "tangential")


def test_secant_start_reaches_the_same_solution():
    """ContactSettings.secant_start: the first step from the bonded predictor with the
    secant stiffness, the later ones with the algorithmic tangent (the body's choice
    restored); Newton converges to the solution of the plain start within the
    tolerance."""
    from hpfebe.solvers import newton
    out = {}
    for secant in (False, True):
        pr, steps, _ = _plastic_iterate()
        steps.settings = ContactSettings(rtol=1e-10, line_search=True, predictor=True,
                                         secant_start=secant, max_iter=60)
        x0 = steps.start(np.zeros(pr.ndofs), 1.0)
        it, info = newton(steps, x0, **steps.newton_options())
        assert info.converged and info.predictor_used
        assert pr.bodies["master"].plastic.tangent == "algorithmic"
        out[secant] = it.x
    assert np.abs(out[True] - out[False]).max() <= 1e-7 * np.abs(out[False]).max()
    with pytest.raises(ValueError, match="secant_start"):
        ContactSettings(secant_start="yes")
