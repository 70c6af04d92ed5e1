"""Issue 10, contact solvers: no wrong answer without an error, and errors that name the
real cause (tolerances, NaN loads, operator types, scalar gap callables, extreme eps)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LaplaceBEM
from hpfebe.bem.lame import LameBEM
from hpfebe.contact import FrictionSettings, solve_friction, solve_penalty

E, NU, D = 266926.0, 0.29, 2e-4


@pytest.fixture(scope="module")
def body():
    mesh = BoundaryMesh.polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)], n=4, p=1,
                                labels=["C", "N", "D", "N"])
    return LameBEM(mesh, E, NU)


@pytest.mark.parametrize("tol", [-1.0, np.nan, 0.0, "1e-8"])
def test_penalty_tolerance_checked(body, tol):
    with pytest.raises(ValueError, match="tol"):
        solve_penalty(body, 1e-5, -D, tol=tol)


def test_nan_load_named_as_such(body):
    load = np.zeros(2 * body.V_space.ndof)
    load[3] = np.nan
    for solve in (lambda: solve_penalty(body, 1e-5, -D, load=load),
                  lambda: solve_friction(body, -D, FrictionSettings(
                                      1e-5, 1e-5, "coulomb", mu_f=0.3), load=load)):
        with pytest.raises(ValueError, match="load must be finite"):
            solve()


def test_laplace_operator_refused(body):
    lap = LaplaceBEM(body.mesh)
    with pytest.raises(ValueError, match="LameBEM"):
        solve_penalty(lap, 1e-5, -D)
    with pytest.raises(ValueError, match="LameBEM"):
        solve_friction(lap, -D, FrictionSettings(1e-5, 1e-5, "tresca", F=1.0))


def test_wrong_S_shape_named(body):
    with pytest.raises(ValueError, match="S must have shape"):
        solve_penalty(body, 1e-5, -D, S=np.eye(3))


def test_scalar_gap_callable_is_refused(body):
    """Issue 25: a gap callable must return one value per point (a scalar may be a
    constant or ``norm(x) - 1`` of all points at once); a constant gap is a float."""
    for solve in (lambda: solve_penalty(body, 1e-5, lambda x: -D),
                  lambda: solve_friction(body, lambda x: -D, FrictionSettings(
                                      1e-5, 1e-5, "coulomb", mu_f=0.3))):
        with pytest.raises(ValueError, match=r"gap\(x\) must have shape \(\d+,\)"):
            solve()


def test_extreme_eps_is_not_reported_as_converged(body):
    """eps = 1e-20 h: the contact force cannot balance S_hat U to six digits; Newton
    stops at round-off and the solver says so (it used to return converged=True with
    pressures off by a factor ~2 and more)."""
    ref = solve_penalty(body, 1e-8 * 0.5, -D)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = solve_penalty(body, 1e-20 * 0.5, -D)
    assert ref.converged
    assert not res.converged and "ill-conditioned" in res.reason, res.reason
    assert res.info.backward_error > 1e-6


def test_friction_at_extreme_eps_names_ill_conditioning(body):
    """Coulomb friction with eps = 1e-20 on a fixed body used to end with "singular
    Newton matrix (body not fixed?)": the body is fixed; the cause is conditioning."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = solve_friction(body, -D, FrictionSettings(1e-20, 1e-20, "coulomb", mu_f=0.3))
    assert not res.converged
    assert "ill-conditioned" in res.reason and "not fixed" not in res.reason, res.reason
