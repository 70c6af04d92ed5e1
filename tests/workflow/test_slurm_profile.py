"""Fast checks of profiles/slurm/config.yaml (no SLURM needed; tools/slurm_local.sh runs
the profile end to end on a single-node SLURM).

Snakemake silently ignores a rule name in `groups` or `set-resources` that no rule has,
so the names are checked against the workflow's jobs here."""

from __future__ import annotations

import dataclasses
import math
import re
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
PROFILE = ROOT / "profiles" / "slurm" / "config.yaml"


@pytest.fixture(scope="module")
def profile() -> dict:
    return yaml.safe_load(PROFILE.read_text())


@pytest.fixture(scope="module")
def rules() -> set[str]:
    sys.path.insert(0, str(ROOT))
    from experiments.registry import discover

    return {job.rule for job in discover(ROOT / "experiments").jobs}


@pytest.fixture(scope="module")
def recorded_wall_s() -> dict:
    return yaml.safe_load((ROOT / "config" / "job_times.yaml").read_text())["wall_s"]


def test_executor_and_status_command(profile):
    assert profile["executor"] == "slurm"
    # squeue works with and without job accounting (sacct hangs the run without it)
    assert profile["slurm-status-command"] == "squeue"
    assert 1 <= profile["slurm-init-seconds-before-status-checks"] <= 10
    assert profile["retries"] >= 1


def test_named_rules_exist(profile, rules):
    named = set(profile.get("groups") or {}) | set(profile.get("set-resources") or {})
    assert named <= rules, f"no such rule: {sorted(named - rules)}"


def test_status_checks_capped(profile):
    """The plugin's back-off (10 s more after each check that saw no job end) is capped
    by the Snakefile at `seconds-between-status-checks`, through the plugin's property
    (skipped without the plugin; a plugin version without it fails here)."""
    assert 1 <= profile["seconds-between-status-checks"] <= 30
    assert "_SlurmExecutor.next_seconds_between_status_checks" in (ROOT / "Snakefile").read_text()
    plugin = pytest.importorskip("snakemake_executor_plugin_slurm")
    prop = getattr(plugin.Executor, "next_seconds_between_status_checks", None)
    assert isinstance(prop, property) and prop.fset is not None


def test_groups_run_their_jobs_one_after_another(profile):
    """Without a per-job slot of local scope, Snakemake sizes a group job to run all its
    jobs side by side (N CPUs, N x memory): larger than a node, it never starts."""
    groups = profile.get("groups") or {}
    assert set(groups.values()) == set(profile["group-components"])
    assert profile["resources"]["hpfebe_slot"] == 1
    assert profile["default-resources"]["hpfebe_slot"] == 1
    assert profile["set-resource-scopes"]["hpfebe_slot"] == "local"


def test_no_group_job_outlasts_the_longest_job(profile, recorded_wall_s):
    """However Snakemake chunks a group into SLURM jobs of `group-components` jobs each,
    no chunk runs longer than the longest single job (full run, config/job_times.yaml):
    grouping never lengthens the run on a cluster with free nodes."""
    groups = profile.get("groups") or {}
    longest = max(recorded_wall_s.values())
    for name, size in profile["group-components"].items():
        walls = sorted((recorded_wall_s[r] for r, g in groups.items() if g == name),
                       reverse=True)
        assert sum(walls[:size]) <= longest, (name, walls[:size], longest)
        assert math.ceil(len(walls) / size) >= 1


def test_default_resources_cover_the_measured_maxima(profile, recorded_wall_s):
    peaks = yaml.safe_load((ROOT / "config" / "job_times.yaml").read_text())["peak_mb"]
    res = profile["default-resources"]
    assert res["runtime"] * 60 >= 5 * max(recorded_wall_s.values())
    assert res["mem_mb"] >= 1.5 * max(peaks.values())


def test_workflow_profile_cap_documented(profile):
    """profiles/default (cores) is applied on top of --profile and caps every job's
    threads: the profile's documented command turns it off."""
    default = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text())
    if "cores" in (default or {}):
        assert "--workflow-profile none" in PROFILE.read_text()


def test_plugin_options_exist(profile):
    """Every slurm-* key is an option of the installed plugin (skipped without it)."""
    plugin = pytest.importorskip("snakemake_executor_plugin_slurm")
    fields = {f.name for f in dataclasses.fields(plugin.ExecutorSettings)}
    for key in profile:
        if key.startswith("slurm-"):
            assert key[len("slurm-"):].replace("-", "_") in fields, key


def test_plugin_version_pinned():
    """The `cluster` extra pins the plugin to the range tools/slurm_local.sh was run
    with, and the installed plugin (if any) is in it."""
    import tomllib

    with open(ROOT / "pyproject.toml", "rb") as f:
        extra = tomllib.load(f)["project"]["optional-dependencies"]["cluster"]
    (req,) = [r for r in extra if r.startswith("snakemake-executor-plugin-slurm")]
    assert re.search(r">=\s*[\d.]+\s*,\s*<\s*[\d.]+", req), req
    from importlib import metadata

    try:
        installed = metadata.version("snakemake-executor-plugin-slurm")
    except metadata.PackageNotFoundError:
        pytest.skip("plugin not installed")
    packaging = pytest.importorskip("packaging.requirements")
    assert packaging.Requirement(req).specifier.contains(installed), (req, installed)
