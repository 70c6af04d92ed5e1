"""Issue 25, config class: a bad value of a Chapter 4 config key is refused before any
computation, as the README promises - ``hpfebe run`` names the key and the config file
that set it, prints no traceback and exits with status 2."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:        # as `hpfebe run` does: the suite's experiments/
    sys.path.insert(0, str(ROOT))

from experiments.ch4_section44.dtn import (PUBLISHED_42, mortar_claims,  # noqa: E402
                                           readings_claim)

from hpfebe import cli  # noqa: E402
from hpfebe.scenes.section44 import READING_TEXT, Section44Scene  # noqa: E402
from hpfebe.suite import published_table  # noqa: E402

#: (job, key, bad value): the nested keys of issue 25 and the tolerances that are never
#: reached when <= 0 (run in-process through the CLI's own entry point, as `hpfebe run`)
BAD = [
    ("ch4_mortar", "map_omegas", [-1.0]),
    ("ch4_mortar", "map_omegas", []),
    ("ch4_mortar", "adapt_q1", 1.5),
    ("ch4_mortar", "conv_degrees", [[1, 1], [0, 1]]),
    ("ch4_mortar", "conv_degrees", [[2]]),
    ("ch4_mortar", "tol_uzawa", -1.0e-6),
    ("ch4_section44", "newton_tol", -1),
    ("ch4_section44", "newton_tol", 0.0),
    ("ch4_section44", "omegas_D", [0.0, 0.5]),
    ("ch4_plasticity", "h_levels", [-0.2, 0.1]),
    ("ch4_plasticity", "h_levels", []),
    ("ch4_adaptive_fefe", "mesh_steps", [0, -1]),
]


@pytest.mark.parametrize("job,key,value", BAD, ids=[f"{j}.{k}={v}" for j, k, v in BAD])
def test_bad_value_exits_2_naming_key_and_file(tmp_path, capsys, monkeypatch, job, key,
                                               value):
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({job: {key: value}}))
    out = tmp_path / "out"
    monkeypatch.chdir(ROOT)
    rc = cli.main(["run", job, "--quick", "--config", str(bad), "--out", str(out)])
    captured = capsys.readouterr()
    msg = captured.err + captured.out
    assert rc == 2, msg
    assert key in msg and str(bad) in msg, msg
    assert "Traceback" not in msg, msg
    assert not list(out.glob("*.json")), "refused after computing"


def test_section44_claims_over_no_converged_run_are_open():
    """Table 4.2's claims over the converged runs are undecided (holds None), not held,
    when no DtN run converged (issue 25: newton_tol -1 claimed 'holds' over no run)."""
    pub = published_table(PUBLISHED_42)
    tab = pub[["omega_D", "omega_N"]].assign(       # every run failed, as mortar_sweep has it
        dtn_iterations=np.nan, dtn_iterations_alt_tol=np.nan,
        uzawa_iterations_first_dtn=np.nan, converged=False, reason="newton: not converged",
        uzawa_first_run=3, uzawa_max_later=0, dtn_steps_run=1,
        **{f"its_{name}": np.nan for name in READING_TEXT})
    claims = {c.id: c for c in mortar_claims(Section44Scene(), tab, pub)}
    claims["readings"] = readings_claim(Section44Scene(), tab, pub)
    for cid in ("counts", "alt_tol", "uzawa_later", "readings"):
        assert claims[cid].holds is None, (cid, claims[cid].evidence)
    assert claims["no_convergence"].holds is False
