"""The mixed (U, psi) penalty solver on the compressed Lame operators
(hpfebe.contact.matrix_free): agreement with the dense penalty solve, reported
non-convergence, refused input."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401  (sp.linalg)

from hpfebe.bem import LameBEM
from hpfebe.contact import matrix_free as mf
from hpfebe.contact.matrix_free import solve_penalty_mixed
from hpfebe.scenes import bem_hertz as bh
from hpfebe.scenes.materials import E, NU


def _bem(n, compression="hmatrix", tol=1e-6):
    return LameBEM(bh.half_disk(n), E, NU, zero_force=False, compression=compression,
                   tol=tol)


@pytest.mark.parametrize("tol", [1e-6, 1e-8])
def test_agrees_with_dense_penalty_solve(tol):
    run = bh.HertzRun(128, tol=tol)
    comp = bh.solve(run)
    dense = bh.solve(run, compression=None)
    assert comp["converged"] and dense["converged"]
    assert comp["backward_error"] <= tol
    # the compressed operators are accurate to tol: so is the solution
    diff = np.linalg.norm(comp["U"] - dense["U"]) / np.linalg.norm(dense["U"])
    assert diff <= tol
    assert comp["a"] == pytest.approx(dense["a"], rel=10 * tol)


def test_gmres_and_deflation_variants_agree():
    bem = _bem(64)
    run = bh.HertzRun(64)
    a = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta),
                            preconditioner="near_field", coarse=None)
    b = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta),
                            preconditioner="near_field", coarse=8)
    c = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta),
                            preconditioner="multilevel")
    assert a.converged and b.converged and c.converged
    assert (a.preconditioner, c.preconditioner) == ("near_field", "multilevel")
    assert np.linalg.norm(a.U - b.U) <= 1e-6 * np.linalg.norm(a.U)
    assert np.linalg.norm(a.U - c.U) <= 1e-6 * np.linalg.norm(a.U)


def test_auto_preconditioner_switches_at_the_measured_crossover(monkeypatch):
    bem = _bem(64)
    run = bh.HertzRun(64)
    small = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta))
    monkeypatch.setattr(mf, "AUTO_NEAR_FIELD_MAX", 32)
    large = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta))
    assert (small.preconditioner, large.preconditioner) == ("near_field", "multilevel")
    assert np.linalg.norm(small.U - large.U) <= 1e-6 * np.linalg.norm(small.U)


def test_non_convergence_is_reported_with_a_reason():
    bem = _bem(64)
    run = bh.HertzRun(64)
    res = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta), max_iter=1)
    assert not res.converged
    assert res.reason.startswith("max_iter") and "backward errors" in res.reason
    res = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta), restart=2,
                              gmres_maxiter=1, gmres_tol=1e-12)
    assert not res.converged and res.reason.startswith("gmres did not converge")


def test_bad_input_names_the_parameter():
    bem = _bem(32)
    with pytest.raises(ValueError, match="eps"):
        solve_penalty_mixed(bem, 0.0, bh.gap, (0.0, -1e-3))
    with pytest.raises(ValueError, match="eps"):
        solve_penalty_mixed(bem, -1.0, bh.gap, (0.0, -1e-3))
    for tol in (0.0, 1.0, -1e-3, np.nan):
        with pytest.raises(ValueError, match="tol"):
            solve_penalty_mixed(bem, 1e-6, bh.gap, (0.0, -1e-3), tol=tol)
    with pytest.raises(ValueError, match="dirichlet_displacement"):
        solve_penalty_mixed(bem, 1e-6, bh.gap, (0.0, np.nan))
    with pytest.raises(ValueError, match="compression"):
        solve_penalty_mixed(_bem(32, compression=None), 1e-6, bh.gap, (0.0, -1e-3))
    with pytest.raises(ValueError, match="zero_force"):
        solve_penalty_mixed(LameBEM(bh.half_disk(32), E, NU, compression="hmatrix"),
                            1e-6, bh.gap, (0.0, -1e-3))
    with pytest.raises(ValueError, match="preconditioner"):
        solve_penalty_mixed(bem, 1e-6, bh.gap, (0.0, -1e-3), preconditioner="lu")
    with pytest.raises(ValueError, match="contact_label"):
        solve_penalty_mixed(bem, 1e-6, bh.gap, (0.0, -1e-3), contact_label="X")
    with pytest.raises(ValueError, match="delta"):
        bh.HertzRun(64, delta=-1e-3)
    with pytest.raises(ValueError, match="delta"):
        bh.HertzRun(64, delta=0.0)


def _system_at_solution(n):
    """The mixed system of the Hertz run with N = n and the penalty Jacobian at its
    solution (the contact set of the last Newton steps); multilevel preconditioner."""
    run = bh.HertzRun(n)
    bem = _bem(n)
    res = solve_penalty_mixed(bem, run.eps, bh.gap, (0.0, -run.delta), tol=run.tol,
                              preconditioner="multilevel")
    sysm = mf._MixedSystem(bem, bh.gap, (0.0, -run.delta), None, "C", "D", None,
                           "multilevel")
    C = sysm.pen.jacobian(res.U, run.eps, sysm.n)
    return res, sysm, C[sysm.free][:, sysm.free]


@pytest.mark.parametrize("n", [128, 512])
def test_primal_multilevel_is_spectrally_equivalent_to_w_plus_c(n):
    # P_A^{-1} (W + C_eps): eigenvalues in a fixed interval (measured 0.86-3.5 at
    # N = 128, 0.84-6.0 at N = 512); the fine blocks alone leave lambda_min -> 0 like h
    _, sysm, Cff = _system_at_solution(n)
    eye = np.eye(sysm.nf)
    A = sysm.mixed0(np.vstack([eye, np.zeros((sysm.m, sysm.nf))]))[:sysm.nf] + Cff
    ev = np.linalg.eigvals(sysm.PA.update(Cff)(eye) @ A).real
    assert ev.min() >= 0.5 and ev.max() <= 10.0
    fine = sp.linalg.splu(sysm.PA._fine(Cff)).solve(eye)
    assert np.linalg.eigvals(fine @ A).real.min() < 0.5 * ev.min()


def test_gmres_iterations_bounded_in_n():
    # multilevel block-triangular preconditioner: GMRES iterations per Newton step
    # nearly constant in N (measured max 62 at N = 128, 87 at N = 512, 82 at 256, 93 at
    # 1024, 112 at 4096); the near-field LU with deflation grew (max 95 at N = 256, 391
    # at 1024, 952 at 4096)
    its = {}
    for n in (128, 512):
        res, _, _ = _system_at_solution(n)
        assert res.converged
        its[n] = max(res.gmres_iterations)
    assert its[512] <= 1.6 * its[128] and its[512] <= 110
