"""The one validation helper of the public entry points: numbers, integers, booleans,
choices, arrays, objects of a required kind and callables of a required output shape.

Every check names the parameter, shows the value it got and says what is allowed::

    real("sigma_Y", np.float32(4), positive=True)      -> 4.0
    real("nu", 0.5, lo=-1, hi=0.5, lo_open=True, hi_open=True)
        ValueError: nu must be a finite real number in (-1, 0.5), got 0.5
    tolerance("tol", 2.0)
        ValueError: tol must be a finite real number in (0, 1), got 2.0
    integer("max_cuts", 1.5, lo=0)
        ValueError: max_cuts must be an integer >= 0, got 1.5
    boolean("predictor", "no")
        InputTypeError: predictor must be True or False, got 'no'

Numbers are Python or numpy reals (``np.float32``, ``np.int64``, a 0-d array such as
``np.array(2.0)``); a bool is never a number (True is not 1.0), a string is never parsed
("0.3" is not 0.3), NaN is never a value.  A value of the wrong *kind* (a string, a
bool, None, a list where a number is expected, an object of another class) raises
:class:`InputTypeError`, which is a TypeError and also a ValueError (callers and tests
that catch the ValueError of an input check keep working); a value of the right kind out
of range (negative, NaN, 1.5 as a count, a wrong shape) raises ValueError.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterable

import numpy as np

__all__ = ["InputTypeError", "real", "tolerance", "integer", "boolean", "choice", "array",
           "instance", "callable_returning", "finite"]


class InputTypeError(TypeError, ValueError):
    """A parameter of the wrong kind (a string for a number, a bool for a count, a
    LaplaceBEM for a Lame body): a TypeError that is also a ValueError."""


def _got(value) -> str:
    text = repr(value)
    if len(text) > 80:
        text = text[:77] + "..."
    if isinstance(value, np.ndarray):
        return f"{text} (array of shape {value.shape}, dtype {value.dtype})"
    return text


def _interval(lo, hi, lo_open: bool, hi_open: bool) -> str:
    if lo is not None and hi is not None:
        return f" in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    if lo is not None:
        return f" {'>' if lo_open else '>='} {lo:g}"
    if hi is not None:
        return f" {'<' if hi_open else '<='} {hi:g}"
    return ""


def _scalar(value):
    """``value`` as a Python number if it is a real number of some kind (Python, numpy
    scalar or 0-d array of integer or float dtype), else None."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        return None
    if isinstance(value, np.ndarray):
        if value.ndim != 0 or value.dtype.kind not in "iuf":
            return None
        return value.item()
    if isinstance(value, (np.integer, np.floating)):
        return value.item()
    if isinstance(value, numbers.Real):
        return value
    return None


def real(name: str, value, *, positive: bool = False, nonnegative: bool = False,
         finite: bool = True, lo=None, hi=None, lo_open: bool = False,
         hi_open: bool = False, allow_none: bool = False):
    """``value`` as a Python float: a real number (Python, numpy scalar, 0-d array);
    never a bool, a string, a complex or NaN.  ``finite`` (default): no +-inf either.
    ``positive``: > 0; ``nonnegative``: >= 0; ``lo``/``hi``: bounds, inclusive unless
    ``lo_open``/``hi_open``.  ``allow_none``: None passes through (returned as None)."""
    if value is None and allow_none:
        return None
    if positive:
        lo, lo_open = 0.0, True
    elif nonnegative:
        lo, lo_open = 0.0, False
    what = ("a finite real number" if finite else "a real number") + \
        _interval(lo, hi, lo_open, hi_open)
    x = _scalar(value)
    if x is None:
        raise InputTypeError(f"{name} must be {what}, got {_got(value)}")
    try:
        v = float(x)
    except (OverflowError, TypeError, ValueError):     # an int beyond float's range
        raise ValueError(f"{name} must be {what}, got {_got(value)}") from None
    bad = math.isnan(v) or (finite and math.isinf(v))
    if lo is not None:
        bad = bad or (v <= lo if lo_open else v < lo)
    if hi is not None:
        bad = bad or (v >= hi if hi_open else v > hi)
    if bad:
        raise ValueError(f"{name} must be {what}, got {_got(value)}")
    return v


