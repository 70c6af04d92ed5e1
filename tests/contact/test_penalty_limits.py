"""hpfebe.contact.limits: the Section 3.2.5 body, the eps -> 0 limit on a mesh, the
Williams corner exponent, backward errors and the acceptance check of penalty runs."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from hpfebe.analysis import energy_norm
from hpfebe.bem.lame import LameBEM
from hpfebe.contact import solve_penalty
from hpfebe.contact.limits import (MACHEPS, backward_error, check_penalty_solution,
                                   constrained_limit, saturation_index, singular_exponent,
                                   solve_penalty_checked)
from hpfebe.contact.penalty import penalty_residual
from hpfebe.geometry import BoundaryMesh
from hpfebe.scenes.penalty import square_body

E, NU, D = 266926.0, 0.29, 2e-4


@pytest.fixture(scope="module")
def body8():
    bem = square_body(8, E, NU, "strain")
    bem.S_hat
    return bem


# --------------------------------------------------------------------------- body
@pytest.mark.parametrize("n,p", [(2, 1), (4, 2), (3, 3)])
def test_square_body(n, p):
    """[-1,1]^2, n elements of degree p per side, labels C (bottom), N, D (top), N;
    free displacement dofs 2 (3 n p - 1)."""
    bem = square_body(n, E, NU, "stress", p=p)
    m = bem.mesh
    assert m.n_elements == 4 * n and np.all(m.degrees == p)
    assert bem.plane == "stress"
    bottom = m.where("C")
    assert bottom.sum() == n and np.allclose(m.normals[bottom], [0.0, -1.0])
    assert np.allclose(m.normals[m.where("D")], [0.0, 1.0])
    assert m.where("N").sum() == 2 * n
    assert len(bem.V_space.free_dofs("D", components=2)) == 2 * (3 * n * p - 1)


# --------------------------------------------------------------------------- corner
def test_singular_exponent_values():
    """Clamped / free right angle: 0.7177 for nu = 0.29 (plane strain), 0.711 for nu = 0.3
    (the classical value); the root solves Williams' equation; plane stress uses
    kappa = (3 - nu)/(1 + nu)."""
    assert abs(singular_exponent(0.29) - 0.7177) < 1e-4
    assert abs(singular_exponent(0.3) - 0.711) < 1e-3
    for nu, plane, kappa in [(0.29, "strain", 3 - 4 * 0.29),
                             (0.25, "stress", (3 - 0.25) / 1.25)]:
        for omega in (math.pi / 2, 0.6 * math.pi):
            lam = singular_exponent(nu, plane, omega)
            assert 0 < lam < 1
            f = (4 * kappa * math.sin(lam * omega) ** 2 + 4 * lam ** 2 * math.sin(omega) ** 2
                 - (kappa + 1) ** 2)
            assert abs(f) < 1e-12
    # plane strain nu = nu' / (1 + nu') is plane stress nu' (same kappa)
    assert abs(singular_exponent(0.2, "stress") - singular_exponent(0.2 / 1.2)) < 1e-12
    # a smaller angle is less singular
    assert singular_exponent(0.3, omega=0.4 * math.pi) > singular_exponent(0.3)


def test_singular_exponent_bad_input():
    with pytest.raises(ValueError, match="omega"):
        singular_exponent(0.3, omega=math.pi)        # complex exponent 1/2 + i ...
    with pytest.raises(ValueError, match="omega"):
        singular_exponent(0.3, omega=-1.0)
    with pytest.raises(ValueError, match="nu"):
        singular_exponent(0.5)
    with pytest.raises(ValueError, match="plane"):
        singular_exponent(0.3, "plain")


# --------------------------------------------------------------------------- eps -> 0
def test_constrained_limit_is_the_eps_to_zero_limit(body8):
    """U_0: U_n = g at the contact nodes, S_hat U_0 = 0 in the other free rows, zero on
    Gamma_D; the penalty solutions converge to it like eps."""
    bem, S = body8, body8.S_hat
    U0 = constrained_limit(bem, -D)
    Vs = bem.V_space
    C = Vs.dofs_on("C")
    assert np.allclose(U0[2 * C + 1], D, rtol=0, atol=1e-15)          # U_n = -U_y = -D
    Dd = Vs.dofs_on("D")
    assert np.all(U0[2 * Dd] == 0) and np.all(U0[2 * Dd + 1] == 0)
    rest = np.setdiff1d(Vs.free_dofs("D", components=2), 2 * C + 1)
    assert np.abs((S @ U0)[rest]).max() < 1e-9 * np.abs(S @ U0).max()
    n0 = energy_norm(S, U0)
    errs = [energy_norm(S, solve_penalty(bem, C_eps / 8, -D, S=S).U - U0) / n0
            for C_eps in (1e-7, 1e-8, 1e-9)]
    assert errs[0] < 1e-2
    assert 0.08 < errs[1] / errs[0] < 0.12 and 0.08 < errs[2] / errs[1] < 0.12, errs


def test_constrained_limit_general_axis():
    """A contact side facing +x (n = (1, 0)): U_n = U_x = g there."""
    mesh = BoundaryMesh.polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)], n=3,
                                labels=["N", "C", "N", "D"])
    bem = LameBEM(mesh, E, NU)
    U0 = constrained_limit(bem, 1e-3)
    C = bem.V_space.dofs_on("C")
    assert np.allclose(U0[2 * C], 1e-3, rtol=0, atol=1e-15)
    assert energy_norm(bem.S_hat, U0) > 0


def test_constrained_limit_bad_input(body8):
    with pytest.raises(ValueError, match="contact_label"):
        constrained_limit(body8, -D, contact_label="X")
    with pytest.raises(ValueError, match="gap"):
        constrained_limit(body8, math.nan)
    tilted = BoundaryMesh.polygon([(-1, -1), (1, -0.5), (1, 1), (-1, 1)], n=2,
                                  labels=["C", "N", "D", "N"])
    with pytest.raises(ValueError, match="axis"):
        constrained_limit(LameBEM(tilted, E, NU), -D)


def test_saturation_index():
    C = 10.0 ** -np.arange(4, 12)
    e = np.maximum(C, 1e-8)                # ~ eps down to a floor at C = 1e-8
    assert saturation_index(C, e) == 5     # C[5] = 1e-9: first step without decrease
    assert saturation_index(C, C) is None
    assert saturation_index(C[::2], np.maximum(C[::2], 1e-8)) == 3
    with pytest.raises(ValueError, match="decreasing"):
        saturation_index(C[::-1], e)
    with pytest.raises(ValueError, match="equal length"):
        saturation_index(C, e[:-1])
    with pytest.raises(ValueError, match="ratio"):
        saturation_index(C, e, ratio=2.0)


# --------------------------------------------------------------------------- accuracy
def test_backward_error():
    """Oettli-Prager: ~ macheps for a backward stable solve; |r|/(|A||x|) for a given
    residual; rows with (|A||x|)_i = 0 do not count."""
    rng = np.random.default_rng(1)
    A = rng.standard_normal((30, 30)) + 30 * np.eye(30)
    b = rng.standard_normal(30)
    x = np.linalg.solve(A, b)
    assert backward_error(A, x, A @ x - b) < 10 * MACHEPS
    r = np.zeros(30)
    r[3] = 1e-6
    assert backward_error(A, x, r) == pytest.approx(1e-6 / (np.abs(A[3]) @ np.abs(x)))
    assert backward_error(np.diag([1.0, 0.0]), np.ones(2), np.array([0.0, 5.0])) == 0.0
    with pytest.raises(ValueError, match="square"):
        backward_error(A[:, :5], x, b)


def test_check_accepts_good_and_flags_false_convergence(body8):
    """A converged run is accepted; the same result with a perturbed U but still claiming
    convergence is not ("NOT accepted" in the reason); a run cut short is not converged."""
    bem, S = body8, body8.S_hat
    tilt = lambda x: -D + 4e-4 * (x[:, 0] + 1.0)      # noqa: E731  partial contact
    res, chk = solve_penalty_checked(bem, 1e-6 / 8, tilt, S=S)
    assert res.converged and chk.accepted and not chk.lapack_warning
    assert chk.relative_residual <= 1e-6 and np.isfinite(chk.condition_number)
    assert chk.solve_s >= 0
    U = res.U * (1 + 1e-6)
    free = bem.V_space.free_dofs("D", components=2)
    G = penalty_residual(bem, U, res.eps, tilt, S=S)[free]
    bad = replace(res, U=U, residuals=res.residuals + [float(np.abs(G).max())])
    c2 = check_penalty_solution(bem, bad, tilt, S=S)
    assert not c2.accepted and "NOT accepted" in c2.reason
    assert c2.backward_error > 1e3 * MACHEPS
    res1, c1 = solve_penalty_checked(bem, 1e-6 / 8, tilt, S=S, max_iter=1)
    assert not res1.converged and not c1.accepted and c1.reason == "max_iter"


def test_check_flat_tiny_eps_reports_lapack(body8):
    """C_eps = 1e-20: cond * macheps > 1, LAPACK's warning ends up in the reason, and the
    solver does not call the result converged: Newton stops at round-off with a backward
    error of the contact equation far above 1e-6 (issue 10: the pressures are wrong
    there; the componentwise backward error of the linear system alone, ~macheps, does
    not show it)."""
    ref, _ = solve_penalty_checked(body8, 1e-8 / 8, -D, S=body8.S_hat)
    res, chk = solve_penalty_checked(body8, 1e-20 / 8, -D, S=body8.S_hat)
    assert chk.condition_number * MACHEPS > 1
    assert chk.lapack_warning and "LAPACK" in chk.reason
    assert not res.converged and "ill-conditioned" in res.reason and not chk.accepted
    p_ref, p = ref.pressure_nodes[1].max(), res.pressure_nodes[1].max()
    assert abs(p - p_ref) > 0.1 * p_ref                  # the answer is indeed wrong


def test_check_bad_input(body8):
    res = solve_penalty(body8, 1e-6, -D)
    with pytest.raises(ValueError, match="keep_jacobian"):
        check_penalty_solution(body8, res, -D)
    res = solve_penalty(body8, 1e-6, -D, keep_jacobian=True)
    with pytest.raises(ValueError, match="accept_rel"):
        check_penalty_solution(body8, res, -D, accept_rel=0.0)
