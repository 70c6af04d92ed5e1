"""The adaptive h-BEM contact core of Section 3.3.5: the contact datum of (3.107) from the
penalty law, the indicator wrapper, |||U|||_B of (3.105), the error against a reference on
a nested mesh, and the adaptive loop on a Lame BE body against a rigid line."""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.adaptivity import adapt, lame_bem_indicators
from hpfebe.adaptivity.bem_estimator import (consistency_weight, contact_traction,
                                             lame_contact_indicators, norm_B, true_error)
from hpfebe.bem.lame import LameBEM
from hpfebe.contact.friction import FrictionSettings, solve_friction
from hpfebe.geometry import common_refinement
from hpfebe.spaces import prolongate

SQUARE = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
LABELS = ["C", "C", "D", "C"]
E, NU, MU_F, EPS = 266926.0, 0.29, 0.1, 5e-8


def mesh_of(n):
    return BoundaryMesh.polygon(SQUARE, n=n, labels=LABELS, p=1)


def line_gap(d):
    """Rigid line y = -1 + d below the body: g = -d on the bottom side, far elsewhere."""
    return lambda x: np.where(x[:, 1] < -1.0 + 1e-9, -d, 1.0)


def solve(mesh, d=6e-4, eps=EPS):
    op = LameBEM(mesh, E, NU, "strain")
    res = solve_friction(op, line_gap(d), FrictionSettings(eps, eps, "coulomb", mu_f=MU_F))
    assert res.converged, res.reason
    return op, res, op.Psi(res.U)


@pytest.fixture(scope="module")
def coarse():
    return solve(mesh_of(4))


def test_contact_datum_is_the_penalty_coulomb_law(coarse):
    """-p_n n - t_t t with p_n = (U_n - g)_+ / eps_n, t_t = clip(U_t / eps_t, +-mu_f p_n)
    (one load step), on the body."""
    op, res, _ = coarse
    mesh = op.mesh
    gap = line_gap(6e-4)
    f = contact_traction(op, res.U, gap, EPS, 2 * EPS, mu_f=MU_F)
    on = np.flatnonzero(mesh.where("C"))
    elem = np.repeat(on, 5)
    t = np.tile(np.linspace(-0.9, 0.9, 5), len(on))
    x = mesh.points(elem, t)
    u = op.V_space.evaluate(res.U.reshape(-1, 2), elem, t)
    n, tan = mesh.normals[elem], mesh.tangents[elem]
    pn = np.maximum(np.sum(u * n, 1) - gap(x), 0.0) / EPS
    tt = np.clip(np.sum(u * tan, 1) / (2 * EPS), -MU_F * pn, MU_F * pn)
    got = f(x, n, elem, t)
    assert np.allclose(got, -pn[:, None] * n - tt[:, None] * tan, rtol=1e-13, atol=0)
    assert np.any(pn > 0) and np.any(np.abs(tt) > 0)
    # Tresca: the bound F on all of Gamma_C
    fT = contact_traction(op, res.U, gap, EPS, 2 * EPS, F=1.0)
    ttT = np.clip(np.sum(u * tan, 1) / (2 * EPS), -1.0, 1.0)
    assert np.allclose(np.sum(fT(x, n, elem, t) * tan, 1), -ttT, rtol=1e-13, atol=0)
    with pytest.raises(ValueError, match="eps_n"):
        contact_traction(op, res.U, gap, 0.0, EPS, mu_f=MU_F)
    with pytest.raises(ValueError, match="gap"):
        contact_traction(op, res.U, -6e-4, EPS, EPS, mu_f=MU_F)


def test_consistency_weight():
    assert consistency_weight("literal", E, NU) == 1.0
    assert consistency_weight("balanced", E, NU, "strain") == pytest.approx(E / (1 - NU ** 2),
                                                                            rel=1e-14)
    assert consistency_weight("balanced", E, NU, "stress") == pytest.approx(E, rel=1e-14)
    with pytest.raises(ValueError, match="indicator variant"):
        consistency_weight("nonsense", E, NU)


def test_contact_indicators_weight_the_consistency_term(coarse):
    op, res, Psi = coarse
    gap = line_gap(6e-4)
    f = contact_traction(op, res.U, gap, EPS, EPS, mu_f=MU_F)
    _, parts = lame_bem_indicators(op, res.U, Psi, {"C": f}, return_parts=True)
    for w in (1.0, 1e3):
        eta = lame_contact_indicators(op, res.U, Psi, gap, EPS, EPS, mu_f=MU_F, weight=w)
        assert np.allclose(eta, np.hypot(parts["traction"], w * parts["consistency"]),
                           rtol=1e-13, atol=0)
    # the literal indicator is the traction term: the squared consistency term is ~1e-11
    # of the squared traction term
    assert parts["consistency"].max() < 1e-5 * parts["traction"].max()
    with pytest.raises(ValueError, match="weight"):
        lame_contact_indicators(op, res.U, Psi, gap, EPS, EPS, mu_f=MU_F, weight=0.0)