def tolerance(name: str, value) -> float:
    """A relative tolerance of a stopping test: a real number in (0, 1).  0 never stops
    (or, beside an absolute floor, is not scale-free); 1 or more accepts a residual or
    increment as large as the quantity it is measured against ("converged" would mean
    nothing)."""
    return real(name, value, lo=0.0, hi=1.0, lo_open=True, hi_open=True)


def integer(name: str, value, *, lo=None, hi=None, allow_none: bool = False):
    """``value`` as a Python int: an integer (Python, numpy, 0-d array) or a float of
    integral value (2.0; never rounded: 1.5 is refused); never a bool or a string.
    ``lo``/``hi``: inclusive bounds.  ``allow_none``: None passes through."""
    if value is None and allow_none:
        return None
    what = "an integer" + _interval(lo, hi, False, False)
    x = _scalar(value)
    if x is None:
        raise InputTypeError(f"{name} must be {what}, got {_got(value)}")
    if isinstance(x, numbers.Integral):
        n = int(x)
    else:
        try:
            f = float(x)
        except (TypeError, ValueError):
            raise InputTypeError(f"{name} must be {what}, got {_got(value)}") from None
        if not (math.isfinite(f) and f == math.floor(f)):
            raise ValueError(f"{name} must be {what}, got {_got(value)} "
                             "(counts are never rounded)")
        n = int(f)
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        raise ValueError(f"{name} must be {what}, got {_got(value)}")
    return n


