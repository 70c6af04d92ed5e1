"""The one ContactSettings of Algorithm 4.1 (hpfebe.contact.ContactSettings): frozen,
validated, the keywords of Newton it makes, and TwoBodyContact.solve taking it."""

import dataclasses

import numpy as np
import pytest

from hpfebe.contact import ContactSettings
from hpfebe.scenes import STAMP_SOLVER, StampContact


def test_defaults_and_newton_options():
    s = ContactSettings()
    kw = s.newton_options()
    assert kw["tol"] == 1e-10 and kw["atol"] == 0.0 and kw["max_iter"] == 30
    assert kw["norm"] == 2 and not kw["roundoff_stop"] and not kw["line_search"].enabled
    ls = ContactSettings(line_search=True, min_step=2.0 ** -5).line_search_rule()
    assert ls.enabled and ls.accept_last and ls.max_halvings == 5 and ls.slack == 0.0
    ls = ContactSettings(line_search=True, merit="energy").line_search_rule()
    assert ls.max_halvings == 30 and not ls.accept_last
    assert ContactSettings().line_search_rule().refine == 0
    assert ContactSettings(line_search=True, ls_refine=3).line_search_rule().refine == 3
    assert ContactSettings(norm="max").newton_options()["norm"] == np.inf
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.rtol = 1.0


@pytest.mark.parametrize("kw, name", [
    (dict(rtol=-1.0), "rtol"), (dict(atol=np.nan), "atol"), (dict(rtol=0.0), "rtol"),
    (dict(max_iter=0), "max_iter"), (dict(max_iter=2.5), "max_iter"),
    (dict(max_cuts=-1), "max_cuts"), (dict(min_step=0.0), "min_step"),
    (dict(norm="l1"), "norm"), (dict(merit="work"), "merit"),
    (dict(lu_ordering="AMD"), "lu_ordering"), (dict(linear_solver="cg"), "linear_solver"),
    (dict(line_search=1), "line_search"), (dict(predictor="yes"), "predictor"),
    (dict(ls_refine=-1), "ls_refine"), (dict(ls_refine=0.5), "ls_refine")])
def test_wrong_settings_are_named(kw, name):
    with pytest.raises(ValueError, match=name):
        ContactSettings(**kw)


def test_stamp_contact_carries_the_solver():
    s = StampContact()
    assert s.solver is STAMP_SOLVER and s.solver.line_search and s.solver.predictor
    assert (s.solver.rtol, s.solver.max_iter, s.solver.max_cuts) == (1e-8, 40, 4)
    with pytest.raises(ValueError, match="solver"):
        StampContact(solver=dict(rtol=1e-8))


def _pressed_blocks(scale: float):
    """Two FE blocks in Coulomb contact (mu_f = 0.3), the upper pressed by a traction
    and sheared by a prescribed displacement of its top (12 points stick, 4 slip; 2
    Newton iterations per step); E and the traction times ``scale`` (the same
    displacements, all forces times ``scale``)."""
    from hpfebe.contact import TwoBodyContact
    from hpfebe.fem import ElasticBody, rectangle_mesh
    E = 266926.0 * scale
    up = ElasticBody(rectangle_mesh(0, 2, 0, 1, 4, 3), E, 0.29)
    lo = ElasticBody(rectangle_mesh(0, 2, -1, 0, 5, 3), E, 0.29)
    pr = TwoBodyContact(up, lo, "bottom", "top", eps_n=1 / (10 * E), eps_t=1 / (10 * E),
                        mu_f=0.3)
    f = pr.traction_load("slave", "top", (0.0, -100.0 * scale))
    top = pr.dofs_on("slave", "top", 0)
    fixed = np.concatenate([pr.dofs_on("master", "bottom"), top])
    vals = np.concatenate([np.zeros(fixed.size - top.size), np.full(top.size, 1e-3)])
    return pr, f, fixed, vals


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_stopping_rule_is_scale_free(scale):
    """E and loads times 1e6 or 1e-6: the same Newton iterations, the same state and the
    same displacement (to the stopping tolerance); with a floor atol = rtol x (half the
    data force) scaled with the problem, the same again.  A constant floor set for one
    scale is refused at the other instead of accepting the start (``atol`` named).
    Measured: 2 + 2 iterations at every scale, displacements equal to 3.3e-15 (x 1e6)
    and 2.6e-15 (x 1e-6)."""
    from hpfebe.contact.loading import LoadSteps
    from hpfebe.contact.two_body import data_force
    runs = {}
    for s in (1.0, scale):
        pr, f, fixed, vals = _pressed_blocks(s)
        force = data_force(LoadSteps(pr, f, fixed, vals, ContactSettings()))
        for name, atol in (("relative", 0.0), ("floor", 0.5 * 1e-10 * force)):
            res = pr.solve(f, fixed, vals, load_factors=[0.5, 1.0],
                           settings=ContactSettings(atol=atol))
            assert res.converged, res.reason
            runs[s, name] = (res, force)
    ref = runs[1.0, "relative"][0]
    assert max(ref.iterations) >= 2 and {1, 2} <= set(np.unique(ref.state))  # stick, slip
    for name in ("relative", "floor"):
        (a, fa), (b, fb) = runs[1.0, name], runs[scale, name]
        assert np.isclose(fb / fa, scale, rtol=1e-12)
        assert a.iterations == b.iterations and np.array_equal(a.state, b.state)
        assert np.abs(a.U - b.U).max() <= 1e-8 * np.abs(a.U).max()
    pr, f, fixed, vals = _pressed_blocks(1.0)
    floor = 0.5 * 1e-10 * runs[max(1.0, scale), "floor"][1]     # fine at the larger scale
    if scale < 1:
        pr, f, fixed, vals = _pressed_blocks(scale)                 # too large here
    with pytest.raises(ValueError, match=r"atol must be at most rtol x the data force"):
        pr.solve(f, fixed, vals, settings=ContactSettings(atol=floor))
