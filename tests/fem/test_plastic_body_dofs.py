"""ElastoPlasticFE.dofs_on / dof_coordinates: the protocol of the other FE bodies, on
the dof numbering of the plastic body's own basis (issue 26)."""

import numpy as np
import pytest

from hpfebe.constitutive.j2 import J2Material
from hpfebe.fem.elasticity import ElasticBody, rectangle_mesh
from hpfebe.fem.plastic_body import ElastoPlasticFE

MAT = J2Material(266926.0, 0.29, 4.0, 450.0, 1.0)


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_dofs_on_and_coordinates(kind):
    mesh = rectangle_mesh(0, 2, 0, 1, 4, 2, kind)
    fe = ElastoPlasticFE(mesh, MAT)
    xy = fe.dof_coordinates()
    assert xy.shape == (fe.ndofs, 2)
    # coordinates on the body's own basis: dof k of component c sits at its vertex
    for c in (0, 1):
        assert np.array_equal(xy[fe.basis.nodal_dofs[c]], mesh.p.T)
    bottom = fe.dofs_on("bottom")
    assert bottom.size == 2 * 5 and np.all(xy[bottom, 1] == 0)
    assert np.array_equal(np.sort(np.concatenate([fe.dofs_on("bottom", 0),
                                                  fe.dofs_on("bottom", 1)])), bottom)
    assert np.all(fe.dofs_on(["left", "right"], 1) % 2 == 1)
    assert np.array_equal(fe.dofs_on("top"), ElasticBody(mesh, MAT.E, MAT.nu).dofs_on("top"))
    with pytest.raises(ValueError, match="boundary label"):
        fe.dofs_on("nowhere")
