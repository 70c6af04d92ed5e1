"""Hostile input to the mortar contact of Sections 4.3-4.4 (issue 25), one parametrised
test per class: coverage of Gamma^1_C by Gamma^2_C, orientation of the normals,
lift-off (separation computable), absolute stopping floors (a tiny lift), coercion of
the settings, wrong objects and vectors of the wrong length.  Every case gives the right
answer or a ValueError / TypeError naming the parameter and what is allowed."""

import numpy as np
import pytest

from hpfebe.bem.lame import LameBEM
from hpfebe.contact import MortarContact
from hpfebe.coupling.mortar import MortarProjection
from hpfebe.geometry import BoundaryMesh
from hpfebe.scenes import (ModelProblem, dtn_settings, model_meshes, model_problem,
                           section44_scene)
from hpfebe.scenes.materials import E, NU, PLANE
from hpfebe.solvers import (DtNSettings, GlobalUzawaSettings, SemismoothSettings,
                            UzawaSettings)


def _shifted(mesh, dx):
    return BoundaryMesh(mesh.nodes + [dx, 0.0], mesh.elements, mesh.labels, mesh.degrees)


@pytest.fixture(scope="module")
def coarse():
    return model_problem(ModelProblem(n1=4, n2=3, p1=1, p2=1))


# ------------------------------------------------------------------ coverage
@pytest.mark.parametrize("case", ["shift_0.5", "overhang_fe", "box_wider"])
def test_uncovered_contact_zone_refused(case):
    """Gamma^2_C must cover Gamma^1_C: a stamp shifted by 0.5 or overhanging the work
    piece gave an obstacle 9-47 % wrong at the uncovered nodes, 'converged'."""
    if case == "shift_0.5":
        m1, m2, normal = model_meshes(4, 3, 1, 1)
        with pytest.raises(ValueError, match=r"must cover Gamma\^1_C.*\[-1, -0.5\]"):
            MortarContact(LameBEM(m1, E, NU, PLANE), LameBEM(_shifted(m2, 0.5), E, NU,
                                                               PLANE),
                          ("D", (0.0, -0.09)), ("D", (0.0, 0.0)), 0.1, normal=normal)
    elif case == "overhang_fe":
        from hpfebe.contact.mortar_fe import FEMortarContact
        from hpfebe.constitutive.j2 import J2Material
        from hpfebe.fem import rectangle_mesh
        from hpfebe.fem.elasticity import ElasticBody
        from hpfebe.fem.plastic_body import ElastoPlasticFE
        stamp = ElasticBody(rectangle_mesh(1.5, 2.5, 0.0, 2.0, 4, 8), E, NU)
        work = ElastoPlasticFE(rectangle_mesh(-2, 2, -2, 0, 16, 8),
                               J2Material(E, NU, 4.0, 450.0, 1.0), "full")
        with pytest.raises(ValueError, match=r"stamp, work: .*\[2, 2.5\] of Gamma\^1_C"):
            FEMortarContact(stamp, work, ("top", (0.0, 0.0)), ("bottom", (0.0, 1e-4)), 0.2)
    else:
        m1, m2, _ = model_meshes(4, 3, 1, 1)
        # the longer side as the mortar side: refused, the shorter one is accepted
        with pytest.raises(ValueError, match="mortar side must be the shorter"):
            MortarProjection(_shifted(m2, 0.0), _narrow(m1))
        MortarProjection(_narrow(m1), m2)


def _narrow(mesh):
    """The arc body with its contact zone cut to |x| <= 0.5 (the rest relabelled)."""
    mid = 0.5 * (mesh.a + mesh.b)[:, 0]
    labels = np.where((mesh.labels == "C") & (np.abs(mid) > 0.5), "N", mesh.labels)
    return BoundaryMesh(mesh.nodes, mesh.elements, labels, mesh.degrees)


# ------------------------------------------------------------------ orientation
@pytest.mark.parametrize("normal,match", [
    (lambda x: -np.tile([0.0, -1.0], (len(x), 1)), "outward normal of body 1"),
    (lambda x: np.zeros((len(x), 2)), "nonzero"),
    (lambda x: np.full((len(x), 2), np.nan), "finite"),
    (lambda x: np.ones(len(x)), r"shape \(5, 2\)"),
    ("down", "callable"),
])
def test_bad_normals_refused(normal, match):
    """Inward normals converged with 0.09 of penetration; zero / NaN normals failed
    inside numpy."""
    m1, m2, _ = model_meshes(4, 3, 1, 1)
    with pytest.raises(ValueError, match=match):
        MortarContact(LameBEM(m1, E, NU, PLANE), LameBEM(m2, E, NU, PLANE),
                      ("D", (0.0, -0.09)), ("D", (0.0, 0.0)), 0.1, normal=normal)


