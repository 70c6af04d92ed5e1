"""Hostile input to the stamping scenes, the two-body penalty contact and the solvers
(issue 25), one parametrised test per class: absolute stopping floors, coercion, NaN,
wrong objects.  Every refusal is a ValueError / TypeError naming the parameter."""

import math

import numpy as np
import pytest

from hpfebe import TwoBodyContact
from hpfebe.bem.lame import LameBEM
from hpfebe.constitutive.j2 import J2Material
from hpfebe.contact import ContactSettings
from hpfebe.fem import ElasticBody, rectangle_mesh
from hpfebe.scenes import (StampContact, be_work_piece, lift_schedule, stamp_body, touch,
                           touch_be, work_piece)
from hpfebe.scenes.adaptive_fefe import FEFEContactScene
from hpfebe.scenes.plasticity import StampingScene
from hpfebe.solvers import fixed_point, load_path, newton

E, NU = 266926.0, 0.29
WORK = (-2.0, 2.0, -3.0, -1.0)
STAMP = (-1.0, 1.0, -1.0, 0.0)
X = (1.0, -1.1)
MAT = J2Material(E, NU, 4.0, 450.0, 1.0)
ELASTIC = J2Material(E, NU, 1e30, 450.0, 1.0)


def _fe_touch(u, n_load=1, **kw):
    fe = work_piece(WORK, 1.0, kw.pop("material", ELASTIC))
    args = dict(stamp=stamp_body("FE", STAMP, 1.0, E, NU), fe=fe, u_total=u,
                n_load=n_load, n_unload=0, X=X, settings=StampContact(mu_f=0.0))
    args.update(kw)
    return touch(**args)


# ------------------------------------------------------------------ absolute floors
@pytest.mark.parametrize("u", [4.2e-12, 4.2e-14, -4.2e-12])
def test_floor_never_accepts_the_start_of_a_tiny_lift(u):
    """Issue 25: an elastic frictionless stamp pressed by 4.2e-12 'converged' after 0
    Newton iterations with a force 14.7 x the linear one (the floor rtol sigma_Y width
    was above every force of the scene).  Now the floor scales with the lift: the force
    is linear in u to the six digits of BACKWARD_TOL (measured 1e-15), and a pull
    (u < 0: the stamp lifts off) gives no force."""
    ref = _fe_touch(4.2e-3)
    tr = _fe_touch(u)
    assert tr.converged, tr.reason
    f, fref = tr.records[-1].force, ref.records[-1].force
    if u > 0:
        assert tr.records[0].iterations >= 1
        assert abs(f / u - fref / 4.2e-3) <= 1e-6 * abs(fref / 4.2e-3)
    else:
        assert abs(f) <= 1e-6 * abs(fref / 4.2e-3 * u)


# ------------------------------------------------------------------ coercion
def _stamp(**kw):
    args = dict(kind="FE", box=STAMP, h=1.0, E=E, nu=NU)
    args.update(kw)
    return stamp_body(**args)


COERCION = [
    ("box", lambda: _stamp(kind="BE", box=(1.0, -1.0, -1.0, 0.0))),   # was: labels swapped
    ("box", lambda: _stamp(kind="FE", box=(1.0, -1.0, -1.0, 0.0))),
    ("box", lambda: _stamp(box=(-1.0, 1.0, 0.0))),
    ("box", lambda: _stamp(box="0 1 0 1")),
    ("h", lambda: _stamp(h="0.5")),
    ("p", lambda: _stamp(kind="BE", p=1.5)),
    ("kind", lambda: _stamp(kind="fe")),
    ("mesh_kind", lambda: _stamp(mesh_kind="hex")),
    ("u_total", lambda: lift_schedule("4e-3", 2, 0)),
    ("n_load", lambda: lift_schedule(4e-3, 1.5, 0)),
    ("n_unload", lambda: lift_schedule(4e-3, 2, True)),
    ("u_total", lambda: _fe_touch("4.2e-3")),
    ("touch_id", lambda: _fe_touch(4.2e-3, touch_id=0)),
    ("two_pass", lambda: StampContact(two_pass="no")),
    ("mu_f", lambda: StampContact(mu_f="0.2")),
    ("F", lambda: StampContact(F=True)),
    ("F", lambda: StampContact(F="1")),
    ("eps_n_factor", lambda: StampContact(eps_n_factor=0)),
    ("predictor", lambda: StampingScene(predictor="no")),
    ("max_cuts", lambda: StampingScene(max_cuts=1.5)),
    ("n_load", lambda: StampingScene(n_load=2.5)),
    ("rtol", lambda: StampingScene(rtol="1e-8")),
    ("u_master", lambda: FEFEContactScene(u_master="5e-4")),
    ("slave_cells", lambda: FEFEContactScene(slave_cells=(4.5, 8))),
    ("split", lambda: _pair(split="no")),
    ("nq", lambda: _pair(nq=1.5)),
    ("mu_f", lambda: _pair(mu_f="0.1")),
    ("fixed_dofs", lambda: _pair().solve(None, [0.5, 1.5])),
    ("fixed_values", lambda: _pair().solve(None, [0, 1], "abc")),
    ("load.factors", lambda: _pair().solve(None, [0, 1], 0.0, load_factors=[0.5, 0.5])),
    ("max_iter", lambda: newton(None, np.zeros(1), 1e-8, max_iter=2.5)),
    ("tol", lambda: newton(None, np.zeros(1), "1e-8")),
    ("max_cuts", lambda: load_path(None, [1.0], np.zeros(1), max_cuts=1.5)),
    ("max_iter", lambda: fixed_point(lambda x: x, np.zeros(1), 1e-8, max_iter=1.5)),
]


