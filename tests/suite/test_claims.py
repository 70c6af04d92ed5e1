"""Claim and rate helpers: hpfebe.suite.claims.{rate,beats_uniform,range}_claim,
hpfebe.analysis.rates.{loglog_interpolate,fitted_rate,observed_rates},
hpfebe.analysis.norms.energy_norm."""

import math

import numpy as np
import pytest
import scipy.sparse as sp

from hpfebe.analysis.norms import energy_norm
from hpfebe.analysis.rates import fitted_rate, loglog_interpolate, observed_rates
from hpfebe.suite.claims import (Claim, beats_uniform_claim, joint_claim, range_claim,
                                 rate_claim)

DOF = np.array([10.0, 40.0, 160.0, 640.0])
ERR = 3.0 * DOF ** -0.5


# ------------------------------------------------------------------ rates
def test_loglog_interpolate_exact_on_power_laws():
    for x in (10.0, 25.0, 100.0, 640.0):
        assert loglog_interpolate(x, DOF, ERR) == pytest.approx(3.0 * x ** -0.5, rel=1e-13)
    # unsorted data give the same curve
    assert loglog_interpolate(25.0, DOF[::-1], ERR[::-1]) == loglog_interpolate(25.0, DOF, ERR)


@pytest.mark.parametrize("x, xs, ys, match", [
    (5.0, DOF, ERR, "outside"), (700.0, DOF, ERR, "outside"),
    (20.0, DOF, -ERR, "ys"), (20.0, [0.0, 1.0, 2.0, 40.0], ERR, "xs"),
    (-1.0, DOF, ERR, "x must"), (20.0, DOF, ERR[:3], "equal length"),
    (20.0, [10.0, 10.0, 40.0, 160.0], ERR, "distinct")])
def test_loglog_interpolate_rejects(x, xs, ys, match):
    with pytest.raises(ValueError, match=match):
        loglog_interpolate(x, xs, ys)


def test_fitted_rate():
    assert fitted_rate(DOF, ERR) == pytest.approx(-0.5, abs=1e-13)
    y = ERR.copy()
    y[0] *= 10.0  # pre-asymptotic first point: only the last ones count
    assert fitted_rate(DOF, y, last=3) == pytest.approx(-0.5, abs=1e-13)
    assert fitted_rate(DOF, y) < -0.5
    with pytest.raises(ValueError, match="last"):
        fitted_rate(DOF, ERR, last=1)
    with pytest.raises(ValueError, match="at least 2"):
        fitted_rate(DOF[:1], ERR[:1])
    with pytest.raises(ValueError, match="y must"):
        fitted_rate(DOF, -ERR)


def test_observed_rates_in_h_and_in_inverse_h():
    h = 1.0 / np.array([2.0, 4.0, 8.0])
    r = observed_rates(h, h ** 2)
    assert math.isnan(r[0]) and np.allclose(r[1:], 2.0)


# ------------------------------------------------------------------ energy norm
def test_energy_norm_dense_sparse_and_roundoff():
    S = np.array([[2.0, -1.0], [-1.0, 2.0]])
    U = np.array([1.0, 2.0])
    assert energy_norm(S, U) == pytest.approx(math.sqrt(6.0))
    assert energy_norm(sp.csr_matrix(S), U) == pytest.approx(math.sqrt(6.0))
    assert energy_norm(-1e-30 * np.eye(2), U) == 0.0  # slightly negative -> 0
    with pytest.raises(ValueError, match="S must"):
        energy_norm(np.eye(3), U)


# ------------------------------------------------------------------ claims
def test_rate_claim():
    c = rate_claim("rate ~1", 0.93, 1.0, 0.1)
    assert isinstance(c, Claim) and c.holds is True and c.text == "rate ~1"
    assert "0.930" in c.evidence and "1" in c.evidence
    assert rate_claim("rate ~1", 0.85, 1.0, 0.1, what="H1 rate").holds is False
    assert "H1 rate" in rate_claim("x", 0.85, 1.0, 0.1, what="H1 rate").evidence
    assert rate_claim("nan", float("nan"), 1.0, 0.1).holds is False
    with pytest.raises(ValueError, match="tol"):
        rate_claim("x", 1.0, 1.0, -0.1)


