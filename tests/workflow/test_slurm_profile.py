"""Fast checks of profiles/slurm/config.yaml (no SLURM needed; tools/slurm_local.sh runs
the profile end to end on a single-node SLURM).

Snakemake silently ignores a rule name in `set-resources` that no rule has, so the names
are checked against the workflow's jobs here (the Snakefile refuses a bundle naming no
job)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
PROFILE = ROOT / "profiles" / "slurm" / "config.yaml"
BUNDLES = ROOT / "profiles" / "slurm" / "bundles.yaml"


@pytest.fixture(scope="module")
def profile() -> dict:
    return yaml.safe_load(PROFILE.read_text())


@pytest.fixture(scope="module")
def bundles() -> dict:
    return yaml.safe_load(BUNDLES.read_text())


@pytest.fixture(scope="module")
def rules() -> set[str]:
    from hpfebe.suite.registry import discover

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


def test_named_rules_exist(profile, bundles, rules):
    named = set(profile.get("set-resources") or {})
    assert named <= rules, f"no such rule: {sorted(named - rules)}"
    bundled = [r for members in bundles.values() for r in members]
    assert set(bundled) <= rules, f"no such job: {sorted(set(bundled) - rules)}"
    assert len(bundled) == len(set(bundled)), "a job in two bundles"


def test_profile_turns_the_bundles_on(profile):
    assert f"bundles={BUNDLES.relative_to(ROOT)}" in profile["config"]


def test_status_checks_capped(profile):
    """The plugin's back-off (10 s more after each check that saw no job end) is capped
    by the Snakefile at `seconds-between-status-checks`, through the plugin's property
    (skipped without the plugin; a plugin version without it fails here)."""
    assert 1 <= profile["seconds-between-status-checks"] <= 30
    assert "_SlurmExecutor.next_seconds_between_status_checks" in (ROOT / "Snakefile").read_text()
    plugin = pytest.importorskip("snakemake_executor_plugin_slurm")
    prop = getattr(plugin.Executor, "next_seconds_between_status_checks", None)
    assert isinstance(prop, property) and prop.fset is not None


def test_no_bundle_outlasts_the_longest_job(bundles, recorded_wall_s):
    """A bundle runs its jobs one after another: together they take no longer than the
    longest single job (full run, config/job_times.yaml), so bundling never lengthens the
    run on a cluster with free nodes; the numba_cache job and the jobs outside bundles
    stay SLURM jobs of their own."""
    longest = max(recorded_wall_s.values())
    for name, members in bundles.items():
        assert sum(recorded_wall_s[r] for r in members) <= longest, (name, members)
    assert not any(max(recorded_wall_s[r] for r in members) == longest
                   for members in bundles.values())


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
