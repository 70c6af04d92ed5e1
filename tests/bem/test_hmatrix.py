"""Compressed hp-BEM operators (hpfebe.bem.hmatrix, issue 27): agreement with the dense
operators on small meshes at every degree (and mixed degrees), Laplace and Lame; the
error control (tolerance met, estimates reported, a wrong tolerance refused); the
cluster tree and the block partition; the solvers (CG on V, GMRES on W)."""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM
from hpfebe.bem.hmatrix import HMatrixSettings, block_tree, cluster_tree

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]


def _rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _mesh(p, n):
    return BoundaryMesh.polygon(L_SHAPE, n=n, p=p)


def _pair(kind, mesh, tol):
    if kind == "laplace":
        return (LaplaceBEM(mesh, closed_form=False),
                LaplaceBEM(mesh, compression="hmatrix", tol=tol))
    return (LameBEM(mesh, 1000.0, 0.3, closed_form=False),
            LameBEM(mesh, 1000.0, 0.3, compression="hmatrix", tol=tol))


# elements per side: enough for far-field blocks at the automatic leaf size
CASES = [("laplace", 1, 40), ("laplace", 2, 16), ("laplace", 3, 12), ("laplace", 4, 10),
         ("lame", 1, 24), ("lame", 2, 10), ("lame", 4, 6)]


@pytest.mark.parametrize("kind,p,n", CASES)
def test_matvecs_agree_with_dense(kind, p, n):
    """V, K, K', W, B and their transposes against the dense matrices: relative error
    of a random matvec <= tol; the H-matrices have far-field (low-rank) blocks."""
    tol = 1e-8
    dense, comp = _pair(kind, _mesh(p, n), tol)
    rng = np.random.default_rng(p)
    for name in ("V", "K", "K_adj", "W", "B"):
        A, H = getattr(dense, name), getattr(comp, name)
        x = rng.standard_normal(A.shape[1])
        y = rng.standard_normal(A.shape[0])
        assert H.shape == A.shape
        assert _rel(H @ x, A @ x) <= tol, name
        assert _rel(H.T @ y, A.T @ y) <= tol, name
    info = comp.hmatrix_info(sampled_rows=4)
    for name in ("V", "K", "W"):
        assert info[name]["n_far"] > 0 and info[name]["bytes"] > 0
        assert info[name]["sampled_error"] <= tol
        assert info[name]["error_bound"] <= tol
        assert info[name]["unconverged_blocks"] == 0


def test_mixed_degrees_and_column_blocks():
    """Mixed degrees p_I in 1..4; matmat on column blocks equals column-wise matvec."""
    mesh = _mesh(1, 12)
    mesh = mesh.with_degrees(1 + np.arange(mesh.n_elements) % 4)
    dense, comp = _pair("laplace", mesh, 1e-8)
    X = np.random.default_rng(0).standard_normal((dense.W.shape[1], 3))
    for name in ("V", "W"):
        A, H = getattr(dense, name), getattr(comp, name)
        Xn = X[:A.shape[1]]
        HX = H @ Xn
        assert _rel(HX, A @ Xn) <= 1e-8
        assert np.allclose(HX[:, 1], H @ Xn[:, 1], rtol=0, atol=1e-14 * abs(HX).max())


@pytest.mark.parametrize("kind", ["laplace", "lame"])
def test_psi_and_s_hat_agree_with_dense(kind):
    """Psi (CG on the compressed V, with the zero-flux / zero-force constraint) and
    S_hat = W + B^T P B (inner CG) as the dense ones, to a small multiple of tol."""
    tol = 1e-8
    dense, comp = _pair(kind, _mesh(2, 10), tol)
    rng = np.random.default_rng(1)
    U = rng.standard_normal(dense.K.shape[1])
    assert _rel(comp.Psi(U), dense.Psi(U)) <= 1e3 * tol
    assert _rel(comp.S_hat @ U, dense.S_hat @ U) <= 1e3 * tol
    Uc = rng.standard_normal((dense.K.shape[1], 2))
    assert _rel(comp.Psi(Uc), dense.Psi(Uc)) <= 1e3 * tol
    assert all(ok for _, ok in comp.hmatrix_info(0)["solves"])


