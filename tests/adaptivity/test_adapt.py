"""Algorithm 3.2 on one mesh or several (hpfebe.adaptivity.adapt): the marking of each
mesh on its own indicators, the marked elements of every step in the history, stopping."""

import numpy as np
import pytest

from hpfebe.adaptivity import adapt, mark_max
from hpfebe.fem import refine_labelled
from hpfebe.fem.elasticity import rectangle_mesh
from hpfebe.geometry import BoundaryMesh


def _square(n=2):
    return rectangle_mesh(0.0, 1.0, 0.0, 1.0, n, n, kind="tri")


def _corner_eta(mesh, corner):
    """A synthetic indicator growing towards ``corner`` (distinct values)."""
    c = mesh.p[:, mesh.t].mean(axis=1)
    return 1.0 / (0.05 + np.hypot(c[0] - corner[0], c[1] - corner[1]))


def _solve(meshes):
    return None, tuple(2 * m.p.shape[1] for m in meshes)


def _estimate(meshes, state):
    return [_corner_eta(meshes[0], (0, 0)), 10.0 * _corner_eta(meshes[1], (1, 1))]


def test_two_meshes_each_marked_on_its_own():
    h = adapt((_square(), _square(4)), _solve, _estimate, n_steps=4, theta=0.9)
    assert h.n_meshes == 2 and len(h.records) == 4 and h.reason == "n_steps"
    assert len(h.marked) == len(h.meshes) == len(h.etas) == 4
    for k, (meshes, etas, marked, rec) in enumerate(zip(h.meshes, h.etas, h.marked,
                                                         h.records)):
        for i in (0, 1):
            assert marked[i].shape == (meshes[i].t.shape[1],)
            if k < 3:
                # each mesh by its own maximum (the second indicator is 10x larger)
                np.testing.assert_array_equal(marked[i], mark_max(etas[i], 0.9))
                assert rec["n_marked"][i] == marked[i].sum() > 0
            else:
                assert not marked[i].any() and rec["n_marked"][i] == 0
            assert rec["n_elements"][i] == meshes[i].t.shape[1]
            assert rec["ndof"][i] == 2 * meshes[i].p.shape[1]
            assert rec["eta"][i] == pytest.approx(np.sqrt(np.sum(etas[i] ** 2)))
        assert rec["eta_total"] == pytest.approx(np.hypot(*rec["eta"]))
        if k:   # the meshes grew where they were marked, independently
            assert all(meshes[i].t.shape[1] > h.meshes[k - 1][i].t.shape[1] for i in (0, 1))
    assert h.column("eta").shape == (4, 2)
    np.testing.assert_array_equal(h.column("ndof", 1), [r["ndof"][1] for r in h.records])
    assert h.mesh is h.meshes[-1] and len(h.eta) == 2
    # labels kept by the default refinement of scikit-fem meshes
    assert set(h.mesh[0].boundaries) == {"left", "right", "bottom", "top"}


def test_per_mesh_marking_theta_refine():
    calls = []

    def refine(mesh, marked):
        calls.append(int(marked.sum()))
        return refine_labelled(mesh, marked)

    h = adapt((_square(), _square()), _solve, _estimate, n_steps=2,
              marking=("uniform", "max"), theta=(0.5, 1.0), refine=(refine, refine_labelled))
    assert h.marked[0][0].all()
    # theta = 1: only the largest (two cells tie at the corner)
    np.testing.assert_array_equal(h.marked[0][1], h.etas[0][1] == h.etas[0][1].max())
    assert 1 <= h.marked[0][1].sum() < h.marked[0][1].size
    assert calls == [h.records[0]["n_elements"][0]]


def test_stop_callback_and_tol():
    h = adapt((_square(), _square()), _solve, _estimate, n_steps=10, marking="uniform",
              stop=lambda rec: rec["ndof"][0] > 100)
    assert h.reason == "stop" and h.column("ndof", 0)[-1] > 100
    assert h.column("ndof", 0)[-2] <= 100
    assert not any(m.any() for m in h.marked[-1])
    h = adapt((_square(), _square()), _solve, lambda m, s: [np.full(c.t.shape[1], 1e-3)
                                                             for c in m], n_steps=5, tol=1.0)
    assert h.reason == "tol" and len(h.records) == 1


def test_several_meshes_validation():
    with pytest.raises(ValueError, match="marking"):
        adapt((_square(), _square()), _solve, _estimate, n_steps=2, marking=("max",))
    with pytest.raises(ValueError, match="marking"):
        adapt((_square(), _square()), _solve, _estimate, n_steps=2, marking=("max", "best"))
    with pytest.raises(ValueError, match="theta"):
        adapt((_square(), _square()), _solve, _estimate, n_steps=2, theta=(0.5, 2.0))
    with pytest.raises(ValueError, match="one entry per mesh"):
        adapt((_square(), _square()), _solve, lambda m, s: [np.ones(m[0].t.shape[1])],
              n_steps=2)
    with pytest.raises(ValueError, match="mesh"):
        adapt((), _solve, _estimate, n_steps=2)


def test_one_mesh_records_marked_elements():
    """The call of experiments/ch3_adaptive_bem (one BoundaryMesh,
    hpfebe.scenes.adaptive_bem.adaptive_run) and its history."""
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=1)

    def estimate(m, s):
        mid = 0.5 * (m.a + m.b)
        return 1.0 / (0.05 + np.hypot(mid[:, 0], mid[:, 1]))

    h = adapt(mesh, lambda m: (None, m.n_elements), estimate, n_steps=3, theta=0.9)
    assert h.n_meshes is None
    assert h.column("n_elements").ndim == 1
    for k, (m, eta, marked, rec) in enumerate(zip(h.meshes, h.etas, h.marked, h.records)):
        assert marked.shape == (m.n_elements,)
        expected = mark_max(eta, 0.9) if k < 2 else np.zeros(m.n_elements, bool)
        np.testing.assert_array_equal(marked, expected)
        assert rec["n_marked"] == marked.sum() and rec["eta_total"] == rec["eta"]
    with pytest.raises(ValueError, match="index"):
        h.column("eta", 0)
