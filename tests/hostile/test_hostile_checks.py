"""The one validation helper (hpfebe.checks): every kind of hostile value of a number,
count, flag, choice, array or callable parameter is refused with a message naming the
parameter and its value; every honest spelling (numpy scalars, 0-d arrays) is accepted."""

import numpy as np
import pytest

from hpfebe import checks
from hpfebe.checks import InputTypeError


@pytest.mark.parametrize("value", [4, 4.0, np.float32(4), np.float64(4), np.int64(4),
                                   np.array(4.0), np.array(4)])
def test_real_accepts_numbers(value):
    v = checks.real("sigma_Y", value, positive=True)
    assert type(v) is float and v == 4.0


@pytest.mark.parametrize("value, kind", [
    (True, InputTypeError), (np.bool_(False), InputTypeError), ("4", InputTypeError),
    (None, InputTypeError), (1 + 2j, InputTypeError), ([4.0], InputTypeError),
    (np.array([4.0]), InputTypeError), (np.array("4"), InputTypeError),
    (float("nan"), ValueError), (np.float32("nan"), ValueError),
    (float("inf"), ValueError), (-1.0, ValueError), (0.0, ValueError), (10**400, ValueError),
])
def test_real_refuses(value, kind):
    with pytest.raises(kind, match=r"sigma_Y must be a finite real number > 0, got"):
        checks.real("sigma_Y", value, positive=True)


def test_real_bounds_and_kinds():
    assert checks.real("nu", 0.3, lo=-1, hi=0.5, lo_open=True, hi_open=True) == 0.3
    with pytest.raises(ValueError, match=r"nu must be a finite real number in \(-1, 0.5\)"):
        checks.real("nu", 0.5, lo=-1, hi=0.5, lo_open=True, hi_open=True)
    assert checks.real("atol", 0, nonnegative=True) == 0.0
    assert checks.real("F", None, allow_none=True) is None
    assert checks.real("x", float("inf"), finite=False) == float("inf")
    with pytest.raises(ValueError):
        checks.real("x", float("nan"), finite=False)       # NaN is never a value
    # a wrong kind is a TypeError, and a ValueError for callers catching those
    with pytest.raises(TypeError):
        checks.real("x", "1")
    with pytest.raises(ValueError):
        checks.real("x", "1")


@pytest.mark.parametrize("value", [3, np.int32(3), 3.0, np.array(3)])
def test_integer_accepts(value):
    n = checks.integer("max_iter", value, lo=1)
    assert type(n) is int and n == 3


@pytest.mark.parametrize("value, kind, text", [
    (1.5, ValueError, "never rounded"), (True, InputTypeError, "True"),
    ("3", InputTypeError, "'3'"), (float("nan"), ValueError, "nan"),
    (-1, ValueError, "-1"), (None, InputTypeError, "None")])
def test_integer_refuses(value, kind, text):
    with pytest.raises(kind, match=r"max_cuts must be an integer >= 0, got") as err:
        checks.integer("max_cuts", value, lo=0)
    assert text in str(err.value)


@pytest.mark.parametrize("value", ["no", "False", 0, 1, 1.0, None, np.array([True])])
def test_boolean_refuses(value):
    with pytest.raises(InputTypeError, match="predictor must be True or False"):
        checks.boolean("predictor", value)


def test_boolean_and_choice_accept():
    assert checks.boolean("x", np.bool_(True)) is True
    assert checks.boolean("x", False) is False
    assert checks.choice("norm", "l2", ("l2", "max")) == "l2"
    assert checks.choice("law", "Tresca", ("tresca",), fold_case=True) == "tresca"
    for bad in ("L2", None, 2, ["l2"], np.array(["l2"])):
        with pytest.raises(ValueError, match=r"norm must be one of \('l2', 'max'\)"):
            checks.choice("norm", bad, ("l2", "max"))
    with pytest.raises(ValueError):
        checks.choice("p", True, (1, 2))                  # True is not 1


def test_array():
    a = checks.array("x", [[0, 1], [2, 3]], shape=(None, 2))
    assert a.dtype == float and a.shape == (2, 2)
    assert checks.array("k", [1.0, 2.0], dtype=int).dtype.kind == "i"
    cases = [("abc", InputTypeError, "be an array of real numbers"),
             ([True, False], InputTypeError, "be an array of real numbers"),
             ([[1, 2], [3]], InputTypeError, "be an array of real numbers"),
             ([1 + 1j], InputTypeError, "be an array of real numbers"),
             ([[1, 2, 3]], ValueError, r"have shape \(n, 2\), got shape \(1, 3\)"),
             ([[1, np.nan]], ValueError, r"be finite, got nan at index \(0, 1\)")]
    for value, kind, text in cases:
        with pytest.raises(kind, match="x must " + text):
            checks.array("x", value, shape=(None, 2))
    with pytest.raises(ValueError, match="never rounded"):
        checks.array("k", [1.5], dtype=int)
    with pytest.raises(ValueError, match="at least 2 entries"):
        checks.array("x", [1.0], min_size=2)


def test_finite_instance_callable():
    checks.finite("state", np.zeros(3), np.ones((2, 2)))
    with pytest.raises(ValueError, match="state must be finite, got nan at flat index 1"):
        checks.finite("state", np.zeros(3), np.array([0.0, np.nan]))
    with pytest.raises(InputTypeError, match="body must be a float, got an object of type str"):
        checks.instance("body", "x", float)
    with pytest.raises(InputTypeError, match="body must be a Lame body, got an object of type int"):
        checks.instance("body", 3, (float,), "a Lame body")
    x = np.zeros((4, 2))
    g = checks.callable_returning("gap", lambda x: x[:, 0] + 1, x, lambda x: (len(x),))
    assert np.allclose(g(np.ones((3, 2))), 2.0)
    with pytest.raises(ValueError, match=r"gap\(x\) must have shape \(4,\), got shape \(\)"):
        checks.callable_returning("gap", lambda x: 1.0, x, lambda x: (len(x),))
    with pytest.raises(InputTypeError, match="gap must be a callable"):
        checks.callable_returning("gap", 1.0, x, (4,))
    g = checks.callable_returning("gap", lambda x: np.where(x[:, 0] > 0, 1.0, np.nan), np.ones((2, 2)),
                                  lambda x: (len(x),))
    with pytest.raises(ValueError, match=r"gap\(x\) must be finite"):
        g(np.zeros((2, 2)))