def test_dirichlet_solution_matches_dense():
    """The interior Dirichlet problem u = x^2 - y^2: Psi compressed = Psi dense."""
    mesh = BoundaryMesh.polygon(SQUARE, n=64, p=1)
    dense, comp = _pair("laplace", mesh, 1e-8)
    g = dense.V_space.interpolate(lambda x: x[:, 0] ** 2 - x[:, 1] ** 2)
    assert _rel(comp.solve_dirichlet(g), dense.solve_dirichlet(g)) <= 1e-6


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-10])
def test_tolerance_is_met_and_ranks_grow(tol):
    """Each requested tolerance is met by the matvec, the sampled rows and the bound."""
    dense, comp = _pair("laplace", BoundaryMesh.polygon(SQUARE, n=64, p=2), tol)
    x = np.random.default_rng(2).standard_normal(dense.V.shape[0])
    assert _rel(comp.V @ x, dense.V @ x) <= tol
    info = comp.hmatrix_info(sampled_rows=6)["V"]
    assert info["sampled_error"] <= tol and info["error_bound"] <= tol


def test_ranks_grow_as_tolerance_shrinks():
    mesh = BoundaryMesh.polygon(SQUARE, n=64, p=1)
    ranks = [LaplaceBEM(mesh, compression="hmatrix", tol=t).hm.hmatrix("V").far_rank.sum()
             for t in (1e-3, 1e-10)]
    assert ranks[0] < ranks[1]


@pytest.mark.parametrize("tol", [0, 1, -1e-8, 1.5, float("nan"), "1e-8", True])
def test_wrong_tolerance_refused(tol):
    mesh = BoundaryMesh.polygon(SQUARE, n=2, p=1)
    with pytest.raises((ValueError, TypeError), match="tol"):
        LaplaceBEM(mesh, compression="hmatrix", tol=tol)
    with pytest.raises((ValueError, TypeError), match="tol"):
        LameBEM(mesh, 1.0, 0.3, compression="hmatrix", tol=tol)
    with pytest.raises((ValueError, TypeError), match="tol"):
        HMatrixSettings(tol=tol)


def test_wrong_compression_refused_and_dense_default():
    mesh = BoundaryMesh.polygon(SQUARE, n=2, p=1)
    with pytest.raises(ValueError, match="compression"):
        LaplaceBEM(mesh, compression="aca")
    b = LaplaceBEM(mesh)
    assert b.compression is None and b.hm is None and isinstance(b.V, np.ndarray)
    with pytest.raises(ValueError, match="compression"):
        b.hmatrix_info()


def test_cluster_tree_and_block_partition():
    """Leaves hold <= leaf_size elements, every element once; near and far blocks
    partition the matrix exactly once; far blocks are admissible."""
    mesh = BoundaryMesh.polygon(L_SHAPE, n=20, p=1)
    tree = cluster_tree(mesh.nodes, mesh.elements, 8)
    assert np.array_equal(np.sort(tree.order), np.arange(mesh.n_elements))
    leaves = [c for c in range(tree.n_clusters) if tree.is_leaf(c)]
    assert all(tree.stop[c] - tree.start[c] <= 8 for c in leaves)
    near, far = block_tree(tree, 1.0)
    cover = np.zeros((mesh.n_elements, mesh.n_elements), int)
    for t, s in np.vstack([near, far]):
        cover[tree.start[t]:tree.stop[t], tree.start[s]:tree.stop[s]] += 1
    assert (cover == 1).all() and len(far) > 0
    for t, s in far:
        bt, bs = tree.box[t], tree.box[s]
        dist = np.hypot(max(0, bt[0] - bs[2], bs[0] - bt[2]), max(0, bt[1] - bs[3], bs[1] - bt[3]))
        diam = min(np.hypot(*(bt[2:] - bt[:2])), np.hypot(*(bs[2:] - bs[:2])))
        assert diam <= dist


def test_gmres_on_stabilised_hypersingular():
    """W u = f by GMRES on the compressed W + a a^T (a: the constants, the kernel of W)
    equals the dense solve."""
    mesh = BoundaryMesh.polygon(SQUARE, n=40, p=2)
    dense, comp = _pair("laplace", mesh, 1e-10)
    a = np.ones(dense.W.shape[0]) / np.sqrt(dense.W.shape[0])
    f = dense.M.T @ np.random.default_rng(3).standard_normal(dense.M.shape[0])
    f -= a * (a @ f)
    u_dense = np.linalg.solve(dense.W + np.outer(a, a), f)
    u, info = comp.hm.solve_gmres("W", f, shift=a[:, None])
    assert info.converged and _rel(u, u_dense) <= 1e-7
