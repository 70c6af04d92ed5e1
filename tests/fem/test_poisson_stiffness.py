"""hpfebe.fem.poisson.stiffness: the batched Q_p stiffness against scikit-fem's
pairwise ``asm(laplace, basis)``."""

import numpy as np
import pytest
from skfem import Basis, MeshQuad, asm

from hpfebe.fem import poisson
from hpfebe.fem.poisson import PoissonFE, laplace, stiffness


def _domain():
    # stretched, unequal cells (breaks the symmetries of a uniform square mesh)
    return MeshQuad.init_tensor(np.array([0.0, 0.1, 0.45, 1.0]), np.array([0.0, 0.7, 1.0]))


@pytest.mark.parametrize("p", [1, 2, 4, 7])
def test_stiffness_equals_the_pairwise_assembly(p):
    fe = PoissonFE(_domain(), p)
    K, ref = stiffness(fe.basis), asm(laplace, fe.basis).tocsr()
    scale = abs(ref).max()
    assert abs(K - ref).max() <= 1e-13 * scale
    assert abs(K - K.T).max() == 0.0                      # exactly symmetric
    # constants are in the kernel (1: the vertex functions' sum, hierarchical basis)
    one = np.zeros(K.shape[0])
    one[fe.basis.nodal_dofs[0]] = 1.0
    assert np.abs(K @ one).max() <= 1e-13 * scale
    # the round-off entries of orthogonal pairs are not in the pattern
    assert K.nnz <= ref.nnz


def test_stiffness_drops_only_round_off_entries():
    fe = PoissonFE(_domain(), 6)
    K, ref = stiffness(fe.basis), asm(laplace, fe.basis).tocsr()
    dropped = abs(ref) - abs(ref).multiply(K != 0)
    assert dropped.nnz > 0 and dropped.max() <= 1e-14 * abs(ref).max()


@pytest.mark.parametrize("variant", ["tensor", "rotated vertices", "sheared"])
def test_affine_mapping_agrees_with_the_bilinear_one(variant):
    mesh = _domain()
    if variant == "rotated vertices":             # the same cells, another first vertex
        mesh = MeshQuad(mesh.p, np.roll(mesh.t, 1, axis=0))
    elif variant == "sheared":                    # parallelograms
        mesh = MeshQuad(mesh.p + np.array([[0.3], [0.0]]) * mesh.p[1], mesh.t)
    affine = poisson._AffineQuadMapping.of(mesh)
    assert affine is not None
    fe = PoissonFE(mesh, 3)                       # built on the affine mapping
    general = Basis(mesh, fe.element, mapping=mesh._mapping(), intorder=2 * 3 + 1)
    assert np.abs(fe.basis.dx - general.dx).max() <= 1e-14 * np.abs(general.dx).max()
    for i in range(general.Nbfun):
        g, r = general.basis[i][0].grad, fe.basis.basis[i][0].grad
        assert np.abs(g - r).max() <= 1e-13 * np.abs(g).max()
    pts = np.array([[0.05, 0.2], [0.3, 0.9], [0.99, 0.01]])
    pts[:, 0] += 0.3 * pts[:, 1] if variant == "sheared" else 0.0
    cells = mesh.element_finder()(*pts.T)
    assert np.allclose(affine.invF(pts.T[:, :, None], tind=cells),
                       mesh._mapping().invF(pts.T[:, :, None], tind=cells), atol=1e-12)


def test_affine_mapping_refuses_other_quadrilaterals():
    mesh = _domain()
    p = mesh.p.copy()
    inner = np.flatnonzero((p[0] > 0) & (p[0] < 1) & (p[1] > 0) & (p[1] < 1))
    p[:, inner[0]] += [0.02, 0.03]                # four cells become trapezoids
    mesh = MeshQuad(p, mesh.t)
    assert poisson._AffineQuadMapping.of(mesh) is None
    fe = PoissonFE(mesh, 2)                       # the general mapping: still correct
    K = stiffness(fe.basis)
    assert abs(K - asm(laplace, fe.basis).tocsr()).max() <= 1e-13 * abs(K).max()
