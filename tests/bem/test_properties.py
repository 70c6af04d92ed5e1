"""Property-based checks (hypothesis) of the Laplace operators on random star-shaped
polygons with random element counts and degrees."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hpfebe import BoundaryMesh
from hpfebe.bem import LaplaceBEM


@st.composite
def star_polygons(draw):
    m = draw(st.integers(3, 7))
    radii = draw(st.lists(st.floats(0.3, 2.0), min_size=m, max_size=m))
    jitter = draw(st.lists(st.floats(-0.3, 0.3), min_size=m, max_size=m))
    ang = 2 * np.pi * (np.arange(m) + np.array(jitter)) / m
    verts = np.column_stack([np.array(radii) * np.cos(ang), np.array(radii) * np.sin(ang)])
    n = draw(st.lists(st.integers(1, 3), min_size=m, max_size=m))
    p = draw(st.lists(st.integers(1, 4), min_size=m, max_size=m))
    return BoundaryMesh.polygon(verts, n=n, p=p)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(star_polygons())
def test_operator_identities_on_random_polygons(mesh):
    op = LaplaceBEM(mesh)
    assert np.linalg.eigvalsh(op.V).min() > 0                         # V SPD
    one = np.ones(op.V_space.ndof)
    assert np.abs(op.B @ one).max() < 1e-12                           # (K + 1/2) 1 = 0
    S = op.S_hat
    assert np.abs(S @ one).max() < 1e-10 * np.abs(S).max()            # S_hat 1 = 0
    lam = np.linalg.eigvalsh(S)
    assert lam.min() > -1e-10 * lam.max()                             # S_hat SPSD
    # u = x is harmonic and linear: the interpolant is exact, its Neumann datum n_x is
    # constant per element (in W_hp), so Psi reproduces it up to rounding
    psi = op.Psi(op.V_space.interpolate(lambda pts: pts[:, 0]))
    elem = np.arange(mesh.n_elements)
    assert np.allclose(op.W_space.evaluate(psi, elem, np.zeros(len(elem))),
                       mesh.normals[:, 0], atol=1e-10)
