"""A body condensed onto its contact dofs (Sections 4.3.3, 4.4): the stiffness of a BE
body (S_hat) or an FE body (K) with its Dirichlet dofs eliminated and the rest
condensed by one Cholesky factorisation, the form in which the mortar contact problems
(:class:`hpfebe.contact.MortarContact`, :class:`hpfebe.contact.FEMortarContact`) see it.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla


class CondensedBody:
    """S_hat of one body with its Dirichlet dofs eliminated and condensed onto its
    contact dofs (Schur complement, one Cholesky of the rest):

        A = S_cc - S_cr S_rr^-1 S_rc,   b = f_c - S_cr S_rr^-1 f_r,   f = -S_{.D} U_D.

    ``contact`` are interleaved dofs; those that are Dirichlet dofs are dropped
    (``cpos`` = positions of the kept ones in ``contact``)."""

    def __init__(self, S, fixed, values, contact):
        S = np.asarray(S, dtype=float)
        n = S.shape[0]
        fixed = np.asarray(fixed, dtype=np.int64)
        values = np.broadcast_to(np.asarray(values, dtype=float), fixed.shape)
        contact = np.asarray(contact, dtype=np.int64)
        is_fixed = np.zeros(n, dtype=bool)
        is_fixed[fixed] = True
        self.cpos = np.flatnonzero(~is_fixed[contact])
        c = contact[self.cpos]
        rest = np.ones(n, dtype=bool)
        rest[fixed] = False
        rest[c] = False
        r = np.flatnonzero(rest)
        self.n, self.fixed, self.values, self.c, self.r = n, fixed, values.copy(), c, r
        self.S = S
        f = -S[:, fixed] @ self.values
        cho = sla.cho_factor(S[np.ix_(r, r)])
        self.X = sla.cho_solve(cho, S[np.ix_(r, c)])
        self.y = sla.cho_solve(cho, f[r])
        A = S[np.ix_(c, c)] - S[np.ix_(c, r)] @ self.X
        self.A = 0.5 * (A + A.T)
        self.b = f[c] - S[np.ix_(c, r)] @ self.y
        self._choA = None

    def expand(self, u_c) -> np.ndarray:
        """The full U from its contact values (Dirichlet values, rest eliminated)."""
        u = np.zeros(self.n)
        u[self.fixed] = self.values
        u[self.c] = u_c
        u[self.r] = self.y - self.X @ u_c
        return u

    def solve(self, load_c) -> np.ndarray:
        """Contact values of the Neumann problem A u_c = b + load_c (the Cholesky factor
        of A once; LAPACK potrs directly - what scipy's cho_solve calls, without its
        per-call checks)."""
        if self._choA is None:
            self._choA = sla.cho_factor(self.A)
            self._potrs = sla.get_lapack_funcs("potrs", (self._choA[0],))
        rhs = np.asarray(self.b + load_c, dtype=float)
        if rhs.shape != self.b.shape or not np.isfinite(rhs).all():
            raise ValueError(f"load_c must be a finite vector of shape {self.b.shape}")
        if rhs.size == 0:
            return rhs.copy()
        x, info = self._potrs(self._choA[0], rhs, lower=self._choA[1])
        if info != 0:
            raise ValueError(f"illegal value in argument {-info} of potrs")
        return x

    def reaction(self, u_c) -> np.ndarray:
        """(S U - L) on the contact dofs (the residual functional, Algorithm 4.3 step 5)."""
        return self.A @ u_c - self.b