def _pair(**kw):
    up = ElasticBody(rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2), E, NU)
    lo = ElasticBody(rectangle_mesh(0.0, 1.0, -1.0, 0.0, 2, 2), E, NU)
    return TwoBodyContact(up, lo, "bottom", "top", eps_n=1e-6, **kw)


@pytest.mark.parametrize("name, call", COERCION, ids=[f"{n}-{i}" for i, (n, _) in
                                                      enumerate(COERCION)])
def test_coercion_is_refused_naming_the_parameter(name, call):
    with pytest.raises((ValueError, TypeError), match=name):
        call()


# ------------------------------------------------------------------ NaN
NAN = [
    ("u_total", lambda: lift_schedule(math.nan, 2, 0)),
    ("u_total", lambda: _fe_touch(math.inf)),
    ("X", lambda: _fe_touch(4.2e-3, X=(math.nan, -1.1))),
    ("h", lambda: _stamp(h=math.nan)),
    ("box", lambda: _stamp(box=(-1.0, math.nan, -1.0, 0.0))),
    ("offset", lambda: _fe_touch(4.2e-3, offset=np.full(2 * 10, math.nan))),
    ("mu_f", lambda: StampContact(mu_f=math.nan)),
    ("F", lambda: StampContact(F=math.inf)),
    ("fixed_values", lambda: _pair().solve(None, [0, 1], [math.nan, 0.0])),
    ("x0", lambda: newton(None, np.array([math.nan]), 1e-8)),
    ("load factors", lambda: load_path(None, [math.nan], np.zeros(1))),
]


@pytest.mark.parametrize("name, call", NAN, ids=[f"{n}-{i}" for i, (n, _) in
                                                 enumerate(NAN)])
def test_nan_is_refused_naming_the_parameter(name, call):
    with pytest.raises(ValueError, match=name):
        call()


# ------------------------------------------------------------------ wrong objects
def _lame():
    return stamp_body("BE", STAMP, 1.0, E, NU)


WRONG = [
    ("fe", lambda: touch(_lame(), _lame(), 4.2e-3, 1, 0, X, StampContact())),
    ("be", lambda: touch_be(_lame(), work_piece(WORK, 1.0, MAT), 4.2e-3, 1, X,
                            StampContact())),
    ("stamp", lambda: touch("FE", work_piece(WORK, 1.0, MAT), 4.2e-3, 1, 0, X,
                            StampContact())),
    ("stamp", lambda: touch_be(work_piece(WORK, 1.0, MAT), be_work_piece(WORK, 2.0, MAT),
                               4.2e-3, 1, X, StampContact())),
    ("settings", lambda: _fe_touch(4.2e-3, settings=ContactSettings())),
    ("solver", lambda: StampContact(solver={"rtol": 1e-8})),
    ("material", lambda: work_piece(WORK, 1.0, {"E": E})),
    ("settings", lambda: _pair().solve(settings={"rtol": 1e-8})),
    ("update", lambda: fixed_point(None, np.zeros(1), 1e-8)),
]


@pytest.mark.parametrize("name, call", WRONG, ids=[f"{n}-{i}" for i, (n, _) in
                                                   enumerate(WRONG)])
def test_wrong_objects_are_refused_naming_the_parameter(name, call):
    with pytest.raises((ValueError, TypeError), match=name):
        call()


def test_be_stamp_box_keeps_its_labels():
    """stamp_body('BE', ...) of a valid box: 'bottom' is the side at y0, as for FE."""
    b = _lame()
    assert isinstance(b, LameBEM)
    mid = 0.5 * (b.mesh.a + b.mesh.b)
    assert np.allclose(mid[b.mesh.where("bottom"), 1], STAMP[2])
    assert np.allclose(mid[b.mesh.where("top"), 1], STAMP[3])
