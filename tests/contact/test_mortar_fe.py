"""The mortar FE/FE contact with an elastoplastic work piece (hpfebe.contact.mortar_fe,
Section 4.4, the scene of hpfebe.scenes.section44): the DtN algorithm (Algorithm 4.3
with the elastoplastic Neumann problem) converges to the solution of the monolithic
semismooth Newton method on a small version of the scene; non-convergence of DtN is
detected for a diverging damping pair."""

import numpy as np
import pytest

from hpfebe.contact import NeumannSettings
from hpfebe.contact.mortar_fe import FEMortarContact
from hpfebe.coupling.mortar import fe_trace_mesh
from hpfebe.fem import rectangle_mesh
from hpfebe.scenes import READINGS, DtNReadings, dtn_settings, section44_scene


@pytest.fixture(scope="module")
def scene():
    # stamp 4 x 8 Q1 cells (5 contact nodes), work piece 16 x 8; the rest as Section 4.4
    return section44_scene((4, 8), (16, 8), formulation="full")


@pytest.fixture(scope="module")
def mono(scene):
    sol = scene.monolithic(tol=1e-10)
    assert sol.info.converged, sol.info.reason
    return sol


def test_dtn_matches_monolithic(scene, mono):
    sol = scene.dtn(dtn_settings(0.5, 0.5, tol=1e-10), NeumannSettings(1e-10))
    assert sol.info.converged, sol.info.reason
    # the work piece yields: the problem is elastoplastic
    assert sol.extra["fields"]["eps_p_norm_mean"].max() > 0
    assert mono.extra["fields"]["eps_p_norm_mean"].max() > 0
    for key in ("u1", "u2"):
        a, b = sol.extra[key], mono.extra[key]
        assert np.abs(a - b).max() <= 1e-7 * np.abs(b).max(), key
    assert np.abs(sol.P - mono.P).max() <= 1e-7 * np.abs(mono.P).max()
    # the Tresca conditions at the contact nodes and the work piece's equilibrium
    r = scene.kkt_residual(sol)
    assert r["lam_excess"] <= 1e-12 and r["complementarity"] <= 1e-8
    assert r["equilibrium2"] <= 1e-8
    # nothing committed: the work piece keeps its virgin history for the next run
    assert np.all(scene.work.committed.alpha == 0)


def test_dtn_default_tolerances_close_to_monolithic(scene, mono):
    """TOL_DtN = 1e-6 (the thesis's): U2 within 1e-5 of the monolithic solution."""
    readings = DtNReadings(scene)
    sol = scene.dtn(dtn_settings(0.5, 0.7), hook=readings)
    assert sol.info.converged, sol.info.reason
    assert np.abs(sol.extra["u2"] - mono.extra["u2"]).max() <= \
        1e-5 * np.abs(mono.extra["u2"]).max()
    # Uzawa: several iterations in the first DtN iteration, then at most 2
    uz = [s.counts["uzawa"] for s in sol.info.steps]
    assert uz[0] >= 2 and max(uz[1:]) <= 2
    # every reading of the stopping rule recorded per iteration by the hook; the
    # fixed_point stop (relative to the new P) and the printed one (relative to the
    # previous P) agree
    rd = readings.values
    assert set(rd) == set(READINGS)
    assert all(len(v) == sol.info.iterations for v in rd.values())
    assert np.allclose(rd["P_l2_new"], sol.info.counts["relative_increments"])
    assert np.isinf(rd["P_l2_prev"][0]) and np.isinf(rd["U2_l2_prev"][0])   # P_0 = 0
    first = lambda v: int(np.flatnonzero(np.asarray(v) <= 1e-6)[0]) + 1  # noqa: E731
    assert first(rd["P_l2_prev"]) == first(rd["P_l2_new"]) == sol.info.iterations


@pytest.mark.parametrize("omega_N", [0.3, 0.7])
def test_tangential_increments_contract_by_one_minus_omega_N(scene, omega_N):
    """Where the stamp slides, step 6 relaxes the tangential traction alone: the
    tangential part of P^k - P^k-1 shrinks by exactly 1 - omega_N per DtN iteration,
    whatever omega_D does, and bounds the printed stopping rule from below."""
    readings = DtNReadings(scene)
    sol = scene.dtn(dtn_settings(0.5, omega_N, tol=1e-8), hook=readings)
    assert sol.info.converged, sol.info.reason
    # every contact node slides (|lambda| = 1) but the middle one (x = 0, symmetry)
    lam = np.abs(sol.lam)
    assert np.all((lam >= 1 - 1e-12) | (lam <= 1e-9)) and np.sum(lam <= 1e-9) == 1
    rd = readings.values
    t = np.asarray(rd["P_t_l2_prev"])[1:]
    a = (t * np.asarray(sol.info.counts["P_norms"])[: t.size])[t > 1e-9]
    assert a.size >= 4
    assert np.abs(a[1:] / a[:-1] - (1 - omega_N)).max() <= 1e-6
    assert np.all(np.asarray(rd["P_t_l2_prev"]) <= np.asarray(rd["P_l2_prev"]))


