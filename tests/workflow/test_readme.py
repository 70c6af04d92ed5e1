"""The README's core-API example runs and prints what it claims."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_core_example_runs(capsys):
    text = README.read_text()
    section = text.split("## Using the core", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    err = float(re.search(r"L2 error of du/dn: (\S+)", out).group(1))
    assert err < 1e-4   # measured 8.9e-6 (p = 3, h = 1/8)
    assert "S_hat 1 = 0: True" in out
    vals = re.search(r"u\(0.5, 0.5\): (\S+) exact: (\S+)", out)
    assert abs(float(vals.group(1)) - float(vals.group(2))) < 1e-6


def test_readme_contact_example_runs(capsys):
    section = README.read_text().split("## Using the core", 1)[1]
    code = re.findall(r"```python\n(.*?)```", section, re.S)[1]
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("True converged")
    force = float(re.search(r"contact force: (\S+)", out).group(1))
    assert force > 0   # measured 165.5 (N per unit depth) for the 1e-3 lift
