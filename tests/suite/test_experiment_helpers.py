"""The helpers the experiments share: hpfebe.suite.figures (new_figure, style_axes,
reference_slope, slope_line, readable_log_ticks), hpfebe.suite.tables (published_table,
grouped_rates), hpfebe.suite.runs (select_scenes, from_config_sections, timed)."""

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from hpfebe.analysis import observed_rates
from hpfebe.suite import (ConfigError, from_config_sections, grouped_rates, new_figure,
                          published_table, readable_log_ticks, reference_slope,
                          select_scenes, slope_line, style_axes, timed)
from hpfebe.suite.tables import PUBLISHED_DIR


# ------------------------------------------------------------------ figures
def test_new_figure_one_axes_or_an_array():
    fig, ax = new_figure((4.0, 3.0))
    assert isinstance(fig, Figure) and tuple(fig.get_size_inches()) == (4.0, 3.0)
    assert fig.axes == [ax]
    fig, axs = new_figure((8.0, 3.0), 1, 2, layout="constrained", sharey=True)
    assert axs.shape == (2,) and fig.get_layout_engine() is not None


def test_style_axes_labels_grid_legend():
    fig, ax = new_figure((4.0, 3.0))
    ax.loglog([1, 10], [1, 0.1], label="curve")
    style_axes(ax, "DOF", "error", "title", title_size=9, legend=dict(fontsize=7))
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) == ("DOF", "error", "title")
    assert ax.title.get_fontsize() == 9
    assert ax.xaxis.get_major_ticks()[0].gridline.get_visible()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["curve"]
    # None leaves a label as it is; no legend unless asked for
    fig, ax = new_figure((4.0, 3.0))
    ax.set_xlabel("kept")
    style_axes(ax, ylabel="y")
    assert ax.get_xlabel() == "kept" and ax.get_legend() is None


def test_reference_slopes_are_power_laws():
    fig, ax = new_figure((4.0, 3.0))
    x = np.array([10.0, 40.0, 160.0])
    reference_slope(ax, x, 2.0, -0.5, "DOF$^{-1/2}$")
    xs, ys = ax.lines[-1].get_data()
    np.testing.assert_allclose(ys, 2.0 * (np.asarray(xs) / 10.0) ** -0.5)
    assert ax.texts[-1].get_text() == "DOF$^{-1/2}$"
    line = slope_line(ax, x, -1.0, (160.0, 3.0), "k:", label="ref")
    np.testing.assert_allclose(line.get_ydata(), 3.0 * 160.0 / x)
    assert line.get_label() == "ref" and line.get_linestyle() == ":"


def test_readable_log_ticks_plain_numbers():
    fig, ax = new_figure((4.0, 3.0))
    ax.loglog([2, 50], [1, 2])
    readable_log_ticks(ax.xaxis)
    fig.canvas.draw()
    labels = {t.get_text() for t in ax.get_xticklabels() if t.get_text()}
    assert {"5", "10", "20"} <= labels


# ------------------------------------------------------------------ tables
def test_published_table_reads_the_thesis_table():
    pub = published_table("table_3_1_penalty_eps.csv")
    assert {"C_eps", "dof", "err"} <= set(pub.columns) and len(pub) > 0
    assert (PUBLISHED_DIR / "table_3_1_penalty_eps.csv").is_file()
    with pytest.raises(ValueError, match="filename"):
        published_table("no_such_table.csv")


def test_published_table_skips_the_caption(tmp_path):
    (tmp_path / "t.csv").write_text("# caption\na,b\n1,2\n")
    assert published_table("t.csv", tmp_path).to_dict("list") == {"a": [1], "b": [2]}


def test_grouped_rates_per_group_in_row_order():
    df = pd.DataFrame(dict(p=[1, 2, 1, 2, 1], h=[0.5, 0.5, 0.25, 0.25, 0.125],
                           e=[1.0, 1.0, 0.5, 0.25, 0.25]))
    r = grouped_rates(df, "p", "h", "e")
    np.testing.assert_allclose(r, [np.nan, np.nan, 1.0, 2.0, 1.0], equal_nan=True)
    one = df[df.p == 1]
    np.testing.assert_array_equal(r[df.p == 1], observed_rates(one.h.to_numpy(),
                                                               one.e.to_numpy()))
    # arrays instead of column names (rates in DOF^-1)
    np.testing.assert_allclose(grouped_rates(df, ["p"], 1.0 / (4 / df.h), "e"), r)


# ------------------------------------------------------------------ runs
SCENES = {"smooth": ("a",), "singular": ("b",), "timing": ("c",)}


def test_select_scenes_in_the_order_of_scenes():
    assert select_scenes(SCENES, None, "mod") == ("smooth", "singular", "timing")
    assert select_scenes(SCENES, ["timing", "smooth"], "mod") == ("smooth", "timing")
    with pytest.raises(ValueError, match=r"unknown scene\(s\) \['x'\] of mod; known"):
        select_scenes(SCENES, ["x", "smooth"], "mod")


@dataclass(frozen=True)
class Sub:
    n: int = 1


@dataclass(frozen=True)
class Main:
    alpha: float = 0.0
    sub: Sub = field(default_factory=Sub)


def test_from_config_sections():
    prm = from_config_sections(Main, {"alpha": 2.0, "sub": {"n": 3}}, "mod", sub=Sub)
    assert prm == Main(alpha=2.0, sub=Sub(3))
    assert from_config_sections(Main, None, "mod", sub=Sub) == Main()
    with pytest.raises(ConfigError) as err:
        from_config_sections(Main, {"sub": {"m": 1}}, "mod", sub=Sub)
    assert "mod.sub" in str(err.value) + str(err.value.path)


def test_timed_returns_value_and_seconds():
    value, seconds = timed(sum, [1, 2, 3])
    assert value == 6 and 0.0 <= seconds < 5.0
