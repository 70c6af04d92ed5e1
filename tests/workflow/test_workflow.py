"""The workflow: Snakefile dry runs and real runs in a scratch tree, the experiment
registry.  No test reads or writes the working tree's results/, report/ or .snakemake/:
the runs use a scratch directory whose experiments/, config/, src/, profiles/ and
report/published/ are links to the checkout's."""

import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _registry_module():
    from hpfebe.suite import registry

    return registry


def scratch_tree(path: Path) -> Path:
    """A scratch working directory for the Snakefile: the checkout's sources linked
    (experiments/ copied, so that a test can touch a module), results/, report/ and
    .snakemake/ its own (empty)."""
    for d in ("config", "src", "profiles"):
        (path / d).symlink_to(ROOT / d)
    shutil.copytree(ROOT / "experiments", path / "experiments",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (path / "report").mkdir()
    (path / "report" / "published").symlink_to(ROOT / "report" / "published")
    return path


def snakemake(*args, cwd: Path, timeout=600):
    return subprocess.run([sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"),
                           *args], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def planned(r) -> set[str]:
    """The rules a dry run plans (empty set for "Nothing to be done")."""
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout + r.stderr
    if "Nothing to be done" in out:
        return set()
    return {b.split("\n", 1)[0].split(":", 1)[0].strip()
            for b in out.split("\nrule ")[1:]} - {"all"}


@pytest.fixture
def tree(tmp_path):
    return scratch_tree(tmp_path)


# --------------------------------------------------------------------------- Snakefile
def test_dry_run(tree):
    r = subprocess.run([sys.executable, "-m", "snakemake", "-n"], cwd=ROOT,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    # the workflow profile (profiles/default) is picked up by a bare `snakemake`
    assert "profiles/default" in r.stdout + r.stderr


def test_dry_run_quick_passes_quick_flag(tree):
    r = snakemake("-n", "-p", "--configfile", "config/quick.yaml", cwd=tree)
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout + r.stderr
    assert "rule bem_laplace" in out
    assert "-m hpfebe run bem_laplace --out results --quick" in out
    assert "--config config/quick.yaml" in out
    assert "NUMBA_NUM_THREADS=1" in out and "OMP_NUM_THREADS=1" in out
    # glibc's allocator keeps freed arrays (the Snakefile's ALLOC_VARS)
    assert "MALLOC_MMAP_THRESHOLD_=4294967296 MALLOC_TRIM_THRESHOLD_=4294967296" in out


def test_job_commands_do_not_change_between_calls(tree):
    """A job's command, inputs and params are the same on every call (a changing value,
    such as the pid of the Snakemake that watches the job, made every job rerun)."""
    runs = [snakemake("-n", "-p", "--configfile", "config/quick.yaml", cwd=tree)
            for _ in range(2)]
    cmds = [sorted(line for line in r.stdout.splitlines() if "-m hpfebe" in line)
            for r in runs]
    assert cmds[0] and cmds[0] == cmds[1]
    assert "HPFEBE_PARENT_PID" not in runs[0].stdout


def test_registry_cache_written_by_the_main_snakemake(tree):
    """The main Snakemake writes the registry it discovered to .snakemake/hpfebe/ (the
    nested Snakemakes of cluster jobs read it instead of parsing every experiment file
    again, while no file under experiments/ changed)."""
    import pickle


    r = snakemake("-n", cwd=tree)
    assert r.returncode == 0, r.stdout + r.stderr
    stamp, cached = pickle.loads((tree / ".snakemake" / "hpfebe" / "registry.pickle")
                                 .read_bytes())
    fresh = _registry_module().discover(ROOT / "experiments")   # the Snakefile's own
    assert [j.rule for j in cached.jobs] == [j.rule for j in fresh.jobs]
    assert str(ROOT / "src" / "hpfebe" / "suite" / "registry.py") in stamp


def test_one_rule_per_job(tree):
    reg = _registry_module().discover(ROOT / "experiments")
    r = snakemake("--list-rules", cwd=tree)
    assert r.returncode == 0, r.stdout + r.stderr
    rules = set(r.stdout.split())
    assert {"all", "report", "numba_cache"} <= rules
    assert {j.rule for j in reg.jobs} <= rules


def test_numba_kernels_compiled_once_first(tree):
    """On a fresh machine (no results yet) one `hpfebe compile` job comes first and every
    job calling numba waits for it (no two jobs compile the same kernels); a module with
    NUMBA = False runs beside it."""
    reg = _registry_module().discover(ROOT / "experiments")
    r = snakemake("-n", "--configfile", "config/quick.yaml", cwd=tree)
    assert r.returncode == 0, r.stdout + r.stderr
    blocks = {b.split(":", 1)[0].strip(): b for b in r.stdout.split("\nrule ")[1:]}
    assert "numba_cache" in blocks
    for j in reg.jobs:
        waits = "results/logs/numba_cache.json" in blocks[j.rule].split("output:")[0]
        assert waits == j.experiment.numba, j.rule
    assert any(not e.numba for e in reg)


# Two of the cheapest jobs, run for real in a scratch tree (quick configuration; the
# compile stamp is laid beforehand, so that no compile job runs).
CHEAP = ("figure_bem_laplace", "figure_coercivity")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    tree = scratch_tree(tmp_path_factory.mktemp("workflow"))
    (tree / "results" / "logs").mkdir(parents=True)
    (tree / "results" / "logs" / "numba_cache.json").write_text("{}")
    targets = [f"results/{a}.json" for a in CHEAP]
    r = snakemake("-j2", *targets, "--configfile", "config/quick.yaml", cwd=tree)
    assert r.returncode == 0, r.stdout + r.stderr
    return tree, targets


def test_one_artefact_runs_its_job_only(built):
    tree, _ = built
    names = sorted(p.name for p in (tree / "results").glob("*.json"))
    assert names == sorted(f"{a}.json" for a in CHEAP)
    log = (tree / "results" / "logs" / "bem_laplace.log").read_text()
    assert "skfem" not in log            # dependencies' INFO lines kept out of job logs
    assert "bem_laplace finished" in log
    # the job watches the Snakemake that started it (the pid reaches it through the
    # environment, not through its command: see test_job_commands_do_not_change...)
    assert "stops when process" in log and "the Snakemake that started it" in log


def test_local_jobs_run_in_the_job_server(built):
    """A local run starts the job server (Snakefile onstart): both jobs ran in processes
    forked from it, exited 0, and the server stopped with the run."""
    tree, _ = built
    log = (tree / ".snakemake" / "hpfebe" / "jobserver.log").read_text()
    for rule in ("bem_laplace", "ch2_coercivity"):
        assert f": run {rule} --out results --quick" in log, log
    assert log.count(": exit 0") == 2 and "refused" not in log
    assert log.rstrip().endswith("jobserver: stopped"), log


def test_second_call_does_nothing(built):
    tree, targets = built
    assert planned(snakemake("-n", *targets, "--configfile", "config/quick.yaml",
                             cwd=tree)) == set()


def test_module_file_change_reruns_its_module_only(built):
    """An edit of a module file reruns its job (a touch alone does not: Snakemake
    compares the checksum of a small input file whose mtime moved)."""
    tree, targets = built
    module = tree / "experiments" / "bem_laplace.py"
    text = module.read_text()
    try:
        module.write_text(text + "# an edit\n")
        r = snakemake("-n", *targets, "--configfile", "config/quick.yaml", cwd=tree)
        assert planned(r) == {"bem_laplace"}
    finally:
        module.write_text(text)


def test_one_config_section_reruns_its_module_only(built, tmp_path):
    tree, targets = built
    extra = tmp_path / "extra.yaml"
    extra.write_text("bem_laplace:\n  n_per_side: [2, 4]\n")
    r = snakemake("-n", *targets, "--configfile", "config/quick.yaml", str(extra), cwd=tree)
    assert planned(r) == {"bem_laplace"}
    # the full configuration differs in both sections: both rerun
    assert planned(snakemake("-n", *targets, cwd=tree)) == {"bem_laplace", "ch2_coercivity"}


def test_slurm_profile_dry_run(tree):
    pytest.importorskip("snakemake_executor_plugin_slurm",
                        reason="snakemake-executor-plugin-slurm not installed "
                               "(pip install -e '.[cluster]')")
    r = snakemake("-n", "--profile", "profiles/slurm", cwd=tree)
    assert r.returncode == 0, r.stdout + r.stderr
    import yaml

    bundles = yaml.safe_load((ROOT / "profiles" / "slurm" / "bundles.yaml").read_text())
    bundled = {r for members in bundles.values() for r in members}
    jobs = {j.rule for j in _registry_module().discover(ROOT / "experiments").jobs}
    assert planned(r) == ({f"bundle_{b}" for b in bundles} | (jobs - bundled)
                          | {"numba_cache", "report"})


def test_bundle_runs_its_jobs_in_one_command(tree, tmp_path):
    """A bundle is one rule whose one command runs its jobs one after another; a bundle
    naming no job is refused."""
    bundles = tmp_path / "bundles.yaml"
    bundles.write_text("cheap: [bem_laplace, ch2_coercivity]\n")
    r = snakemake("-n", "-p", "--config", f"bundles={bundles}", cwd=tree)
    assert {"bundle_cheap"} <= planned(r) and not {"bem_laplace", "ch2_coercivity"} & planned(r)
    assert "hpfebe run bem_laplace ch2_coercivity --out results" in r.stdout
    bundles.write_text("cheap: [bem_laplace, no_such_job]\n")
    r = snakemake("-n", "--config", f"bundles={bundles}", cwd=tree)
    assert r.returncode != 0 and "'no_such_job', which is no job" in r.stdout + r.stderr


# --------------------------------------------------------------------------- orphans
# A job whose parent Snakemake is killed outright: its watch thread polls only every
# 60 s here, so only the hook that every rename calls (hpfebe.suite.watch.before_rename)
# can keep its results out.  The job fills its temporary files while the parent lives
# and renames them just after the parent is gone (what a job finishing 0.03 s after the
# kill -9 did under the 1 s poll).
ORPHAN_JOB = r"""
import os, sys, time
from pathlib import Path
import meshio, numpy as np
from hpfebe.suite import watch
from hpfebe.suite.results import atomic_write
from hpfebe.io.vtu import write_vtu
watch.install_signal_handlers()
parent, out = int(os.environ[watch.PARENT_PID_ENV]), Path(sys.argv[1])
watch.watch_parent(parent, interval=60.0)
def gone():
    try:
        with open(f"/proc/{parent}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except OSError:
        return True
def writer(f):
    f.write("x\n")
    print("writing", flush=True)
    while not gone():
        time.sleep(0.001)
landed = []
for what, write in (
        ("csv", lambda: atomic_write(out / "table_9_9.csv", writer)),
        ("vtu", lambda: write_vtu(out / "table_9_9_u.vtu",
                                  meshio.Mesh(np.zeros((2, 3)), [("line", [[0, 1]])]),
                                  before_rename=watch.before_rename))):
    try:
        write()
        landed.append(what)
    except watch.Terminated:
        pass
print("landed", *landed, flush=True)
"""


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="Linux /proc")
def test_no_result_lands_after_the_parent_is_gone(tmp_path):
    """kill -9 of the parent while its job writes: the job's renames after the kill are
    aborted (no result file, no temporary left), although its watch thread has not
    polled yet."""
    out = tmp_path / "results"
    out.mkdir()
    parent_code = ("import os, subprocess, sys, time\n"
                   "from hpfebe.suite import watch\n"
                   "env = dict(os.environ, **{watch.PARENT_PID_ENV: str(os.getpid())})\n"
                   f"subprocess.Popen([sys.executable, '-c', {ORPHAN_JOB!r}, {str(out)!r}],"
                   " env=env)\n"
                   "time.sleep(120)\n")
    parent = subprocess.Popen([sys.executable, "-c", parent_code], stdout=subprocess.PIPE,
                              text=True)
    try:
        line = parent.stdout.readline()
        assert line.startswith("writing"), line
        parent.kill()
        parent.wait(timeout=10)
        rest = parent.stdout.read()        # the job's stdout: until it ends
    finally:
        parent.kill()
    assert rest.split() == ["landed"], rest
    assert sorted(p.name for p in out.iterdir()) == []


def _job_command(parent_pid, *extra):
    """The command and environment of a cluster job's nested Snakemake (SLURM: srun ->
    snakemake --mode remote --target-jobs RULE:), for bem_laplace, the main Snakemake
    named by the environment as ``parent_pid`` on this host."""
    env = dict(os.environ, HPFEBE_PARENT_PID=str(parent_pid),
               HPFEBE_PARENT_HOST=socket.gethostname())
    return [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--mode",
            "remote", "--target-jobs", "bem_laplace:", "--allowed-rules", "bem_laplace",
            "--cores", "1", "--force", "--nolock", "--configfile", "config/quick.yaml",
            *extra], env


def _job_snakemake(tree, parent_pid):
    cmd, env = _job_command(parent_pid, "--keep-incomplete")
    return subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True,
                          timeout=600)


def test_job_after_the_kill_keeps_old_outputs(tree):
    """A job whose Snakemake starts after the main Snakemake was killed (the next job of
    a SLURM group) fails before Snakemake removes its old outputs; with the main
    Snakemake alive the same command runs the job."""
    (tree / "results" / "logs").mkdir(parents=True)
    (tree / "results" / "logs" / "numba_cache.json").write_text("{}")
    old = {tree / "results" / f"figure_bem_laplace.{ext}": f"old {ext}\n".encode()
           for ext in ("csv", "json", "png")}
    for path, data in old.items():
        path.write_bytes(data)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    r = _job_snakemake(tree, dead.pid)
    assert r.returncode != 0
    assert "the Snakemake that submitted this job has ended" in r.stdout + r.stderr
    assert {p: p.read_bytes() for p in old} == old

    r = _job_snakemake(tree, os.getpid())
    assert r.returncode == 0, r.stdout + r.stderr
    assert all(p.read_bytes() != data for p, data in old.items())


def test_kill_after_the_check_puts_the_old_outputs_back(tree):
    """The main Snakemake killed just after a job's Snakemake checked it (its old outputs
    already set aside, hpfebe.suite.old_outputs): the job stops, fails, and its old
    outputs come back unchanged, with their mtimes."""
    (tree / "results" / "logs").mkdir(parents=True)
    (tree / "results" / "logs" / "numba_cache.json").write_text("{}")
    old = {tree / "results" / f"figure_bem_laplace.{ext}": f"old {ext}\n".encode()
           for ext in ("csv", "json", "png")}
    for path, data in old.items():
        path.write_bytes(data)
    mtimes = {p: p.stat().st_mtime_ns for p in old}
    parent = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    cmd, env = _job_command(parent.pid)     # (without keep-incomplete: the harder case)
    job = subprocess.Popen(cmd, cwd=tree, env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
    try:
        t0 = time.time()
        while all(p.exists() for p in old) and job.poll() is None and time.time() - t0 < 300:
            time.sleep(0.001)
        assert not any(p.exists() for p in old), "the outputs were not set aside"
        parent.kill()
        out, _ = job.communicate(timeout=300)
    finally:
        parent.kill()
        job.kill()
    assert job.returncode != 0, out
    assert {p: p.read_bytes() for p in old} == old, out
    assert {p: p.stat().st_mtime_ns for p in old} == mtimes
    assert not list((tree / ".snakemake" / "hpfebe" / "old-outputs").rglob("*.*"))


# --------------------------------------------------------------------------- registry
def test_registry_finds_demo():
    reg = _registry_module().discover(ROOT / "experiments")
    assert reg.find("figure_bem_laplace").name == "bem_laplace"
    assert reg.find("bem_laplace").artefacts == ("figure_bem_laplace",)
    with pytest.raises(KeyError, match="unknown artefact"):
        reg.find("table_0_0")


def test_registry_rules(tmp_path):
    registry = _registry_module()
    (tmp_path / "ch1_a.py").write_text('"""doc"""\nARTEFACTS = ("table_1_1", "figure_1_1")\n')
    (tmp_path / "helpers.py").write_text("X = 1\n")            # no ARTEFACTS: ignored
    (tmp_path / "_private.py").write_text('ARTEFACTS = ("table_7_7",)\n')  # ignored
    reg = registry.discover(tmp_path)
    assert [e.name for e in reg] == ["ch1_a"]
    assert list(reg.artefacts) == ["table_1_1", "figure_1_1"]

    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_1",)\n')
    with pytest.raises(ValueError, match="claimed by both"):
        registry.discover(tmp_path)
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = tuple(f"t{i}" for i in range(2))\n')
    with pytest.raises(ValueError, match="literal"):
        registry.discover(tmp_path)
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_2",)\nNUMBA = False\n')
    assert [e.numba for e in registry.discover(tmp_path)] == [True, False]
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_2",)\nNUMBA = "no"\n')
    with pytest.raises(ValueError, match="NUMBA must be"):
        registry.discover(tmp_path)
    (tmp_path / "ch1_b.py").unlink()
    (tmp_path / "report.py").write_text('ARTEFACTS = ("table_2_9",)\n')
    with pytest.raises(ValueError, match="reserved"):
        registry.discover(tmp_path)


def test_registry_scenes(tmp_path):
    """SCENES partition ARTEFACTS; each scene is a job `<module>__<scene>`; a module's
    sources are its file and the experiments/ files it imports."""
    registry = _registry_module()
    (tmp_path / "_shared.py").write_text("X = 1\n")
    (tmp_path / "ch1_a.py").write_text(
        'from experiments._shared import X\nARTEFACTS = ("table_1_1", "figure_1_1", '
        '"figure_1_2")\nSCENES = {"one": ("table_1_1", "figure_1_1"), "two": '
        '("figure_1_2",)}\n')
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_2",)\n')
    reg = registry.discover(tmp_path)
    assert [j.rule for j in reg.jobs] == ["ch1_a__one", "ch1_a__two", "ch1_b"]
    assert reg.find_jobs("figure_1_2")[0].artefacts == ("figure_1_2",)
    assert [p.name for p in reg.find("ch1_a").sources] == ["ch1_a.py", "_shared.py"]
    bad = {'{"one": ("table_1_1",), "two": ("figure_1_2",)}': "in no scene",
           '{"one": ("table_1_1", "figure_1_1"), "two": ("figure_1_1", "figure_1_2")}':
               "in scenes",
           '{"one": ("table_1_1", "figure_1_1", "figure_1_2", "table_9_9")}': "not in ARTEFACTS",
           '{"One": ("table_1_1", "figure_1_1", "figure_1_2")}': "scene name",
           'dict(one=("table_1_1",))': "literal dict"}
    for scenes, msg in bad.items():
        (tmp_path / "ch1_a.py").write_text(
            f'ARTEFACTS = ("table_1_1", "figure_1_1", "figure_1_2")\nSCENES = {scenes}\n')
        with pytest.raises(ValueError, match=msg):
            registry.discover(tmp_path)


def test_registry_packages(tmp_path):
    """An experiment may be a package: ARTEFACTS and SCENES in its __init__.py; its
    sources are every file of the package and the experiments/ modules they import
    (absolute, or relative to experiments/ from inside the package)."""
    registry = _registry_module()
    (tmp_path / "_shared.py").write_text("X = 1\n")
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("table_1_2",)\n')
    pkg = tmp_path / "ch1_a"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        'from .scene import Y\nARTEFACTS = ("table_1_1", "figure_1_1")\n'
        'SCENES = {"one": ("table_1_1",), "two": ("figure_1_1",)}\n')
    (pkg / "scene.py").write_text("from .._shared import X\nY = X\n")
    (pkg / "figures.py").write_text("from experiments.ch1_b import ARTEFACTS\n")
    reg = registry.discover(tmp_path)
    assert [j.rule for j in reg.jobs] == ["ch1_a__one", "ch1_a__two", "ch1_b"]
    exp = reg.find("figure_1_1")
    assert exp.path == pkg / "__init__.py"
    assert [str(p.relative_to(tmp_path)) for p in exp.sources] == [
        "ch1_a/__init__.py", "ch1_a/figures.py", "ch1_a/scene.py", "_shared.py", "ch1_b.py"]
    (tmp_path / "ch1_b.py").write_text('ARTEFACTS = ("figure_1_1",)\n')
    with pytest.raises(ValueError, match="claimed by both"):
        registry.discover(tmp_path)


def _priorities(r) -> dict[str, int]:
    """rule -> priority of the jobs a dry run plans."""
    assert r.returncode == 0, r.stdout + r.stderr
    out = {}
    for block in r.stdout.split("\nrule ")[1:]:
        name = block.split(":", 1)[0].strip()
        for line in block.splitlines():
            if line.strip().startswith("priority:"):
                out[name] = int(line.split(":", 1)[1])
    return out


def test_longest_first_from_the_last_run_of_the_same_configuration(tree):
    """The priorities (longest job first) take a job's time from its last result only
    if that run had this configuration: a quick run's times do not order a full run."""
    (tree / "results").mkdir()
    fake = {"provenance": {"run": {"quick": True, "module_wall_time_s": 1.0e6}}}
    (tree / "results" / "figure_bem_laplace.json").write_text(json.dumps(fake))
    full = _priorities(snakemake("-n", "--forceall", cwd=tree))
    quick = _priorities(snakemake("-n", "--forceall", "--configfile", "config/quick.yaml",
                                  cwd=tree))
    top = max(v for k, v in quick.items() if k != "numba_cache")
    assert quick["bem_laplace"] == top                 # its quick result: the longest
    assert full["bem_laplace"] < max(v for k, v in full.items() if k != "numba_cache")
