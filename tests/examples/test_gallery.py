"""Every gallery script in examples/ runs (in this process, figures on the Agg backend)
and prints what its text claims."""

import os
import runpy
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SCRIPTS = sorted(EXAMPLES.glob("plot_*.py"))


def test_gallery_has_the_examples_of_issue_26():
    assert len(SCRIPTS) >= 10


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_example_runs(script, capsys, monkeypatch):
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    monkeypatch.chdir(script.parent)
    monkeypatch.setattr(plt, "show", lambda *a, **k: None)
    try:
        runpy.run_path(str(script), run_name="__main__")
        assert plt.get_fignums(), "the example ends in a figure"
    finally:
        plt.close("all")
    out = capsys.readouterr().out
    assert out.strip(), "the example prints its results"
    assert "converged False" not in out and not out.startswith("False")
