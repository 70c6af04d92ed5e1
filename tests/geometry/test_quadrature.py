"""Quadrature rules are exact for the degrees they promise."""

import numpy as np
import pytest

from hpfebe.quadrature import gauss_legendre, gauss_lobatto, gauss_log


@pytest.mark.parametrize("n", [1, 2, 5, 12, 30])
def test_gauss_legendre_exact(n):
    x, w = gauss_legendre(n)
    for k in range(2 * n):
        exact = 0.0 if k % 2 else 2.0 / (k + 1)
        assert abs(np.sum(w * x**k) - exact) < 1e-14


@pytest.mark.parametrize("n", [2, 3, 7, 13, 25])
def test_gauss_lobatto_exact_and_endpoints(n):
    x, w = gauss_lobatto(n)
    assert x[0] == -1.0 and x[-1] == 1.0 and np.all(np.diff(x) > 0)
    for k in range(2 * n - 2):
        exact = 0.0 if k % 2 else 2.0 / (k + 1)
        assert abs(np.sum(w * x**k) - exact) < 1e-14


@pytest.mark.parametrize("n", [1, 2, 4, 8, 16, 24])
def test_log_weighted_rule_exact(n):
    """int_0^1 -log(t) t^k dt = 1/(k+1)^2 for k <= 2n-1."""
    x, w = gauss_log(n)
    assert np.all((x > 0) & (x < 1)) and np.all(w > 0)
    for k in range(2 * n):
        assert abs(np.sum(w * x**k) * (k + 1) ** 2 - 1.0) < 5e-14


def test_bad_order():
    with pytest.raises(ValueError, match="n must be"):
        gauss_legendre(0)
    with pytest.raises(ValueError, match="n must be"):
        gauss_lobatto(1)
