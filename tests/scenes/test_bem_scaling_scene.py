"""The scaling scene of issue 27 (hpfebe.scenes.bem_scaling): its independent check of
V x, its exact data and its settings."""

from __future__ import annotations

import numpy as np
import pytest

from hpfebe.scenes import bem_scaling as bs


@pytest.mark.parametrize("p", [1, 2, 4])
def test_far_field_rows_equal_dense_rows(p):
    """Near pairs by local blocks, the rest by tensor Gauss: the rows of the dense V x to
    round-off (elements at the corners, mid-side and beside the first)."""
    op = bs.operators(bs.ScalingRun("laplace", 64, p))
    x = np.random.default_rng(p).standard_normal(op.W_space.ndof)
    els = [0, 1, 15, 16, 40, 63]
    y = op.V @ x
    ref = y[op.W_space.elem_dofs[els, :p]]
    assert np.abs(bs.far_field_rows(op, x, els) - ref).max() <= 1e-13 * np.abs(y).max()


@pytest.mark.parametrize("pde, rate", [("laplace", 1.0), ("lame", 1.0)])
def test_dense_error_against_exact_data_converges(pde, rate):
    """The exact data are right: the L2 error of psi_h falls like h^p (p = 1)."""
    e = [bs.solve(bs.ScalingRun(pde, n, 1)).error for n in (32, 64)]
    assert abs(np.log2(e[0] / e[1]) - rate) <= 0.25


def test_compressed_matches_dense():
    d = bs.solve(bs.ScalingRun("laplace", 128, 2))
    c = bs.solve(bs.ScalingRun("laplace", 128, 2, "hmatrix", 1e-8))
    assert abs(c.error / d.error - 1) <= 1e-3
    assert bs.relative_difference(c.psi, d.psi) <= 1e-6
    assert c.ratio < 1 and d.ratio == 1
    row = bs.result_row(c, d)
    assert row["method"] == "hmatrix" and row["err_vs_dense"] <= 1e-6


@pytest.mark.parametrize("kw, match", [
    (dict(pde="helmholtz"), "pde"), (dict(n_elements=30), "multiple of 4"),
    (dict(p=0), "p"), (dict(compression="fmm"), "compression"), (dict(tol=1.0), "tol"),
    (dict(tol=0.0), "tol")])
def test_settings_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        bs.ScalingRun(**kw)
