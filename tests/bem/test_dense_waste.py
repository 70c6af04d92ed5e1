"""The dense path without its waste (issue 27): the one-thread sandwich W = T^T V T by its
upper triangle and a tiled mirror, S_hat symmetrised in place with its intermediates
released - the same floats as the former computations (equal arrays, sign bits too)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM, sandwich
from hpfebe.bem.assembly_kernels import _sandwich_rows, _symmetrise, _transpose_csr

L_SHAPE = [(0, 0), (2, 0), (2, 2), (1, 2), (1, 1), (0, 1)]


def _meshes():
    m = BoundaryMesh.polygon(L_SHAPE, h=0.3, p=1)
    return {"p1": BoundaryMesh.polygon(L_SHAPE, h=0.15, p=1),
            "p3": BoundaryMesh.polygon(L_SHAPE, h=0.4, p=3),
            "mixed": m.with_degrees(np.arange(m.n_elements) % 4 + 1)}


def _equal(a, b):
    return a.dtype == b.dtype and np.array_equal(a, b) and np.array_equal(np.signbit(a),
                                                                           np.signbit(b))


def _former_S_hat(op):
    """S_hat as BoundaryOperators computed it before issue 27 (verbatim)."""
    c, lower = op.V_cho
    Y = sla.solve_triangular(c, op.B, lower=lower)
    S = op.W + Y.T @ Y
    if op.constrained:
        Z = sla.solve_triangular(c, op.constraints, lower=lower)
        YZ = Y.T @ Z
        S -= YZ @ np.linalg.solve(Z.T @ Z, YZ.T)
    return 0.5 * (S + S.T)


@pytest.mark.parametrize("name", ["p1", "p3", "mixed"])
def test_sandwich_one_thread_is_upper_triangle_mirrored(name):
    """both=True (one thread) gives the upper triangle of both=False with its exact mirror,
    and :func:`sandwich` is T^T V T to round-off and exactly symmetric."""
    op = LaplaceBEM(_meshes()[name], closed_form=False)
    T = op.T.tocsr()
    R = _transpose_csr(T.indptr, T.indices, T.data, T.shape[1])
    n = T.shape[1]
    V = np.ascontiguousarray(op.V)
    up = np.zeros((n, n))
    _sandwich_rows(*R, V, up, False, np.arange(n))
    assert np.count_nonzero(np.tril(up, -1)) == 0
    both = np.zeros((n, n))
    _sandwich_rows(*R, V, both, True, np.arange(n))
    assert _equal(both, np.triu(up) + np.triu(up, 1).T)
    W = sandwich(op.T, op.V)
    assert _equal(W, both) and _equal(W, W.T)
    ref = T.T @ (V @ T.toarray())
    assert np.abs(W - ref).max() <= 1e-13 * np.abs(ref).max()


def test_sandwich_both_needs_all_rows():
    op = LaplaceBEM(BoundaryMesh.polygon(L_SHAPE, h=0.5, p=1))
    T = op.T.tocsr()
    R = _transpose_csr(T.indptr, T.indices, T.data, T.shape[1])
    n = T.shape[1]
    with pytest.raises(ValueError, match="all rows"):
        _sandwich_rows(*R, np.ascontiguousarray(op.V), np.zeros((n, n)), True,
                       np.arange(n - 1))


@pytest.mark.parametrize("n", [1, 63, 64, 65, 200])
def test_symmetrise_is_numpys_average(n):
    A = np.random.default_rng(n).standard_normal((n, n))
    A[0, -1] = -0.0 if n > 1 else A[0, -1]
    ref = 0.5 * (A + A.T)
    _symmetrise(A)
    assert _equal(A, ref)


@pytest.mark.parametrize("name", ["p1", "p3", "mixed"])
@pytest.mark.parametrize("constrained", [True, False])
@pytest.mark.parametrize("lame", [False, True])
def test_S_hat_equals_former_computation(name, constrained, lame):
    """The same floats as before; B and Lame's Vt (only W's input) leave the cache and
    come back identical when asked for again."""
    mesh = _meshes()[name]
    if lame:
        op = LameBEM(mesh, 266926.0, 0.29, zero_force=constrained)
        ref = LameBEM(mesh, 266926.0, 0.29, zero_force=constrained)
    else:
        op, ref = LaplaceBEM(mesh, zero_flux=constrained), LaplaceBEM(mesh,
                                                                      zero_flux=constrained)
    Vt = ref.Vt if lame else None
    S = op.S_hat
    assert _equal(S, _former_S_hat(ref))
    assert "B" not in op._cache and _equal(op.B, ref.B)
    if lame:
        assert "Vt" not in op._cache
        assert _equal(op.Vt, Vt)
        assert op.S_hat is S                      # cached, not rebuilt