def test_non_yielding_work_piece_is_solved():
    """sigma_Y far beyond the small-strain range (an elastic work piece): the Newton
    floor must not accept an undeformed work piece (it did with sigma_Y x h as floor)."""
    sc = section44_scene((4, 8), (16, 8), sigma_Y=4e12, formulation="full")
    sol = sc.dtn(dtn_settings(0.5, 0.7))
    assert sol.info.converged, sol.info.reason
    assert sc.kkt_residual(sol)["equilibrium2"] <= 1e-7
    assert sol.extra["fields"]["eps_p_norm_mean"].max() == 0
    assert np.abs(sol.extra["u2"][0::2]).max() > 1e-7        # the work piece deforms


def test_divergence_detected(scene):
    sol = scene.dtn(dtn_settings(0.9, 1.0, max_iter=30))
    assert not sol.info.converged
    assert sol.info.reason.startswith(("max_iter", "diverged", "inner solve",
                                       "no solution"))
    assert sol.info.iterations <= 30


def test_bad_input(scene):
    with pytest.raises(ValueError, match="omega_D"):
        dtn_settings(0.0, 0.5)
    with pytest.raises(ValueError, match="omega_N"):
        dtn_settings(0.5, 1.5)
    with pytest.raises(ValueError, match="rho"):
        dtn_settings(0.5, 0.5, rho=-1.0)
    with pytest.raises(ValueError, match="newton tol"):
        NeumannSettings(tol=0.0)
    with pytest.raises(ValueError, match="F"):
        FEMortarContact(scene.stamp, scene.work, ("top", (0, 0)), ("bottom", (0, 1e-4)),
                        -1.0)
    with pytest.raises(ValueError, match="dirichlet1"):
        FEMortarContact(scene.stamp, scene.work, ("bottom", (0, 0)), ("bottom", (0, 1e-4)),
                        0.2)
    with pytest.raises(ValueError, match="contact"):
        fe_trace_mesh(rectangle_mesh(0, 1, 0, 1, 2, 2), "middle")


def test_trace_mesh_vertices():
    m = rectangle_mesh(-2, 2, -2, 0, 8, 4)
    bm, space, vertex = fe_trace_mesh(m, "top")
    top = space.dofs_on("C")
    assert top.size == 9
    assert np.allclose(m.p[1, vertex[top]], 0.0)
    assert np.allclose(np.sort(m.p[0, vertex[top]]), np.linspace(-2, 2, 9))


def test_stamp_condensed_once(scene, monkeypatch):
    """The stamp's Schur complement is built with the scene and reused by every DtN run
    (no CondensedBody, no new Cholesky factorisation of the stamp, per damping pair)."""
    import hpfebe.bodies.condensed as condensed
    import hpfebe.contact.mortar_fe as mortar_fe

    def refactorised(*args, **kwargs):
        raise AssertionError("the stamp was factorised again")

    monkeypatch.setattr(condensed.sla, "cho_factor", refactorised)
    monkeypatch.setattr(mortar_fe, "CondensedBody", refactorised)
    body1 = scene.body1
    for pair in ((0.5, 0.7), (0.7, 0.5)):
        assert scene.dtn(dtn_settings(*pair)).info.converged
    assert scene.body1 is body1


def test_spd_band_solve():
    """Banded Cholesky of the Newton step of step 2: the SuperLU solution to round-off;
    None (SuperLU fallback) for a non-symmetric, an indefinite or a wide-band matrix."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from hpfebe.contact.mortar_fe import spd_band_solve

    n = 200
    A = sp.diags([-1.0, -0.5, 4.0, -0.5, -1.0], [-2, -1, 0, 1, 2], shape=(n, n)).tocsr()
    b = np.sin(np.arange(n))
    x = spd_band_solve(A, b)
    ref = spla.spsolve(A.tocsc(), b)
    assert np.abs(x - ref).max() <= 1e-13 * np.abs(ref).max()
    assert spd_band_solve(A + sp.diags([0.1], [1], shape=(n, n)), b) is None
    assert spd_band_solve(-A, b) is None
    wide = A + sp.coo_matrix(([1e-3, 1e-3], ([0, n - 1], [n - 1, 0])), shape=(n, n))
    assert spd_band_solve(wide, b) is None


def test_dtn_newton_uses_band_solve(scene, monkeypatch):
    """Step 2 solves its Newton systems by the banded Cholesky (no SuperLU call)."""
    import scipy.sparse.linalg as spla

    def fail(*a, **k):
        raise AssertionError("spsolve called")

    monkeypatch.setattr(spla, "spsolve", fail)
    P = np.tile([0.0, 5.0], scene.c2.size // 2)       # a yield-level push on Gamma^2_C
    u2, info = scene.neumann(P)
    assert info.converged and info.iterations > 0, info.reason
    assert scene.work_fields(u2)["eps_p_norm"].max() > 0       # plastic: a real Newton