def boolean(name: str, value) -> bool:
    """``value`` as a Python bool: True or False (or a numpy bool); never a string
    ('no' is not True), a number or None."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind == "b":
        return bool(value)
    raise InputTypeError(f"{name} must be True or False, got {_got(value)}")


def choice(name: str, value, allowed: Iterable, *, fold_case: bool = False):
    """``value`` if it is one of ``allowed`` (``fold_case``: strings compared in lower
    case, the lower-case form returned)."""
    allowed = tuple(allowed)
    key = value
    if fold_case and isinstance(value, str):
        key = value.lower()
    def same(a) -> bool:        # True == 1, but a bool is no choice of an int option
        if isinstance(key, np.ndarray) or \
                isinstance(a, (bool, np.bool_)) != isinstance(key, (bool, np.bool_)):
            return False
        try:
            eq = a == key
            return isinstance(eq, (bool, np.bool_)) and bool(eq)
        except (TypeError, ValueError):              # incomparable objects
            return False

    ok = any(same(a) for a in allowed)
    if not ok:
        raise ValueError(f"{name} must be one of {allowed}, got {_got(value)}")
    return key


def _shape_text(shape) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + \
        ("," if len(shape) == 1 else "") + ")"


def array(name: str, value, *, shape=None, ndim=None, dtype=float, finite: bool = True,
          allow_inf: bool = False, min_size: int = 0, copy: bool = False) -> np.ndarray:
    """``value`` as an ndarray of ``dtype`` (float: from integer or float data; int: from
    integer data or floats of integral value; bool: from booleans only).  Never from
    strings, booleans (for a numeric dtype), complex numbers, None or ragged lists.
    ``shape``: a tuple whose entries are ints or None (any length); ``ndim``: the number
    of axes; ``finite`` (float data): no NaN or +-inf (``allow_inf``: no NaN, +-inf
    allowed, e.g. a gap "no obstacle here"); ``min_size``: at least that many
    entries.  ``copy``: always a new array."""
    dtype = np.dtype(dtype)
    of = {"f": "real numbers", "i": "integers", "u": "integers", "b": "booleans"}[dtype.kind]
    if isinstance(value, (str, bytes)) or value is None:
        raise InputTypeError(f"{name} must be an array of {of}, got {_got(value)}")
    try:
        arr = np.array(value, copy=True) if copy else np.asarray(value)
    except (ValueError, TypeError) as err:              # ragged nested lists
        raise InputTypeError(f"{name} must be an array of {of}, got "
                             f"{_got(value)} ({err})") from None
    kind = arr.dtype.kind
    allowed_kinds = {"f": "iuf", "i": "iuf", "u": "iuf", "b": "b"}[dtype.kind]
    if kind not in allowed_kinds or (arr.dtype == object):
        raise InputTypeError(f"{name} must be an array of {of}, got "
                             f"{_got(value)}")
    if dtype.kind in "iu" and kind == "f":
        bad = ~np.isfinite(arr) | (arr != np.floor(arr))
        if np.any(bad):
            raise ValueError(f"{name} must hold integers, got {float(arr[bad].ravel()[0])!r} "
                             "(never rounded)")
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be an array with {ndim} axes, got shape "
                         f"{arr.shape}")
    if shape is not None:
        shape = tuple(shape)
        if arr.ndim != len(shape) or any(s is not None and s != a
                                         for s, a in zip(shape, arr.shape)):
            raise ValueError(f"{name} must have shape {_shape_text(shape)}, got shape "
                             f"{arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name} must have at least {min_size} entries, got {arr.size}")
    arr = arr.astype(dtype, copy=False)
    bad = (np.isnan(arr) if allow_inf else ~np.isfinite(arr)) if finite and \
        dtype.kind == "f" else None
    if bad is not None and np.any(bad):
        k = int(np.flatnonzero(bad.ravel())[0])
        where = np.unravel_index(k, arr.shape) if arr.ndim else ()
        raise ValueError(f"{name} must be finite, got {float(arr.ravel()[k])!r} at index "
                         f"{tuple(int(i) for i in where)} of {_got(value)}")
    return arr


def finite(name: str, *values) -> None:
    """ValueError unless every array of ``values`` is free of NaN and +-inf (a state
    before it is committed as history, an indicator before it is marked)."""
    for v in values:
        arr = np.asarray(v, dtype=float)
        if not np.all(np.isfinite(arr)):
            k = int(np.flatnonzero(~np.isfinite(arr.ravel()))[0])
            raise ValueError(f"{name} must be finite, got {float(arr.ravel()[k])!r} at flat "
                             f"index {k} of {arr.size}")


def instance(name: str, value, kinds, what: str | None = None):
    """``value`` if it is an instance of ``kinds`` (a class or a tuple of classes);
    InputTypeError naming ``name``, the class it got and ``what`` is expected."""
    if not isinstance(value, kinds):
        if what is None:
            ks = kinds if isinstance(kinds, tuple) else (kinds,)
            what = "a " + " or ".join(k.__name__ for k in ks)
        raise InputTypeError(f"{name} must be {what}, got an object of type "
                             f"{type(value).__name__}: {_got(value)}")
    return value


def callable_returning(name: str, f, sample, shape, *, finite: bool = True,
                       allow_inf: bool = False) -> Callable:
    """A wrapper of the callable ``f`` that checks each output ``f(x)`` is a real array
    of ``shape`` (a tuple of ints or None, as :func:`array`, or a callable x -> such a
    tuple) and ``finite`` / ``allow_inf`` (as :func:`array`): a gap g(x) for points x of
    shape (n, 2) must return shape (n,), not a scalar, and no NaN.  ``f(sample)`` is
    checked now (``sample`` None: only the later calls are checked)."""
    if not callable(f):
        raise InputTypeError(f"{name} must be a callable, got {_got(f)}")
    if isinstance(shape, Callable):
        shape_of = shape
    else:
        shape_of = (lambda _x, _s=tuple(shape): _s)

    def checked(x, *args, **kwargs):
        out = f(x, *args, **kwargs)
        want = tuple(shape_of(x))
        try:
            return array(f"{name}(x)", out, shape=want, finite=finite,
                         allow_inf=allow_inf)
        except ValueError as err:
            raise type(err)(f"{err} (for x of shape {np.shape(x)})") from None

    if sample is not None:
        checked(sample)
    checked.__wrapped__ = f
    checked.__doc__ = f.__doc__
    return checked
