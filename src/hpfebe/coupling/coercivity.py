"""Coercivity threshold of the Nitsche form a_h (Lemma 2.2.3) computed, not bounded.

Write the matrix of a_h as A(l) = A0 + l P, l = lambda_Nit (``NitscheFEBE.blocks``): A0
holds the FE stiffness, S_hat and the two flux terms, P the penalty term
<h1^-1 p1^alpha [U], [Phi]>.  P is positive semidefinite and acts only on the dofs whose
traces live on Gamma_I ("I"); on every function with [Phi] = 0 the form is
(grad Phi1, grad Phi1) + <S_hat Phi2, Phi2> > 0.  Hence, with R the remaining dofs (A0_RR
is positive definite: their functions have no jump),

    A(l) > 0   <=>   S0 + l P_II > 0,   S0 = A0_II - A0_IR A0_RR^-1 A0_RI,

and the threshold lambda* = inf{l : A(l) > 0} is the largest generalised eigenvalue mu of
S0 x = -mu P_II x.  We compute it stably from the definite pencil (P_II, B),
B = S0 + L P_II > 0 for some L (found by doubling): P_II x = nu B x, lambda* = L - 1/nu_max.
lambda* <= 0 means a_h is positive definite for every lambda_Nit >= 0.

Because P scales like p1^alpha for a uniform degree, lambda*(alpha) = lambda*(0) p^-alpha
exactly.

The bound of Lemma 2.2.3 (as printed, gamma = 2): lambda_Nit >= 1/2 p^(gamma - alpha) +
C_inv p^(2 - alpha), with C_inv the constant of the squared inverse inequality (2.7),
sum_J h_K p^-gamma ||dn Phi||^2_J <= C_inv p^(2 - gamma) ||grad Phi||^2_Omega1, computed
here as the largest eigenvalue of that pencil on V1_hp (``inverse_constant``).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..solvers.sparse_lu import symmetric_lu
from .nitsche import NitscheFEBE


def _schur(A: sp.spmatrix, I: np.ndarray, R: np.ndarray, chunk: int = 256) -> np.ndarray:
    """Dense Schur complement A_II - A_IR A_RR^-1 A_RI (A symmetric, A_RR positive
    definite)."""
    A = A.tocsc()
    S = A[I][:, I].toarray()
    if R.size == 0:
        return S
    lu = symmetric_lu(A[R][:, R], diag_pivot_thresh=0.0)[0]   # A_RR is SPD
    ARI = A[R][:, I].tocsc()
    AIR = A[I][:, R].tocsr()
    for s in range(0, len(I), chunk):
        S[:, s:s + chunk] -= AIR @ lu.solve(ARI[:, s:s + chunk].toarray())
    return 0.5 * (S + S.T)


def _largest_pencil_threshold(S0: np.ndarray, P: np.ndarray) -> float:
    """Largest mu with S0 + mu P singular, S0 + l P > 0 for l > mu (P >= 0)."""
    L = 1.0
    for _ in range(60):
        try:
            sla.cholesky(S0 + L * P)
            break
        except sla.LinAlgError:
            L *= 2.0
    else:
        raise np.linalg.LinAlgError("no lambda makes S0 + lambda P positive definite "
                                    "(the form is not positive on jump-free functions)")
    nu = sla.eigh(P, S0 + L * P, eigvals_only=True)
    nu_max = float(nu.max())
    if nu_max <= 0:
        return -np.inf
    return L - 1.0 / nu_max


def coercivity_threshold(model: NitscheFEBE) -> float:
    """lambda* = inf{lambda_Nit : a_h positive definite on V_hp} for ``model``'s alpha."""
    K11a, K12a, K22a = model.blocks(0.0)
    K11b, K12b, K22b = model.blocks(1.0)
    A0 = sp.bmat([[K11a, K12a], [K12a.T, sp.csr_matrix(K22a)]]).tocsr()
    P = sp.bmat([[K11b - K11a, K12b - K12a],
                 [(K12b - K12a).T, sp.csr_matrix(K22b - K22a)]]).tocsr()
    P.eliminate_zeros()
    rows = np.flatnonzero(np.diff(P.indptr))
    I = rows
    R = np.setdiff1d(np.arange(A0.shape[0]), I)
    S0 = _schur(A0, I, R)
    PII = P[I][:, I].toarray()
    return _largest_pencil_threshold(S0, 0.5 * (PII + PII.T))


def inverse_constant(model: NitscheFEBE, gamma: float = 2.0) -> float:
    """C_inv of (2.7) squared: max over V1_hp of
    sum_J h_K p^-gamma ||dn Phi||^2_J / (p^(2 - gamma) ||grad Phi||^2_Omega1)."""
    rule, Dn = model.rule, model.Dn
    p = float(model.fe.p)
    w = rule.w * rule.h1 * p ** -gamma / p ** (2.0 - gamma)
    F = (Dn.T @ sp.diags(w) @ Dn).tocsr()[model.free1][:, model.free1]
    F.eliminate_zeros()
    T = np.flatnonzero(np.diff(F.indptr))
    R = np.setdiff1d(np.arange(F.shape[0]), T)
    S = _schur(model.A1, T, R)
    FT = F[T][:, T].toarray()
    return float(sla.eigh(0.5 * (FT + FT.T), S, eigvals_only=True).max())


def lemma_2_2_3_bound(p: int, alpha: float, C_inv: float, gamma: float = 2.0) -> float:
    """The sufficient condition of Lemma 2.2.3: 1/2 p^(gamma-alpha) + C_inv p^(2-alpha)."""
    return 0.5 * p ** (gamma - alpha) + C_inv * p ** (2.0 - alpha)
