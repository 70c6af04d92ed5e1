"""Issue 25, class "NaN": a NaN never becomes history, never silently switches off a
refinement, and is refused by name before numpy or scipy meet it."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.adaptivity import adapt
from hpfebe.adaptivity.mortar_estimator import hp_refine
from hpfebe.bem.lame import LameBEM
from hpfebe.constitutive.j2 import J2Material
from hpfebe.fem.elasticity import rectangle_mesh
from hpfebe.fem.plastic_body import DisplacementSteps, ElastoPlasticFE

MAT = J2Material(266926.0, 0.29, 4.0, 450.0, 1.0)
SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def test_commit_of_a_nan_state_is_refused_and_keeps_the_history():
    fe = ElastoPlasticFE(rectangle_mesh(0, 2, 0, 1, 2, 1), MAT)
    u = np.random.default_rng(0).normal(scale=1e-2, size=fe.ndofs)   # plastic
    fe.commit(u)
    before = fe.committed.copy(), fe.sigma.copy()
    bad = u.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match=r"u \(the displacement committed as history\) "
                                         r"must be finite, got nan at flat index 3"):
        fe.commit(bad)
    # the committed history is the one before the refused commit, bit for bit
    assert np.array_equal(fe.committed.eps_p, before[0].eps_p)
    assert np.array_equal(fe.committed.alpha, before[0].alpha)
    assert np.array_equal(fe.sigma, before[1])
    with pytest.raises(ValueError, match="f_ext must be finite"):
        DisplacementSteps(fe, [0], [0.0], f_ext=np.full(fe.ndofs, np.nan))


@pytest.mark.parametrize("where", [0, 5])
def test_hp_refine_with_a_nan_indicator_is_refused(where):
    """A NaN made eta >= q2 max(eta) false everywhere: every marked element got p + 1,
    none was bisected, without a word."""
    mesh = BoundaryMesh.polygon(SQUARE, n=2, p=1)
    eta = np.linspace(1.0, 2.0, mesh.n_elements)
    marked = np.ones(mesh.n_elements, dtype=bool)
    ok = hp_refine(mesh, marked, eta, 0.9)
    n_h = int(np.sum(eta >= 0.9 * eta.max()))             # 2 bisected, 6 get p + 1
    assert n_h == 2 and ok.n_elements == mesh.n_elements + n_h
    eta[where] = np.nan
    with pytest.raises(ValueError, match=rf"eta \(indicators\) must be finite, got nan "
                                         rf"at index \({where},\)"):
        hp_refine(mesh, marked, eta, 0.9)
    with pytest.raises(ValueError, match="h_fraction"):
        hp_refine(mesh, marked, np.ones(mesh.n_elements), np.nan)


def test_adapt_with_a_nan_estimator_names_the_step():
    mesh = BoundaryMesh.polygon(SQUARE, n=2, p=1)

    def estimate(m, state):
        eta = np.ones(m.n_elements)
        eta[-1] = np.nan if m.n_elements > 8 else 1.0
        return eta

    with pytest.raises(ValueError, match=r"eta \(indicators of mesh 0 at step 1\) must be "
                                         r"finite, got nan"):
        adapt(mesh, lambda m: (None, m.n_elements), estimate, n_steps=3)


@pytest.mark.parametrize("psi_entry", [np.nan, np.inf])
def test_nan_density_is_not_called_a_boundary_point(psi_entry):
    """A NaN psi used to be reported as "potential evaluated on the boundary Gamma"."""
    bem = LameBEM(BoundaryMesh.polygon(SQUARE, n=2, p=1), 1.0, 0.3)
    U = np.zeros(2 * bem.V_space.ndof)
    psi = np.zeros(2 * bem.W_space.ndof)
    psi[1] = psi_entry
    with pytest.raises(ValueError, match=r"psi must be finite, got (nan|inf) at index \(1,\)"):
        bem.representation([[0.5, 0.5]], U, psi)
