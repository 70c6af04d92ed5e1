"""The multilevel additive-Schwarz preconditioner of the compressed V (issue 27,
hpfebe.bem.hmatrix.precond): the preconditioned condition number (dense eigenvalues at
small N) stays nearly constant in N where block Jacobi's grows like N; CG's iterations
grow slowly; the solution is the one of the H-matrix's own (dense) system to the CG
tolerance; Laplace and Lame, p = 1, 2, 4 and mixed degrees; the keyword is checked."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM
from hpfebe.bem.hmatrix import HMatrixSettings, Multilevel
from hpfebe.scenes.bem_scaling import ScalingRun, operators


def _hm(pde, N, p, kind="multilevel"):
    hm = operators(ScalingRun(pde, N, p, "hmatrix", 1e-8)).hm
    hm.settings = replace(hm.settings, preconditioner=kind)
    return hm


def _cond(hm):
    """Dense extreme eigenvalues of C^{-1} V (C^{-1} = L L^T, eigenvalues of L^T V L)."""
    H = hm.hmatrix("V")
    n = H.shape[0]
    A = H.matvec(np.eye(n))
    B = hm.preconditioner_V().solve(np.eye(n))
    assert np.allclose(B, B.T, rtol=0, atol=1e-12 * abs(B).max())     # symmetric
    Lc = np.linalg.cholesky(0.5 * (B + B.T))                          # and SPD
    ev = np.linalg.eigvalsh(Lc.T @ (0.5 * (A + A.T)) @ Lc)
    assert ev[0] > 0.0
    return ev[-1] / ev[0]


def test_condition_number_laplace_p1():
    """Laplace p = 1, N = 256 and 1024: block Jacobi's condition number grows like N
    (measured 33.8 -> 128.7, x 3.8); the multilevel one like log^2 N at most (Haar
    functions in H^{-1/2}: (log 1024 / log 256)^2 = 1.56; measured 7.4 -> 10.3).  Asserted:
    growth <= 2 (Jacobi's 4 excluded), and <= Jacobi's / 4 at N = 1024."""
    ml = [_cond(_hm("laplace", N, 1)) for N in (256, 1024)]
    jac = [_cond(_hm("laplace", N, 1, "jacobi")) for N in (256, 1024)]
    assert jac[1] / jac[0] > 3.0                       # the growth the method removes
    assert ml[1] / ml[0] <= 2.0
    assert ml[0] < jac[0] and ml[1] <= jac[1] / 4.0


@pytest.mark.parametrize("pde,p,N", [("laplace", 2, 128), ("laplace", 4, 64),
                                     ("lame", 1, 128), ("lame", 2, 64)])
def test_condition_number_other_cases(pde, p, N):
    """Higher p and Lame (2 components: a 2 x 2 Haar block per cluster), N and 4N
    (256 -> 1024 unknowns): Jacobi's condition number grows like N (measured x 3.8 ..
    3.9), the multilevel one by at most the log^2 factor (log 4N / log N)^2 <= 1.8 for
    N >= 64 (measured x 1.37 .. 1.44, to 11.4 .. 13.0).  Asserted: growth <= 2, and
    <= Jacobi's / 4 at 4N (measured / 12 .. / 26)."""
    ml = [_cond(_hm(pde, n, p)) for n in (N, 4 * N)]
    jac = [_cond(_hm(pde, n, p, "jacobi")) for n in (N, 4 * N)]
    assert jac[1] / jac[0] > 3.0
    assert ml[1] / ml[0] <= 2.0
    assert ml[1] <= jac[1] / 4.0


