"""The fast paths of the Chapter 2/3 post-processing give the very numbers of the plain
ones (bitwise): far-pair tables of the potentials (hpfebe.bem.potentials), threads,
the prefiltered boundary location and the shared BE-part domain errors
(hpfebe.coupling.errors), the memoised inverse Jacobians of the Q_p basis
(hpfebe.fem.poisson), precomputed residuals of the Lame indicators."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import Basis

from hpfebe.adaptivity.bem_estimator import lame_bem_indicators, lame_boundary_residuals
from hpfebe.bem import LaplaceBEM, potentials, threads
from hpfebe.bem.lame import LameBEM
from hpfebe.coupling import NitscheFEBE
from hpfebe.scenes.interface import problem
from hpfebe.coupling.errors import (be_domain_errors, be_domain_errors_both,
                                    boundary_values)
from hpfebe.fem import poisson
from hpfebe.fem.poisson import PoissonFE
from hpfebe.geometry import BoundaryMesh


def _mesh():
    mesh = BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1, 1.5), (0, 1)],
                                n=[5, 2, 3, 3, 2], p=1)
    return mesh.with_degrees(np.random.default_rng(3).integers(1, 5, mesh.n_elements))


def _points(n=60):
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(0.01, 1.99, n), rng.uniform(0.01, 0.99, n)])
    # near Gamma (bisected panels) and within round-off of a far/near switch
    return np.vstack([pts, [[1.0, 1e-7], [0.5, 1e-3], [2 - 1e-9, 0.5], [0.9, -0.4]]])


CASES = [(potentials.POT_LAPLACE_SL, 1, 1), (potentials.POT_LAPLACE_DL, 1, 1),
         (potentials.POT_LAME_SL, 2, 2), (potentials.POT_LAME_DL_GRAD, 2, 4)]


@pytest.mark.parametrize("kid, d, nout", CASES)
def test_far_tables_equal_generic_path(kid, d, nout):
    """>= MIN_TABLE_POINTS points take the tabulated far pairs; one point at a time the
    generic loop: the same bits."""
    mesh = _mesh()
    op = LaplaceBEM(mesh) if d == 1 else LameBEM(mesh, 1.0, 0.3)
    space = op.W_space if kid in (potentials.POT_LAPLACE_SL, potentials.POT_LAME_SL) \
        else op.V_space
    c = np.random.default_rng(1).standard_normal(d * space.ndof)
    pts = _points()
    assert len(pts) >= potentials.MIN_TABLE_POINTS
    many = potentials.evaluate_potential(kid, op.kp, d, pts, space, c, nout=nout)
    single = np.vstack([potentials.evaluate_potential(kid, op.kp, d, p[None], space, c,
                                                      nout=nout) for p in pts])
    assert np.array_equal(many, single)


def test_threads_give_the_same_bits(monkeypatch):
    mesh = _mesh()
    op = LaplaceBEM(mesh)
    c = np.random.default_rng(2).standard_normal(op.V_space.ndof)
    pts = _points(300)
    one = potentials.evaluate_potential(potentials.POT_LAPLACE_DL, op.kp, 1, pts,
                                        op.V_space, c)
    monkeypatch.setattr(threads.numba, "get_num_threads", lambda: 3)
    monkeypatch.setattr(potentials, "MIN_PAIRS_PER_THREAD", 1)
    three = potentials.evaluate_potential(potentials.POT_LAPLACE_DL, op.kp, 1, pts,
                                          op.V_space, c)
    assert np.array_equal(one, three)


def test_order_thresholds_reproduce_order():
    """The tabulated far orders equal _order at ratios around every threshold."""
    from hpfebe.bem.integration import _order

    nmax, dmax, nf = 48, 5, 17
    thr2 = potentials._order_thresholds(dmax, nf, nmax)
    for deg in range(dmax + 1):
        for n in range(1, nf + 1):
            t = np.sqrt(thr2[deg, n])
            if not np.isfinite(t) or t == 2.0:
                continue
            assert _order(t * (1 + 1e-12), deg, nmax) <= n < _order(t * (1 - 1e-12), deg,
                                                                      nmax)


@pytest.fixture(scope="module")
def nitsche_run():
    model = NitscheFEBE(problem("singular"), 8, 12, 2)
    return model, model.solve(10.0)


def test_boundary_values_prefilter(nitsche_run):
    """boundary_values locates only the points near a BE node: same values as locating
    all points."""
    model, sol = nitsche_run
    m = problem("singular").omega2_domain(24).mesh
    pts = np.vstack([m.p.T, m.p.T + 1e-12, m.p.T - 3e-11])
    elem, t = model.be_mesh.locate(pts)
    ref = np.full(len(pts), np.nan)
    on = elem >= 0
    ref[on] = model.bem.V_space.evaluate(sol.U2, elem[on], t[on])
    assert np.array_equal(boundary_values(model, sol.U2, pts), ref, equal_nan=True)
    assert on.sum() > 0


def test_be_domain_errors_both(nitsche_run):
    model, sol = nitsche_run
    a, b = be_domain_errors_both(model, sol)
    assert a == be_domain_errors(model, sol)
    assert b == be_domain_errors(model, sol, interpolate_exact=True)


def test_memoised_basis_is_skfem_basis():
    # the memo of the inverse Jacobians changes no number (bit for bit) ...
    dom = problem("smooth").fe_domain(5)
    fe = PoissonFE(dom, 3)
    plain = Basis(dom.mesh, fe.element, intorder=7)
    memo = poisson._MemoInvDF(dom.mesh._mapping())
    memoised = Basis(dom.mesh, fe.element, mapping=memo, intorder=7)
    for a, b in zip(memoised.basis, plain.basis):
        assert np.array_equal(np.asarray(a[0]), np.asarray(b[0]))
        assert np.array_equal(a[0].grad, b[0].grad)
    assert np.array_equal(memoised.dx, plain.dx)
    # ... and PoissonFE's basis, on the affine map of these rectangles, agrees with it
    # to the round-off of the bilinear map's Jacobian sum
    for a, b in zip(fe.basis.basis, plain.basis):
        assert np.allclose(np.asarray(a[0]), np.asarray(b[0]), rtol=0, atol=1e-14)
        assert np.abs(a[0].grad - b[0].grad).max() <= 1e-13 * np.abs(b[0].grad).max()
    assert np.abs(fe.basis.dx - plain.dx).max() <= 1e-14 * plain.dx.max()


def test_lame_indicators_with_precomputed_residuals():
    mesh = BoundaryMesh.polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)], n=3,
                                labels=["C", "N", "D", "N"], p=1)
    op = LameBEM(mesh, 100.0, 0.3)
    rng = np.random.default_rng(4)
    U, Psi = rng.standard_normal(2 * op.V_space.ndof), rng.standard_normal(2 * op.W_space.ndof)
    data = {"N": lambda x, n: np.zeros((len(x), 2)), "C": lambda x, n: np.ones((len(x), 2))}
    eta = lame_bem_indicators(op, U, Psi, data)
    r = lame_boundary_residuals(op, U, Psi)
    assert np.array_equal(eta, lame_bem_indicators(op, U, Psi, data, residuals=r))
