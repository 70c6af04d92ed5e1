"""The suite helpers that the Chapter 2-3 experiments share (hpfebe.suite.tables,
hpfebe.suite.figures): the ratio to a published table, the mesh-sequence and the
deformed-field figures."""

from __future__ import annotations

import numpy as np
import pandas as pd

from hpfebe.geometry import BoundaryMesh
from hpfebe.suite import deformed_field_figure, mesh_sequence_figure, published_ratio


def test_published_ratio_joins_on_the_keys():
    ours = pd.DataFrame(dict(C_eps=[1e-4, 1e-4, 1e-5], dof=[22, 46, 22], err=[2.0, 1.0, 3.0],
                             err_unscaled=[1.0, 0.5, 1.5]))
    pub = pd.DataFrame(dict(C_eps=[1e-4, 1e-5, 1e-6], dof=[46, 22, 22], err=[4.0, 6.0, 1.0]))
    r = published_ratio(ours, pub, ("C_eps", "dof"), "err")
    assert list(r) == [0.25, 0.5]                  # rows in both tables only
    assert list(published_ratio(ours, pub, ["C_eps", "dof"], "err", "err_unscaled")) \
        == [0.125, 0.25]


def test_mesh_sequence_figure_one_panel_per_mesh():
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=1)
    marked = np.zeros(mesh.n_elements, bool)
    marked[0] = True
    P = np.vstack([mesh.a, mesh.a[:1]])
    fig = mesh_sequence_figure([(mesh, marked, P, f"step {k}") for k in range(5)], "seq")
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(fig.axes) == 8 and len(visible) == 5        # 2 rows of 4, 3 hidden
    assert [ax.get_title() for ax in visible] == [f"step {k}" for k in range(5)]
    assert len(visible[0].collections) == 2                # refined / not refined
    assert fig._suptitle.get_text() == "seq"


def test_deformed_field_figure_titles_the_extremes():
    x = np.linspace(-1, 1, 5)
    X, Y = np.meshgrid(x, x)
    u = np.stack([1e-4 * X, -2e-4 * Y], axis=-1)
    fig = deformed_field_figure(X, Y, u, 1e3, "field")
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles == ["x-component: -1.0000e-04 .. 1.0000e-04",
                      "y-component: -2.0000e-04 .. 2.0000e-04"]
    assert fig._suptitle.get_text() == "field (grid deformed x1000)"
