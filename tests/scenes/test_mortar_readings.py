"""Readings of Algorithm 4.3 / Section 4.3 settled for Table 4.1 (issue 11 follow-up):
the mortar space M^1_hp of (4.49) as test space, the flat scene (Gamma_C straight, the arc
as initial gap), Coulomb friction inside DtN and the literal function transfer."""

import numpy as np
import pytest

from hpfebe.scenes import ModelProblem, model_gap, model_meshes, model_problem
from hpfebe.solvers import DtNSettings, UzawaSettings
from hpfebe.coupling.mortar import MortarProjection


@pytest.mark.parametrize("p1,p2,n1,n2", [(1, 1, 7, 5), (2, 2, 16, 12), (3, 2, 5, 9)])
def test_mortar_test_space(p1, p2, n1, n2):
    """(4.50) with M^1_hp of (4.49): polynomials of degree <= min(p1, p2) reproduced,
    end-point values matched, and the adjoint is the transpose."""
    m = MortarProjection(*model_meshes(n1, n2, p1, p2)[:2], test_space="mortar")
    s1, s2 = m.space1, m.space2
    for deg in range(min(p1, p2) + 1):
        coef = np.arange(1, deg + 2) * (-0.7) ** np.arange(deg + 1)
        f = lambda x: np.polyval(coef, x[:, 0])  # noqa: E731
        phi2, phi1 = s2.interpolate(f)[m.dofs2], s1.interpolate(f)[m.dofs1]
        assert np.max(np.abs(m.project(phi2) - phi1)) < 1e-11 * max(1, np.abs(phi1).max())
    rng = np.random.default_rng(1)
    phi2 = rng.standard_normal(m.dofs2.size)
    # end points of Gamma^1_C (x = -1, 1) take the values of Phi^2 at x = -1, 1
    ends = np.array([[-1.0, 0.1], [1.0, 0.1]])
    e1, t1 = m.mesh1.locate(ends)
    e2, t2 = m.mesh2.locate(np.array([[-1.0, 0.0], [1.0, 0.0]]))
    full1 = np.zeros(s1.ndof)
    full1[m.dofs1] = m.project(phi2)
    full2 = np.zeros(s2.ndof)
    full2[m.dofs2] = phi2
    assert np.allclose(s1.evaluate(full1, e1, t1), s2.evaluate(full2, e2, t2), atol=1e-12)
    r1 = rng.standard_normal(m.dofs1.size)
    assert abs(m.project(phi2) @ r1 - phi2 @ m.adjoint(r1)) < 1e-11 * np.abs(r1).sum()
    with pytest.raises(ValueError, match="test_space"):
        MortarProjection(*model_meshes(4, 3, 1, 1)[:2], test_space="dual")


def test_flat_scene_and_bad_input():
    m1, m2, normal = model_meshes(8, 6, 1, 1, geometry="flat")
    c = np.flatnonzero(m1.labels == "C")
    assert np.allclose(m1.a[c, 1], 0.0) and np.allclose(normal(m1.a[c]), [0.0, -1.0])
    g = model_gap()(np.array([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]]))
    assert np.allclose(g, [0.1, 0.0, 0.1])
    pr = model_problem(ModelProblem(4, 3, 1, 1, geometry="flat"))
    assert np.allclose(pr.gap, model_gap()(pr.points))
    m1, m2, _ = model_meshes(8, 6, 1, 1, side_depth=1.0)
    assert set(m2.labels) == {"C", "D", "N"}
    for kw, name in ((dict(geometry="curved"), "geometry"), (dict(side_depth=0.0), "side_depth")):
        with pytest.raises(ValueError, match=name):
            model_meshes(4, 3, 1, 1, **kw)
    with pytest.raises(ValueError, match="friction"):
        pr.dtn(DtNSettings(0.5, 0.5), friction="stick")
    with pytest.raises(ValueError, match="transfer"):
        DtNSettings(0.5, 0.5, transfer="dual")


def test_function_transfer_equals_functional_on_matching_meshes():
    """On identical flat contact meshes D = B = M2, so the literal function transfer
    M2 B^T D^-2 equals the functional one: both readings give the same DtN run."""
    pr = model_problem(ModelProblem(6, 6, 2, 2, geometry="flat"))
    m = pr.mortar
    B, D = m.B.toarray(), m.D.toarray()
    # B = D Pi with Pi a permutation (dofs1 vs dofs2 order), M2 = Pi^T D Pi = B^T D^-1 B
    assert np.allclose(B.T @ np.linalg.solve(D, B), m.M2.toarray(), atol=1e-13)
    a = pr.dtn(DtNSettings(0.5, 0.5))
    b = pr.dtn(DtNSettings(0.5, 0.5, transfer="function"))
    assert a.info.converged and b.info.converged
    assert a.info.iterations == b.info.iterations
    assert np.allclose(a.U2, b.U2, atol=1e-9 * np.abs(a.U2).max())


def test_coulomb_dtn_respects_the_friction_cone():
    pr = model_problem(ModelProblem(8, 6, 2, 1))
    sol = pr.dtn(DtNSettings(0.5, 0.5, tol=1e-8, uzawa=UzawaSettings(max_iter=20000)),
                 friction="coulomb")
    assert sol.info.converged, sol.info.reason
    rn, rt = pr.frame(pr.body1.reaction(pr.R.T @ sol.x))
    pn = np.maximum(0.0, -rn)
    assert pn.max() > 0
    assert np.all(np.abs(rt) <= pr.F * pn + 1e-5 * pr.F * pn.max())
    # friction acts (not frictionless): some node carries a tangential force
    assert np.abs(rt).max() > 1e-3 * pr.F * pn.max()


def test_model_problem_settings_and_exports():
    """ModelProblem validates its data (the error names the parameter); the contact
    state of a DtN solution at the constrained nodes of Gamma^1_C is consistent (p_n >=
    0, open nodes carry no pressure, the tangential traction of a sliding node is the
    Tresca bound F, the resultant balances the nodal tractions) and goes to ParaView
    with both bodies' boundaries."""
    from hpfebe.constitutive import OPEN, SLIP
    from hpfebe.scenes import mortar_contact_state
    from hpfebe.scenes.mortar import mortar_exports

    for bad, name in ((dict(n1=0), "n1"), (dict(F=-0.1), "F"), (dict(u_top=(0.0,)), "u_top")):
        with pytest.raises(ValueError, match=name):
            ModelProblem(**bad)
    pr = model_problem(ModelProblem(6, 4, 2, 1))
    sol = pr.dtn(DtNSettings(0.5, 0.7))
    assert sol.info.converged, sol.info.reason
    st = mortar_contact_state(pr, sol)
    assert np.all(np.isfinite(st.g_n)) and len(st.points) < pr.nc    # the ends unconstrained
    assert np.all(st.p_n >= 0) and np.all(st.p_n[st.state == OPEN] <= 1e-8 * st.p_n.max())
    slide = st.state == SLIP
    assert slide.any() and np.allclose(np.abs(st.t_t[slide]), pr.F, rtol=1e-6)
    assert np.all(st.slip[~slide] == 0)
    out = mortar_exports(pr, sol)
    assert sorted(out) == ["body1", "body2", "contact"]
    assert out["contact"].point_data["p_n"].shape == (len(st.points),)
    assert out["body1"].point_data["u"].shape[1] == 3
