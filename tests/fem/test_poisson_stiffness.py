"""hpfebe.fem.poisson.stiffness: the batched Q_p stiffness against scikit-fem's
pairwise ``asm(laplace, basis)``."""

import numpy as np
import pytest
from skfem import MeshQuad, asm

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