def test_beats_uniform_claim():
    dof_a, err_a = [10, 50, 100], [0.9, 0.3, 0.2]
    c = beats_uniform_claim("adaptive wins", dof_a, err_a, DOF, ERR)
    e_u = 3.0 * 100 ** -0.5  # 0.3
    assert c.holds is True and f"{e_u:.4g}" in c.evidence and "100 DOF" in c.evidence
    assert beats_uniform_claim("s", dof_a, err_a, DOF, ERR, factor=0.5).holds is False
    assert "0.5 x uniform" in beats_uniform_claim("s", dof_a, err_a, DOF, ERR, 0.5).evidence
    # a tie is not "better"
    assert beats_uniform_claim("s", [100], [e_u], DOF, ERR).holds is False
    # beyond the uniform range: not decidable
    far = beats_uniform_claim("s", [10, 1000], [1.0, 0.01], DOF, ERR)
    assert far.holds is None and "not decidable" in far.evidence
    with pytest.raises(ValueError, match="factor"):
        beats_uniform_claim("s", dof_a, err_a, DOF, ERR, factor=0.0)


def test_range_claim():
    """Each extreme by its own relative difference; a published 0 against the span."""
    c = range_claim("colorbar", "u_y", (0.0, 0.59e-3), (0.0, 0.5922e-3), 0.1)
    assert c.holds is True and "u_y" in c.evidence and "0.4 % off" in c.evidence
    assert "0.0 % of the published span" in c.evidence and "absolute" in c.evidence
    assert range_claim("c", "u", (-0.2, 1.0), (0.0, 1.0), 0.1).holds is False
    assert range_claim("c", "u", (-0.1, 1.0), (0.0, 1.0), 0.1).holds is True
    with pytest.raises(ValueError, match="span"):
        range_claim("c", "u", (0.0, 1.0), (1.0, 1.0), 0.1)
    with pytest.raises(ValueError, match="pairs"):
        range_claim("c", "u", (0.0,), (0.0, 1.0), 0.1)


def test_range_claim_relative_to_each_extreme_not_the_span():
    """Figure 4.22's work u_x case: a maximum 19 % off held at ~9 % of the span when
    measured against the span; against the maximum itself it differs."""
    pub, ours = (-3.0e-5, 3.3e-5), (-3.0e-5, 3.3e-5 * 0.81)
    c = range_claim("c", "work u_x", ours, pub, 0.1)
    assert c.holds is False
    assert "min -3.0000e-05 against -3.0000e-05: 0.0 % off" in c.evidence
    assert "max 2.6730e-05 against 3.3000e-05: 19.0 % off" in c.evidence
    assert abs(ours[1] - pub[1]) / (pub[1] - pub[0]) < 0.1   # the old test passed it
    # a small extreme far off in relative terms: the span would hide it
    assert range_claim("c", "u", (-0.02, 1.0), (-0.01, 1.0), 0.1).holds is False
    assert "100.0 % off" in range_claim("c", "u", (-0.02, 1.0), (-0.01, 1.0), 0.1).evidence
    # both ends on the boundary of the tolerance hold (exact binary fractions)
    assert range_claim("c", "u", (-1.125, 2.25), (-1.0, 2.0), 0.125).holds is True
    assert range_claim("c", "u", (-1.125, 2.25), (-1.0, 2.0), 0.124).holds is False


def test_range_claim_fixed_extreme_is_not_evidence():
    """An extreme fixed by construction (a Dirichlet value) is not tested."""
    pub = (-1.0, 1.0e-4)
    c = range_claim("c", "u_y", (-0.5, 1.0e-4), pub, 0.1, fixed=("max",))
    assert c.holds is False and "50.0 % off" in c.evidence
    c = range_claim("c", "u_y", (-0.95, 7.0), pub, 0.1, fixed=("max",))
    assert c.holds is True                # the max is not tested
    assert "max 7.0000e+00 fixed by construction" in c.evidence
    assert "no evidence, not tested" in c.evidence
    assert range_claim("c", "u", (5.0, 1.0), (1.0, 1.0 + 1e-9), 0.1, fixed="min").holds
    with pytest.raises(ValueError, match="fixed"):
        range_claim("c", "u", (0.0, 1.0), (0.0, 1.0), 0.1, fixed=("min", "max"))
    with pytest.raises(ValueError, match="fixed"):
        range_claim("c", "u", (0.0, 1.0), (0.0, 1.0), 0.1, fixed=("top",))


def test_joint_claim():
    ok, bad, unk = Claim("a", True, "ea"), Claim("b", False, "eb"), Claim("c", None, "")
    j = joint_claim("all", ok, rate_claim("r", 2.0, 2.0, 0.1), note="n")
    assert j.holds is True and j.text == "all" and j.evidence.startswith("ea; observed")
    assert j.evidence.endswith("(n)")
    assert joint_claim("s", ok, unk).holds is None
    assert joint_claim("s", unk, bad).holds is False
    with pytest.raises(ValueError, match="at least one"):
        joint_claim("s")
