"""The Woodbury Newton solver of two linear bodies in contact
(hpfebe.contact.woodbury.WoodburySolver, ``TwoBodyContact.solve(linear_solver="woodbury")``):
the same Newton solution as a sparse LU of every Newton matrix, up to round-off, with
each body factorised by PARDISO or by SuperLU.

Scene: the Figure 4.13 setup (slave [-1/2, 1/2] x [0, 2], top fixed; master [-2, 2] x
[-2, 0], bottom lifted by 5e-4; Coulomb mu_f = 0.1) on the initial meshes once refined.
Tolerances: the two solvers' converged states agree to about 1e-14 relative (measured);
1e-10 leaves room for the conditioning of the penalty (1/eps = 10 E)."""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe.solvers import SingularStep

from hpfebe.contact import ContactSettings, TwoBodyContact
from hpfebe.contact.newton_matrix import _pardiso_solver
from hpfebe.contact.woodbury import SuperLUBody, WoodburySolver
from hpfebe.fem import refine_labelled
from hpfebe.fem.elasticity import ElasticBody, rectangle_mesh

E, NU = 266926.0, 0.29
BACKENDS = ["superlu", pytest.param("pardiso", marks=pytest.mark.skipif(
    _pardiso_solver() is None, reason="pypardiso not installed"))]


def _problem(refine=1):
    ms = [rectangle_mesh(-0.5, 0.5, 0, 2, 4, 8, kind="tri"),
          rectangle_mesh(-2, 2, -2, 0, 16, 8, kind="tri")]
    for _ in range(refine):
        ms = [refine_labelled(m) for m in ms]
    S, M = (ElasticBody(m, E, NU, "strain") for m in ms)
    pr = TwoBodyContact(S, M, ["bottom", "left", "right"], ["top", "left", "right"],
                        eps_n=1.0 / (10 * E), eps_t=1.0 / (5 * E), mu_f=0.1)
    fixed, is_y = pr.stamp_dofs()
    return pr, fixed, 5e-4 * is_y


def _solve(linear_solver, predictor=False):
    pr, fixed, vals = _problem()
    return pr.solve(None, fixed, vals, load_factors=np.arange(1, 6) / 5, settings=ContactSettings(rtol=1e-10, max_iter=30, linear_solver=linear_solver, predictor=predictor))


@pytest.mark.parametrize("predictor", [False, True])
def test_woodbury_gives_the_lu_solution(predictor):
    a, b = _solve("lu", predictor), _solve("woodbury", predictor)
    assert a.converged and b.converged, (a.reason, b.reason)
    scale = np.abs(a.U).max()
    assert np.abs(a.U - b.U).max() <= 1e-10 * scale
    np.testing.assert_array_equal(a.state, b.state)
    np.testing.assert_allclose(b.p_n, a.p_n, rtol=1e-9, atol=1e-9 * a.p_n.max())
    # the same Newton path: the stick/slip states of the first iterate of a load step
    # are not left to rounding (constitutive.laws); before, e.g. 4 3 3 4 3 against
    # 4 4 4 3 3 here
    assert a.iterations == b.iterations


@pytest.mark.parametrize("backend", BACKENDS)
def test_schur_complement_inverse_and_solve_match_dense_algebra(backend):
    pr, fixed, _ = _problem(refine=0)
    free = np.setdiff1d(np.arange(pr.ndofs), fixed)
    wb = WoodburySolver(pr.K, free, pr.offset, pr.Gn, pr.Gt, backend=backend)
    assert [f.backend for _, _, f in wb.blocks] == [backend, backend]
    Kd = pr.K.toarray()[np.ix_(free, free)]
    Kinv = np.linalg.inv(Kd)
    c = wb.rows
    # SuperLU: the Schur complements of the factors; PARDISO: partial solves
    assert wb.from_factors == [backend == "superlu"] * 2
    np.testing.assert_allclose(wb._columns(c), Kinv[np.ix_(c, c)], rtol=1e-9,
                               atol=1e-9 * np.abs(Kinv).max())
    # a Newton matrix with stick (W_n, W_t) and slip (W_n, W_tn) points
    rng = np.random.default_rng(1)
    n_pts = pr.points.shape[0]
    wn = np.where(rng.random(n_pts) < 0.5, 0.0, rng.random(n_pts) * 10 * E)
    wt = np.where(rng.random(n_pts) < 0.5, 0.0, rng.random(n_pts) * 5 * E)
    wtn = np.where(wt == 0, 0.1 * wn, 0.0)
    Gn, Gt = pr.Gn.toarray()[:, free], pr.Gt.toarray()[:, free]
    A = Kd + Gn.T @ np.diag(wn) @ Gn + Gt.T @ (np.diag(wt) @ Gt - np.diag(wtn) @ Gn)
    r = rng.standard_normal(free.size)
    d = wb.solve(wn, wt, wtn, r)
    np.testing.assert_allclose(d, np.linalg.solve(A, r), rtol=1e-9,
                               atol=1e-9 * np.abs(d).max())
    np.testing.assert_allclose(wb.matvec(wn, wt, wtn, d), r, atol=1e-9 * np.abs(r).max())


