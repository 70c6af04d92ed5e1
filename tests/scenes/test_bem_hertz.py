"""The Hertz scene (hpfebe.scenes.bem_hertz): readings against Hertz's formulas."""

import numpy as np
import pytest

from hpfebe.scenes import bem_hertz as bh


def test_hertz_formulas():
    a, p0 = bh.hertz(100.0, 2.0e5)
    assert a == pytest.approx(np.sqrt(4 * 100.0 / (np.pi * 2.0e5)))
    # the elliptic pressure integrates to F
    assert np.pi * a * p0 / 2 == pytest.approx(100.0)


def test_hertz_errors_decrease_with_h():
    coarse, fine = bh.solve(bh.HertzRun(64)), bh.solve(bh.HertzRun(128))
    assert coarse["converged"] and fine["converged"]
    assert fine["err_a"] < coarse["err_a"]
    assert fine["err_p0"] < coarse["err_p0"]
    # symmetric contact set around x = 0, pressure positive only inside it
    x, p = fine["profile"]
    assert np.all(np.abs(x[p > 0]) <= fine["a"] * (1 + 1e-12))
    # one pressure per node of the contact boundary (nodes shared by two elements once)
    assert np.all(np.diff(x) > 0)


def test_mesh_labels_and_gap():
    mesh = bh.half_disk(100)
    run = bh.HertzRun(100)
    assert int(mesh.where("C").sum()) == run.n_arc
    assert np.allclose(bh.gap(np.array([[0.0, -1.0]])), 0.0)
    assert np.all(bh.gap(mesh.nodes[mesh.elements[mesh.where("C"), 0]]) >= 0.0)
