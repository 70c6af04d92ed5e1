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
