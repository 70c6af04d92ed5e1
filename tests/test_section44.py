"""Table 4.3 / Figure 4.22 (experiments/ch4_section44.py): the quick run through the CLI,
and the penalty solution's penetration decreasing linearly in eps_n."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("section44")
    proc = subprocess.run([sys.executable, "-m", "hpfebe", "run", "table_4_3", "--quick",
                           "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


def test_table_4_3_quick(quick_run):
    tab = pd.read_csv(quick_run / "table_4_3.csv")
    pub = pd.read_csv(ROOT / "report/published/table_4_3_penalty_newton.csv", comment="#")
    assert list(tab.columns[:4]) == list(pub.columns)
    assert np.allclose(tab.inv_eps_n_over_E, [20, 10, 5, 2.5])
    assert np.allclose(tab.inv_eps_t_over_E, 0.5 * tab.inv_eps_n_over_E)
    assert tab.converged.all()
    # an order of magnitude fewer Newton iterations than the thesis's 175-520
    assert (tab.newton_iterations > 0).all() and (tab.newton_iterations < 50).all()
    # penetration decreases and is ~linear in eps_n = 1 / (f E)
    pen = tab.penetration_l2.to_numpy()
    assert np.all(np.diff(pen) > 0)
    slope = np.polyfit(np.log(1 / tab.inv_eps_n_over_E), np.log(pen), 1)[0]
    assert abs(slope - 1) < 0.2, slope
    # same order as the thesis's norms
    ratio = pen / pub.penetration_l2.to_numpy()
    assert np.all((ratio > 0.3) & (ratio < 4)), ratio
    meta = json.loads((quick_run / "table_4_3.json").read_text())
    assert len(meta["claims"]) >= 4


def test_figure_4_22_quick(quick_run):
    assert (quick_run / "figure_4_22.png").stat().st_size > 0
    rg = pd.read_csv(quick_run / "figure_4_22.csv")
    dev = rg[rg.field == "dev_sigma_norm"].ours_max.iloc[0]
    # the work piece yields: max ||dev sigma|| just above sqrt(2/3) sigma_Y
    assert np.sqrt(2 / 3) * 4.0 <= dev < 1.05 * 3.302
    uy = rg[(rg.body == "work") & (rg.field == "u_y")].iloc[0]
    assert uy.ours_max == pytest.approx(1e-4, rel=1e-6)