# ------------------------------------------------------------------ lift-off
@pytest.fixture(scope="module")
def pulled():
    """The Section 4.4 scene (small) with the work piece pulled away from the stamp."""
    return section44_scene((4, 8), (16, 8), lift=-1e-4, formulation="full")


@pytest.mark.parametrize("how", ["frictionless", "relative_rho", "absolute_rho"])
def test_lift_off_is_computable(pulled, how):
    """A stamp pulled away: P = 0 is the solution (the monolithic answer); DtN called it
    'no solution'.  With Section 4.4's absolute rho (above rho_crit of a stamp out of
    contact) Uzawa diverges: the reason names rho_crit."""
    mono = pulled.monolithic()
    assert mono.info.converged and np.abs(mono.P).max() == 0.0, mono.info.reason
    if how == "absolute_rho":
        sol = pulled.dtn(dtn_settings(0.5, 0.7))
        assert not sol.info.converged and "rho_crit" in sol.info.reason
        return
    sol = pulled.dtn(dtn_settings(0.5, 0.7), F=0.0) if how == "frictionless" else \
        pulled.dtn(DtNSettings(0.5, 0.7, relaxation="convex"))
    assert sol.info.converged, sol.info.reason
    # P = 0 up to the round-off of the rigid motion's forces (E x 1e-4 x eps x 1e3)
    assert np.abs(sol.P).max() <= 1e3 * np.finfo(float).eps * E * 1e-4
    assert sol.info.backward_error <= 1e-12


# ------------------------------------------------------------------ floors
@pytest.mark.parametrize("solver", ["monolithic", "dtn"])
def test_tiny_lift_scales_linearly(solver):
    """An elastic frictionless scene: P(1e-14) = 1e-2 P(1e-12) (the Newton floor
    tol x force_floor accepted the rigid start at lift 1e-14: P = 0, converged).  Bound:
    the solver tolerance (monolithic 1e-10; DtN TOL 1e-10 over 1 - contraction)."""
    def run(lift):
        sc = section44_scene((4, 8), (16, 8), sigma_Y=4e12, F=0.0, lift=lift,
                             formulation="full")
        sol = sc.monolithic() if solver == "monolithic" else \
            sc.dtn(dtn_settings(0.5, 0.7, tol=1e-10))
        assert sol.info.converged, sol.info.reason
        return sol.P / lift, sol
    a, _ = run(1e-12)
    b, sol = run(1e-14)
    bound = 1e-8 if solver == "monolithic" else \
        1e-10 / (1 - max(r1 / r0 for r0, r1 in zip(sol.info.residuals[-4:-1],
                                                     sol.info.residuals[-3:])))
    assert np.abs(a).max() > 0
    assert np.abs(a - b).max() <= bound * np.abs(a).max()


# ------------------------------------------------------------------ coercion
@pytest.mark.parametrize("make,match,kind", [
    (lambda: DtNSettings(True, 0.5), "omega_D", TypeError),
    (lambda: DtNSettings("0.5", 0.5), "omega_D", TypeError),
    (lambda: DtNSettings(0.5, 0.5, max_iter="200"), "max_iter", TypeError),
    (lambda: DtNSettings(0.5, 0.5, max_iter=1.5), "max_iter", ValueError),
    (lambda: DtNSettings(0.5, 0.5, aitken="no"), "aitken", TypeError),
    (lambda: DtNSettings(0.5, 0.5, uzawa=1.0), "uzawa", TypeError),
    (lambda: UzawaSettings(relative="no"), "relative", TypeError),
    (lambda: UzawaSettings(max_iter=True), "max_iter", TypeError),
    (lambda: GlobalUzawaSettings(mu_f="0.1"), "mu_f", TypeError),
    (lambda: GlobalUzawaSettings(mu_f=np.nan), "mu_f", ValueError),
    (lambda: SemismoothSettings(max_iter="100"), "max_iter", TypeError),
    (lambda: SemismoothSettings(friction="Coulomb "), "friction", ValueError),
    (lambda: dtn_settings(0.5, 0.5, rho="8e5"), "rho", TypeError),
    (lambda: model_problem(ModelProblem(n1=4, n2=3, p1=1, p2=1, F="0.1")), "F", TypeError),
    (lambda: model_problem(ModelProblem(n1=4.5)), "n1", ValueError),
    (lambda: model_problem(ModelProblem(n1=4, n2=3, p1=1, p2=1, u_top=(0.0, "x"))),
     "u_top", TypeError),
    (lambda: section44_scene((4, 8), (16, 8), lift="1e-4"), "lift", TypeError),
])
def test_coercion_refused(make, match, kind):
    """dtn(omega_D=True) was taken as 1.0; strings failed inside numpy with messages
    that did not name the parameter."""
    with pytest.raises(kind, match=match):
        make()