def test_cg_iterations_grow_slowly():
    """CG iterations on a random right-hand side, Laplace p = 1, N = 256 ... 4096
    (inner tolerance 1e-11): iterations ~ sqrt(cond) log(1/tol), hence ~ log N for the
    multilevel preconditioner (log 4096 / log 256 = 1.5; measured 28 -> 45) and ~ sqrt N
    for Jacobi (x 4; measured 41 -> 99).  Asserted: growth <= 2 and fewer than Jacobi."""
    it = {}
    for kind in ("multilevel", "jacobi"):
        for N in (256, 4096):
            hm = _hm("laplace", N, 1, kind)
            b = np.random.default_rng(0).standard_normal(hm.hmatrix("V").shape[0])
            hm.solve_V(b)
            it[kind, N] = hm.solves[-1].iterations
    assert it["multilevel", 4096] / it["multilevel", 256] <= 2.0
    assert it["jacobi", 4096] / it["jacobi", 256] > 2.0
    assert it["multilevel", 4096] < it["jacobi", 4096] / 1.5


def _mesh_case(pde, p, mixed=False):
    mesh = BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)],
                                n=12, p=p)
    if mixed:
        mesh = mesh.with_degrees(1 + np.arange(mesh.n_elements) % 4)
    if pde == "laplace":
        return LaplaceBEM(mesh, compression="hmatrix", tol=1e-8).hm
    return LameBEM(mesh, 1000.0, 0.3, compression="hmatrix", tol=1e-8).hm


@pytest.mark.parametrize("pde,p,mixed", [("laplace", 1, False), ("laplace", 2, False),
                                         ("laplace", 4, False), ("laplace", 1, True),
                                         ("lame", 1, False), ("lame", 4, False)])
def test_solution_equals_dense(pde, p, mixed):
    """solve_V against the dense solve of the same H-matrix (global numbering), several
    right-hand sides at once: ||x - x*|| / ||x*|| <= cond_2(V) * solver tolerance (CG's
    Euclidean residual bound); both preconditioners."""
    hm = _mesh_case(pde, p, mixed)
    A = hm.V @ np.eye(hm.V.shape[0])
    b = np.random.default_rng(p).standard_normal((A.shape[0], 3))
    x_star = np.linalg.solve(A, b)
    ev = np.linalg.eigvalsh(0.5 * (A + A.T))
    bound = ev[-1] / ev[0] * hm.settings.inner_tol
    for kind in ("multilevel", "jacobi"):
        hm.settings = replace(hm.settings, preconditioner=kind)
        x = hm.solve_V(b)
        assert hm.solves[-1].converged
        assert np.linalg.norm(x - x_star) / np.linalg.norm(x_star) <= bound, kind
    hm.settings = replace(hm.settings, preconditioner="multilevel")
    assert isinstance(hm.preconditioner_V(), Multilevel)


def test_preconditioner_keyword_checked():
    """An unknown preconditioner is refused with its name in the message."""
    with pytest.raises(ValueError, match="preconditioner"):
        HMatrixSettings(preconditioner="ilu")
    assert HMatrixSettings().preconditioner == "multilevel"


def test_lanczos_condition_estimate():
    """CG's Lanczos estimate of cond(C^{-1} V) against the dense eigenvalues (Laplace
    p = 1, N = 1024): a lower bound (Ritz values lie inside the spectrum) within 10 % of
    it once CG has run to 1e-11 (the extreme Ritz values converge first)."""
    for kind in ("multilevel", "jacobi"):
        hm = _hm("laplace", 1024, 1, kind)
        exact = _cond(hm)
        hm.solve_V(np.random.default_rng(0).standard_normal(hm.hmatrix("V").shape[0]))
        est = hm.solves[-1].counts["cond_estimate"]
        assert exact * 0.9 <= est <= exact * (1 + 1e-8), kind


def test_warning_when_tol_too_coarse_for_the_conditioning():
    """cond_2(V) >= the leaf blocks' eigenvalue ratio (Cauchy interlacing; Laplace p = 4,
    N = 256: 736, measured); tol = 0.5 then leaves no digit: a UserWarning naming
    tol; at tol = 1e-8 none."""
    import warnings
    for tol, warns in ((0.5, True), (1e-8, False)):
        hm = operators(ScalingRun("laplace", 256, 4, "hmatrix", tol)).hm
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            hm.preconditioner_V()
        hits = [w for w in got if issubclass(w.category, UserWarning)
                and "tol=" in str(w.message)]
        assert bool(hits) == warns, tol
