"""Quadrature rules on reference intervals.

* ``gauss_legendre(n)``: n-point Gauss-Legendre rule on [-1, 1] (exact for degree 2n-1).
* ``gauss_lobatto(n)``: n-point Gauss-Lobatto rule on [-1, 1] (endpoints included, exact
  for degree 2n-3); its nodes are the nodal points of the continuous space V_hp.
* ``gauss_log(n)``: n-point Gauss rule on (0, 1] for the weight -log(t), exact for
  int_0^1 -log(t) q(t) dt with deg q <= 2n-1.  Built by Gautschi's modified Chebyshev
  algorithm from the modified moments of the shifted Legendre polynomials, which is well
  conditioned (the plain moments 1/(k+1)^2 are not).
* ``rule_tables(nmax)``: all rules up to nmax points packed into arrays for numba kernels.

All rules are cached; they are computed once per process.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.polynomial import legendre as npleg

__all__ = ["gauss_legendre", "gauss_lobatto", "gauss_log", "rule_tables"]


def _check_n(n: int, name: str = "n", minimum: int = 1) -> int:
    if int(n) != n or n < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {n!r}")
    return int(n)


@lru_cache(maxsize=None)
def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1]."""
    n = _check_n(n)
    x, w = npleg.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@lru_cache(maxsize=None)
def gauss_lobatto(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Lobatto nodes and weights on [-1, 1] (n >= 2 points).

    Interior nodes are the roots of P'_{n-1}; weights 2 / (n (n-1) P_{n-1}(x)^2).
    """
    n = _check_n(n, minimum=2)
    p = n - 1
    cp = np.zeros(p + 1)
    cp[p] = 1.0
    if p >= 2:
        # roots of P'_p: eigenvalues of the Jacobi(1,1) Jacobi matrix, then Newton polish
        k = np.arange(1, p - 1)
        off = np.sqrt(k * (k + 2) / ((2 * k + 1) * (2 * k + 3)))
        inner = np.linalg.eigvalsh(np.diag(off, 1) + np.diag(off, -1))
        dcp, ddcp = npleg.legder(cp, 1), npleg.legder(cp, 2)
        for _ in range(3):
            inner = inner - npleg.legval(inner, dcp) / npleg.legval(inner, ddcp)
        x = np.concatenate(([-1.0], np.sort(inner), [1.0]))
    else:
        x = np.array([-1.0, 1.0])
    w = 2.0 / (p * (p + 1) * npleg.legval(x, cp) ** 2)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


def _modified_chebyshev(nu: np.ndarray, a: np.ndarray, b: np.ndarray, n: int):
    """Gautschi's modified Chebyshev algorithm: recurrence coefficients (alpha, beta) of
    the monic orthogonal polynomials of a measure from its modified moments ``nu`` with
    respect to monic polynomials with recurrence coefficients (a, b)."""
    alpha = np.zeros(n)
    beta = np.zeros(n)
    sig_prev = np.zeros(2 * n)
    sig = nu.copy()
    alpha[0] = a[0] + nu[1] / nu[0]
    beta[0] = nu[0]
    for k in range(1, n):
        sig_new = np.zeros(2 * n)
        for l in range(k, 2 * n - k):
            sig_new[l] = (sig[l + 1] - (alpha[k - 1] - a[l]) * sig[l]
                          - beta[k - 1] * sig_prev[l] + b[l] * sig[l - 1])
        alpha[k] = a[k] + sig_new[k + 1] / sig_new[k] - sig[k] / sig[k - 1]
        beta[k] = sig_new[k] / sig[k - 1]
        sig_prev, sig = sig, sig_new
    return alpha, beta


@lru_cache(maxsize=None)
def gauss_log(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes in (0, 1) and weights for int_0^1 -log(t) f(t) dt ~ sum w_i f(t_i)."""
    n = _check_n(n)
    m = 2 * n
    k = np.arange(m, dtype=float)
    # int_0^1 -log(t) P_k(2t-1) dt = 1 (k=0), (-1)^k / (k (k+1)) (k>=1)
    mom = np.empty(m)
    mom[0] = 1.0
    kk = k[1:]
    mom[1:] = (-1.0) ** kk / (kk * (kk + 1.0))
    # normalise to the monic shifted Legendre polynomials: leading coeff (2k)!/(k!)^2
    lead = np.ones(m)
    for j in range(1, m):
        lead[j] = lead[j - 1] * (2 * j) * (2 * j - 1) / (j * j)
    nu = mom / lead
    a = np.full(m, 0.5)
    b = np.zeros(m)
    b[1:] = kk**2 / (4.0 * (4.0 * kk**2 - 1.0))
    alpha, beta = _modified_chebyshev(nu, a, b, n)
    jac = np.diag(alpha) + np.diag(np.sqrt(beta[1:]), 1) + np.diag(np.sqrt(beta[1:]), -1)
    x, v = np.linalg.eigh(jac)
    w = beta[0] * v[0, :] ** 2
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@lru_cache(maxsize=None)
def rule_tables(nmax: int, n_log: int | None = None):
    """Gauss-Legendre and log-weighted rules with 1..nmax points, mapped to [0, 1], packed
    row-wise: ``gx[n, :n]``, ``gw[n, :n]`` (Gauss on [0,1]) and ``lx[n, :n]``, ``lw[n, :n]``
    (weight -log t on (0,1]), the log rules only for n <= ``n_log`` (default nmax; zero
    rows above): building all 48 costs about 1 s of Python (Gautschi's algorithm per n),
    and only the singular BEM integrals read them."""
    n_log = nmax if n_log is None else min(n_log, nmax)
    gx = np.zeros((nmax + 1, nmax))
    gw = np.zeros((nmax + 1, nmax))
    lx = np.zeros((nmax + 1, nmax))
    lw = np.zeros((nmax + 1, nmax))
    for n in range(1, nmax + 1):
        x, w = gauss_legendre(n)
        gx[n, :n] = 0.5 * (x + 1.0)
        gw[n, :n] = 0.5 * w
    for n in range(1, n_log + 1):
        x, w = gauss_log(n)
        lx[n, :n] = x
        lw[n, :n] = w
    for t in (gx, gw, lx, lw):
        t.setflags(write=False)
    return gx, gw, lx, lw