def test_numpy_numbers_accepted():
    s = DtNSettings(np.float32(0.5), np.float64(0.7), max_iter=np.int64(30))
    assert (s.omega_D, s.max_iter) == (0.5, 30) and type(s.omega_D) is float


# ------------------------------------------------------------------ wrong objects
@pytest.mark.parametrize("case", ["Q_length", "lam0_length", "bound_negative",
                                  "laplace_body", "dtn_F_string"])
def test_wrong_objects_refused(coarse, case):
    """A traction of the wrong length to uzawa failed in a reshape; a LaplaceBEM where a
    Lame body is expected with an IndexError."""
    pr = coarse
    if case == "Q_length":
        with pytest.raises(ValueError, match=rf"Q must have shape \({2 * pr.nc},\)"):
            pr.uzawa(np.zeros(pr.c2.size))          # a traction on body 2's dofs
    elif case == "lam0_length":
        with pytest.raises(ValueError, match="lam0"):
            pr.uzawa(np.zeros(2 * pr.nc), lam0=np.zeros(pr.nc + 1))
    elif case == "bound_negative":
        with pytest.raises(ValueError, match="bound"):
            pr.uzawa(np.zeros(2 * pr.nc), bound=-np.ones(pr.nc))
    elif case == "laplace_body":
        from hpfebe.bem import LaplaceBEM
        m1, m2, normal = model_meshes(4, 3, 1, 1)
        with pytest.raises(TypeError, match="bem2 must be a LameBEM"):
            MortarContact(LameBEM(m1, E, NU, PLANE), LaplaceBEM(m2), ("D", (0.0, -0.09)),
                          ("D", (0.0, 0.0)), 0.1, normal=normal)
    else:
        sc = section44_scene((4, 8), (16, 8), formulation="full")
        with pytest.raises(TypeError, match="F must"):
            sc.dtn(dtn_settings(0.5, 0.7), F="0")


@pytest.mark.parametrize("case", ["gap_scalar", "gap_nan", "lam0_nan", "settings_none",
                                  "global_settings", "dtn_settings", "frame_length"])
def test_more_wrong_objects_named(coarse, case):
    """A constant gap given as a float failed with "'float' object is not callable", a
    NaN lam0 was named x0 (the CG's start), settings=None raised an AttributeError and
    a vector of the wrong length to frame a reshape error: each now names its
    parameter."""
    pr = coarse
    m1, m2, normal = model_meshes(4, 3, 1, 1)
    b1, b2 = LameBEM(m1, E, NU, PLANE), LameBEM(m2, E, NU, PLANE)
    data = (("D", (0.0, -0.09)), ("D", (0.0, 0.0)), 0.1)
    cases = {
        "gap_scalar": (lambda: MortarContact(b1, b2, *data, normal=normal, gap=0.0),
                       "gap must be a callable, got 0.0"),
        "gap_nan": (lambda: MortarContact(b1, b2, *data, normal=normal,
                                          gap=lambda x: np.full(len(x), np.nan)),
                    r"gap\(x\) must be finite, got nan"),
        "lam0_nan": (lambda: pr.uzawa(np.zeros(2 * pr.nc), lam0=np.full(pr.nc, np.nan)),
                     "lam0 must be finite"),
        "settings_none": (lambda: pr.semismooth_newton(None),
                          "settings must be a SemismoothSettings"),
        "global_settings": (lambda: pr.global_uzawa(UzawaSettings()),
                            "settings must be a GlobalUzawaSettings"),
        "dtn_settings": (lambda: pr.dtn(UzawaSettings()), "settings must be a DtNSettings"),
        "frame_length": (lambda: pr.frame(np.zeros(3)),
                         rf"v must be {2 * pr.nc} numbers .* got \(3,\)")}
    make, match = cases[case]
    with pytest.raises(ValueError, match=match):
        make()
