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
    assert ContactSettings(norm="max").newton_options()["norm"] == np.inf
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.rtol = 1.0


@pytest.mark.parametrize("kw, name", [
    (dict(rtol=-1.0), "rtol"), (dict(atol=np.nan), "atol"), (dict(rtol=0.0), "rtol"),
    (dict(max_iter=0), "max_iter"), (dict(max_iter=2.5), "max_iter"),
    (dict(max_cuts=-1), "max_cuts"), (dict(min_step=0.0), "min_step"),
    (dict(norm="l1"), "norm"), (dict(merit="work"), "merit"),
    (dict(lu_ordering="AMD"), "lu_ordering"), (dict(linear_solver="cg"), "linear_solver"),
    (dict(line_search=1), "line_search"), (dict(predictor="yes"), "predictor")])
def test_wrong_settings_are_named(kw, name):
    with pytest.raises(ValueError, match=name):
        ContactSettings(**kw)


def test_stamp_contact_carries_the_solver():
    s = StampContact()
    assert s.solver is STAMP_SOLVER and s.solver.line_search and s.solver.predictor
    assert (s.solver.rtol, s.solver.max_iter, s.solver.max_cuts) == (1e-8, 40, 4)
    with pytest.raises(ValueError, match="solver"):
        StampContact(solver=dict(rtol=1e-8))
