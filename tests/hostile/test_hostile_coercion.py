"""Issue 25, class "coercion": numbers of any honest kind (np.float32, 0-d arrays) are
accepted and give the answer of the Python float, bit for bit; strings, bools and
non-integral counts are refused with an error naming the parameter and its value."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.adaptivity import adapt
from hpfebe.adaptivity.marking import mark_max
from hpfebe.bem.lame import LameBEM
from hpfebe.bem.laplace import LaplaceBEM
from hpfebe.constitutive.j2 import J2Material, J2State, return_map
from hpfebe.constitutive.materials import lame_constants
from hpfebe.contact.settings import ContactSettings

E, NU, SY, H = 266926.0, 0.29, 4.0, 450.0
SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


@pytest.mark.parametrize("field, value", [
    ("sigma_Y", np.float32(4)), ("sigma_Y", np.array(4.0)), ("E", np.array(E)),
    ("E", np.float64(E)), ("H", np.int64(450)), ("theta", np.float32(1.0))])
def test_numpy_numbers_give_the_float_answer(field, value):
    """J2Material(sigma_Y=np.float32(4)) and E=np.array(...) (0-d) are numbers: the
    return map equals that of the Python floats exactly (discrepancy 0)."""
    ref = J2Material(E, NU, SY, H, 1.0)
    got = J2Material(**{**dict(E=E, nu=NU, sigma_Y=SY, H=H, theta=1.0), field: value})
    assert type(getattr(got, field)) is float
    eps = np.random.default_rng(1).normal(scale=1e-4, size=(6, 3, 3))
    eps = 0.5 * (eps + np.swapaxes(eps, 1, 2))
    a, b = (return_map(m, eps, J2State.zeros(6)) for m in (ref, got))
    assert np.abs(a.sigma - b.sigma).max() == 0.0
    assert np.abs(a.tangent - b.tangent).max() == 0.0


@pytest.mark.parametrize("make, name", [
    (lambda: J2Material(E, NU, "4", H), "sigma_Y"),
    (lambda: J2Material(E, NU, True, H), "sigma_Y"),
    (lambda: J2Material(np.array([E, E]), NU, SY, H), "E"),
    (lambda: J2Material(E, NU, SY, np.nan), "H"),
    (lambda: J2Material(E, NU, SY, H, theta=1.5), "theta"),
    (lambda: lame_constants(E, "0.3"), "nu"),
    (lambda: lame_constants(E, NU, "strian"), "plane"),
    (lambda: ContactSettings(predictor="no"), "predictor"),
    (lambda: ContactSettings(line_search=1), "line_search"),
    (lambda: ContactSettings(max_cuts=1.5), "max_cuts"),
    (lambda: ContactSettings(max_iter="30"), "max_iter"),
    (lambda: ContactSettings(rtol="1e-8"), "rtol"),
    (lambda: ContactSettings(min_step=np.nan), "min_step"),
    (lambda: ContactSettings(norm="L2"), "norm"),
    (lambda: LameBEM(BoundaryMesh.polygon(SQUARE, n=1), "1", NU), "E"),
    (lambda: LameBEM(BoundaryMesh.polygon(SQUARE, n=1), E, NU, closed_form="no"),
     "closed_form"),
    (lambda: LaplaceBEM(BoundaryMesh.polygon(SQUARE, n=1), closed_form=0), "closed_form"),
    (lambda: mark_max(np.ones(3), theta=True), "theta"),
    (lambda: adapt(BoundaryMesh.polygon(SQUARE, n=1), None, None, n_steps="3"), "n_steps"),
    (lambda: adapt(BoundaryMesh.polygon(SQUARE, n=1), None, None, n_steps=2.5), "n_steps"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=2).refine([0.5]), "marked"),
])
def test_coercion_refused_naming_the_parameter(make, name):
    with pytest.raises(ValueError, match=rf"^{name}\b.*got") as err:
        make()
    assert "must" in str(err.value)


def test_settings_store_plain_python_values():
    s = ContactSettings(rtol=np.float32(1e-8), max_iter=np.int64(7), max_cuts=2.0,
                        predictor=np.bool_(True))
    assert (type(s.rtol), type(s.max_iter), type(s.max_cuts), type(s.predictor)) == \
        (float, int, int, bool)
    assert s.max_cuts == 2 and s.predictor is True


def _solver_settings():
    from hpfebe.contact.mortar_fe import NeumannSettings
    from hpfebe.solvers import (DtNSettings, GlobalUzawaSettings, SemismoothSettings,
                                UzawaSettings)
    return [lambda t: ContactSettings(rtol=t), lambda t: DtNSettings(0.5, 0.5, t),
            lambda t: UzawaSettings(tol=t), lambda t: UzawaSettings(cg_tol=t),
            lambda t: GlobalUzawaSettings(tol=t), lambda t: SemismoothSettings(tol=t),
            lambda t: NeumannSettings(t)]


@pytest.mark.parametrize("k", range(7))
@pytest.mark.parametrize("tol", [1.0, 2.0, 0.0, np.inf])
def test_relative_tolerances_lie_in_0_1(k, tol):
    """A relative tolerance >= 1 accepted a residual as large as the forces it is
    measured against: SemismoothSettings(tol=2) and FEMortarContact.monolithic(tol=2)
    reported "converged" on the mortar scenes.  Every stopping tolerance of Chapter 4
    is a real in (0, 1) (:func:`hpfebe.checks.tolerance`)."""
    with pytest.raises(ValueError, match=r"tol must be a finite real number in \(0, 1\)"):
        _solver_settings()[k](tol)


def test_dirichlet_data_and_dofs_are_numbers():
    from hpfebe.bodies.plastic_be import DirichletSolver, rectangle_work_piece
    from hpfebe.contact import MortarContact
    from hpfebe.scenes import model_meshes
    m1, m2, normal = model_meshes(4, 3, 1, 1)
    b1, b2 = LameBEM(m1, E, NU), LameBEM(m2, E, NU)
    for value, err in ((("1", 0.0), "InputTypeError"), ((np.nan, 0.0), "ValueError")):
        with pytest.raises(ValueError, match=r"dirichlet1 must be \(label, \(Ux, Uy\)\) "
                                             r"with finite real Ux, Uy") as info:
            MortarContact(b1, b2, ("D", value), ("D", (0.0, 0.0)), 0.1, normal=normal)
        assert type(info.value).__name__ == err
    be = rectangle_work_piece((0, 1, 0, 1), 2, 2, J2Material(E, NU, SY, H))
    with pytest.raises(ValueError, match=r"fixed must hold integers, got 1.5"):
        DirichletSolver(be, [0, 1.5], 0.0)          # was truncated to dof 1
    with pytest.raises(ValueError, match="values must be a scalar or one value per"):
        DirichletSolver(be, [0, 1], [0.0, 0.0, 0.0])