def test_bad_linear_solver_is_rejected():
    pr, fixed, vals = _problem(refine=0)
    with pytest.raises(ValueError, match="linear_solver"):
        pr.solve(None, fixed, vals, settings=ContactSettings(linear_solver="cholesky"))


@pytest.mark.parametrize("backend", BACKENDS)
def test_floating_body_is_reported_as_singular(backend, monkeypatch):
    """A master held by the contact only (no Dirichlet conditions, pushed up by a
    traction): its K is singular, the Woodbury solve fails with a reason."""
    monkeypatch.setenv("HPFEBE_PARDISO", "1" if backend == "pardiso" else "0")
    pr, fixed, vals = _problem(refine=0)
    keep = fixed < pr.offset           # only the slave's top fixed: the master floats
    f = pr.traction_load("master", "bottom", (0.0, 100.0))
    res = pr.solve(f, fixed[keep], vals[keep], settings=ContactSettings(linear_solver="woodbury"))
    assert not res.converged
    assert "singular" in res.reason
    if backend == "superlu":
        return        # SuperLU factorises the singular K: the step's residual check fails
    # PARDISO's Cholesky finds a nonpositive pivot: the solver says so itself
    free = np.setdiff1d(np.arange(pr.ndofs), fixed[keep])
    wb = WoodburySolver(pr.K, free, pr.offset, pr.Gn, pr.Gt, backend=backend)
    with pytest.raises(SingularStep, match="singular body stiffness"):
        wb.solve(np.zeros(pr.points.shape[0]), np.zeros(pr.points.shape[0]),
                 np.zeros(pr.points.shape[0]), np.ones(free.size))


def test_schur_inverse_by_solves_when_the_factors_reorder_the_contact_dofs():
    """When SuperLU's postorder moves the contact dofs out of the trailing block, the
    inverse comes from m solves with the factors instead."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    pr, fixed, _ = _problem(refine=0)
    free = np.setdiff1d(np.arange(pr.ndofs), fixed)
    A = sp.csc_matrix(pr.K)[free][:, free][:40][:, :40].tocsc()
    body = SuperLUBody(A, np.arange(34, 40))
    assert body.from_factors
    lu = spla.splu(A)

    class Reordered:                       # the factors of A with other permutations
        perm_c = np.arange(40)[::-1].copy()
        perm_r = perm_c
        solve = staticmethod(lu.solve)

    got = body._kinv_trailing(Reordered(), 40, 6)
    assert body.from_factors is False
    np.testing.assert_allclose(got, np.linalg.inv(A.toarray())[34:, 34:], rtol=1e-9)


def test_fe_body_against_a_rigid_obstacle():
    """One FE body pressed onto a rigid obstacle (one block in K): both solvers agree."""
    from hpfebe.bodies import FEBody, RigidObstacle

    out = []
    for solver in ("lu", "woodbury"):
        body = ElasticBody(rectangle_mesh(0, 2, 0, 1, 6, 3, kind="tri"), E, NU, "strain")
        pr = TwoBodyContact(FEBody(body), RigidObstacle(-1e-4, 1e-5), "bottom",
                            eps_n=1.0 / (10 * E), eps_t=1.0 / (5 * E), mu_f=0.3)
        fixed = pr.dofs_on("slave", "top")
        res = pr.solve(None, fixed, np.zeros(fixed.size), load_factors=np.arange(1, 5) / 4, settings=ContactSettings(linear_solver=solver, line_search=True))
        assert res.converged, res.reason
        out.append(res)
    a, b = out
    assert np.abs(a.p_n).max() > 0
    assert np.abs(a.U - b.U).max() <= 1e-10 * np.abs(a.U).max()
    np.testing.assert_array_equal(a.state, b.state)
