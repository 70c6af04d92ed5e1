"""The closed-form P1 stiffness of ElasticBody (assembly="closed_form") against
scikit-fem's quadrature assembly."""

import numpy as np
import pytest
import skfem

from hpfebe.fem import ElasticBody, rectangle_mesh


@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_closed_form_p1_stiffness_equals_quadrature(plane):
    """Same matrix to round-off on a distorted, locally refined mesh (cells of both
    orientations), and the same energy of a random field."""
    rng = np.random.default_rng(7)
    m = rectangle_mesh(-0.5, 0.5, 0.0, 2.0, 4, 8, kind="tri")
    m = m.refined(np.arange(0, m.t.shape[1], 3))
    inner = (np.abs(m.p[0]) < 0.49) & (m.p[1] > 0.01) & (m.p[1] < 1.99)
    m = skfem.MeshTri(m.p + 0.03 * rng.standard_normal(m.p.shape) * inner, m.t)
    a = ElasticBody(m, 266926.0, 0.29, plane)
    b = ElasticBody(m, 266926.0, 0.29, plane, assembly="closed_form")
    scale = abs(a.K).max()
    assert abs(a.K - b.K).max() <= 1e-13 * scale
    assert (b.K - b.K.T).count_nonzero() == 0 or abs(b.K - b.K.T).max() <= 1e-14 * scale
    u = rng.standard_normal(a.ndofs)
    assert np.isclose(u @ (a.K @ u), u @ (b.K @ u), rtol=1e-12)
    with pytest.raises(ValueError, match="assembly"):
        ElasticBody(m, 1.0, 0.3, assembly="exact")


def test_closed_form_falls_back_to_quadrature_on_quads():
    m = rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2, kind="quad")
    a = ElasticBody(m, 1.0, 0.3)
    b = ElasticBody(m, 1.0, 0.3, assembly="closed_form")
    assert abs(a.K - b.K).max() == 0.0