def test_norm_B(coarse):
    op, res, Psi = coarse
    U = res.U
    plain = np.sqrt(U @ op.W @ U + Psi @ op.V @ Psi)
    assert norm_B(op, U, Psi) == pytest.approx(plain, rel=1e-14)
    full = norm_B(op, U, Psi, EPS, EPS, res.weights, res.p_n, res.t_t)
    pen = EPS * res.weights @ res.p_n ** 2 + EPS * res.weights @ res.t_t ** 2
    assert full ** 2 == pytest.approx(plain ** 2 + pen, rel=1e-12)
    assert pen > 0


def test_true_error_embeds_exactly(coarse):
    """A coarse P1/P0 solution written on a refinement keeps its values: its error against
    itself embedded is zero, against a finer solution positive; the trace agrees at the
    fine nodes."""
    op, res, Psi = coarse
    fine_mesh = common_refinement(mesh_of(8), mesh_of(4).refine([0, 5]))
    assert fine_mesh.n_elements == 32          # the bisections are already in the 8-mesh
    fop, fres, fPsi = solve(fine_mesh)
    Uf = prolongate(op.V_space, res.U, fop.V_space, components=2)
    Pf = prolongate(op.W_space, Psi, fop.W_space, components=2)
    ref = op.V_space.evaluate_at(res.U.reshape(-1, 2), fine_mesh.a)
    ne = fine_mesh.n_elements
    got = fop.V_space.evaluate(Uf.reshape(-1, 2), np.arange(ne), np.full(ne, -1.0))
    assert np.allclose(got, ref, atol=1e-15)
    assert true_error(op, res.U, Psi, fop, Uf, Pf) == pytest.approx(0.0, abs=1e-12)
    assert true_error(fop, fres.U, fPsi, fop, fres.U, fPsi) == 0.0
    e = true_error(op, res.U, Psi, fop, fres.U, fPsi)
    assert e > 0.0
    with pytest.raises(ValueError, match="nested"):
        true_error(fop, fres.U, fPsi, LameBEM(mesh_of(3), E, NU), np.zeros(1), np.zeros(1))


def test_penalty_problem_is_positively_homogeneous_in_d():
    """U(d / 10) = U(d) / 10: the rigid-line penalty problem is positively homogeneous."""
    m = mesh_of(4)
    a = solve(m, 6e-4)[1]
    b = solve(m, 6e-5)[1]
    assert np.allclose(b.U, a.U / 10, rtol=1e-8, atol=1e-14)


def _adaptive(n_steps):
    gap = line_gap(6e-4)
    states = []

    def _solve(mesh):
        st = solve(mesh)
        states.append(st)
        return st, 2 * len(st[0].V_space.free_dofs())

    def _estimate(mesh, st):
        op, res, Psi = st
        return lame_contact_indicators(op, res.U, Psi, gap, EPS, EPS, mu_f=MU_F)

    return adapt(mesh_of(4), _solve, _estimate, n_steps=n_steps, theta=0.9), states


def test_adaptive_loop_is_deterministic_and_refines_symmetrically():
    """The first steps of a longer adaptive run equal a shorter run (the Fig. 3.6
    extension takes the thesis's run from the longer one); the rigid line below the
    symmetric body gives mirror-symmetric refinement."""
    short, _ = _adaptive(3)
    long_, states = _adaptive(4)
    for k in range(3):
        assert np.array_equal(short.meshes[k].nodes, long_.meshes[k].nodes)
        assert short.records[k]["eta"] == long_.records[k]["eta"]
    assert np.array_equal(short.marked[1], long_.marked[1])
    assert not short.marked[-1].any()
    assert long_.records[0]["ndof"] == 22           # the thesis's coarsest mesh
    for mesh, marked in zip(long_.meshes[:-1], long_.marked[:-1]):
        mid = 0.5 * (mesh.a + mesh.b)[marked]
        assert len(mid) > 0
        mir = mid * np.array([-1.0, 1.0])
        assert all(np.min(np.linalg.norm(mid - m, axis=1)) < 1e-9 for m in mir)
    # the refinement starts where the contact changes: on the bottom side or its corners
    assert all(states[0][0].mesh.labels[long_.marked[0]] == "C")
