# hpfebe: reproduce every experiment of the thesis and build the report.
#
#   snakemake -j2                                  full sweeps (config/config.yaml)
#   snakemake -j2 --configfile config/quick.yaml   CI-sized sweeps
#   snakemake -n                                   dry run: what would be (re)built
#   snakemake --profile profiles/slurm             on a SLURM cluster
#
# One rule per job, generated from the registry (hpfebe.suite.registry): a job is a
# scene of an experiment module (rule `<module>__<scene>`) or a module without scenes
# (rule = module name); it runs `python -m hpfebe run <rule>` and writes the artefacts of
# that scene to results/.  What reruns a job (and then the report):
#   - its module file, or an experiments/ file the module imports, changed (its
#     content: Snakemake compares the checksum of a small input whose mtime moved);
#   - its module's config section, or quick/full, changed (params: the merged section);
# nothing else: not another module's section, not README.md, not src/hpfebe (the core:
# rerun what a core change affects with --forcerun RULE, or --forceall; every result
# records the git commit it was built from).  `rule report` builds report/index.html and
# report/report.md.

import atexit
import json
import math
import os
import shlex
import socket
import sys
import threading
import time
from pathlib import Path

configfile: "config/config.yaml"

sys.path.insert(0, str(Path(workflow.basedir, "src")))   # this checkout's hpfebe
from hpfebe.suite.registry import discover, unknown_sections  # noqa: E402  (stdlib only)



def discover_cached(directory):
    """``discover(directory)``, reused from .snakemake/hpfebe/registry.pickle while no
    file under ``directory`` changed (path, size, mtime).  Parsing every experiment file
    takes about 0.5 s of CPU, and on a cluster the Snakefile is read again by the nested
    Snakemakes of every job (a SLURM job of k jobs: 1 + k of them; Snakemake itself
    starts in about 2 s).  Only the main Snakemake writes the cache, from a fresh
    discover(); a nested one falls back to discover() on any mismatch or error."""
    import pickle

    import hpfebe.suite.registry as registry_module

    files = [p for p in directory.rglob("*.py") if "__pycache__" not in p.parts]
    stamp = repr(sorted((str(p), st.st_size, st.st_mtime_ns)
                        for p in [*files, Path(registry_module.__file__)]
                        for st in [p.stat()]))
    cache = Path(".snakemake", "hpfebe", "registry.pickle")
    if not workflow.is_main_process:
        try:
            saved, registry = pickle.loads(cache.read_bytes())
            if saved == stamp:
                return registry
        except Exception:  # missing, partly written by an older run, another Python
            pass
        return discover(directory)
    registry = discover(directory)
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_name(f".{cache.name}.{os.getpid()}")
        tmp.write_bytes(pickle.dumps((stamp, registry)))
        os.replace(tmp, cache)
    except OSError:   # a read-only checkout: no cache
        pass
    return registry


REGISTRY = discover_cached(Path(workflow.basedir) / "experiments")
RESULTS = "results"
LOGS = f"{RESULTS}/logs"
QUICK = config.get("quick", False)
if not isinstance(QUICK, bool):  # "false" is a non-empty string, not false
    raise ValueError(f"config key 'quick' must be true or false, got {QUICK!r}")
for _key, _close in unknown_sections(config, [e.name for e in REGISTRY]):
    if _close:   # a job sees only the files that set its own section: check them all here
        raise ValueError(f"config section {_key!r} is not an experiment module; did you "
                         f"mean {_close!r}?")

# The config files in the order Snakemake merged them: config/config.yaml, then every
# --configfile given on the command line.  The CLI merges them the same way.
CONFIG_FILES = ["config/config.yaml"]
for _f in workflow.config_settings.configfiles:
    _f = Path(os.path.abspath(_f))       # relative to the working directory if inside it
    try:
        _f = _f.relative_to(os.path.abspath(Path.cwd()))
    except ValueError:
        pass
    if str(_f) not in CONFIG_FILES:
        CONFIG_FILES.append(str(_f))


def _top_level_keys(f):
    import yaml

    with open(f, encoding="utf-8") as fh:
        data = yaml.safe_load(fh) or {}
    return set(data) if isinstance(data, dict) else set()


_KEYS = {f: _top_level_keys(f) for f in CONFIG_FILES}


def config_flags(*exps):
    """The job's config files: config/config.yaml and each further file that sets the
    section of one of its modules or `quick` (a file that changes only other modules is
    not part of this job's command, so adding it reruns only those).  The merged top
    level is checked here, for every file: a misspelt section is an error."""
    keys = {e.name for e in exps} | {"quick"}
    files = [f for i, f in enumerate(CONFIG_FILES) if i == 0 or keys & _KEYS[f]]
    return " ".join((["--quick"] if QUICK else [])
                    + [f"--config {shlex.quote(f)}" for f in files])


# One thread per job (snakemake -j2 on 2 cores never oversubscribes): numba, OpenMP and
# BLAS pools are pinned to the job's thread count.
THREAD_VARS = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
               "MKL_NUM_THREADS")
THREAD_ENV = " ".join(f"{v}={{threads}}" for v in THREAD_VARS)
# glibc's allocator in the jobs: arrays below 4 GB from the heap, kept after free (no
# trim, a 256 MB pad) instead of an mmap, first-touch page faults and a munmap for every
# large numpy temporary.  Measured (full --forceall, twice each, A/B in the same hour):
# 93.5 -> 90.0 s wall, 16.1 -> 10.1 s sys, peak RSS 1723 -> 1757 MiB; no effect outside
# glibc.  The job server starts with them too (jobs fork from it: its allocator).
ALLOC_VARS = {"MALLOC_MMAP_THRESHOLD_": "4294967296", "MALLOC_TRIM_THRESHOLD_": "4294967296",
              "MALLOC_TOP_PAD_": "268435456"}
JOB_ENV = " ".join([THREAD_ENV] + [f"{k}={v}" for k, v in ALLOC_VARS.items()])
PYTHON = shlex.quote(sys.executable)

# Interrupted runs: every job watches the Snakemake process that started it (this one:
# the Snakefile is read by it) and stops when it is gone, even after a SIGKILL, instead
# of running on as an orphan that writes into results/; SIGTERM/SIGINT/SIGHUP to a job
# remove its temporary files (hpfebe.suite.watch.install_signal_handlers).  The pid
# reaches the jobs through the environment they inherit, not through their command: a
# value that changes on every call must not be part of a job's command, inputs or params
# (Snakemake would rerun every job every time).  After an interrupted run:
# `snakemake --unlock`, then rerun (see README, "Reliability").
# On a cluster a job runs under nested Snakemakes that read this file again (SLURM:
# sbatch -> snakemake -> srun -> snakemake -> the job): only the main Snakemake sets the
# variables, the nested ones pass on what they inherited (sbatch --export=ALL).  A job
# on the main Snakemake's host watches its pid; a job on another host watches the
# heartbeat file that the main Snakemake rewrites every second (onstart below: where jobs
# run elsewhere), and stops when it has not changed for 10 s (hpfebe.suite.watch
# HEARTBEAT_TIMEOUT_S, watch_heartbeat).  Besides the watch's 1 s poll, every rename of a
# result file checks the parent first and is aborted if it is gone (hpfebe.suite.watch
# before_rename): no result lands after the main Snakemake's death.
if workflow.is_main_process:
    os.environ["HPFEBE_PARENT_PID"] = str(os.getpid())
    os.environ["HPFEBE_PARENT_HOST"] = socket.gethostname()


# The SLURM executor plugin (2.8) waits 10 s longer after every status check that saw no
# job end (up to 180 s): a job ending after a quiet minute was noticed up to 30 s late,
# on the critical path twice (after numba_cache, after the last job).  In the main
# Snakemake the wait is capped at the profile's `seconds-between-status-checks` (the
# plugin uses that setting for nothing else).
if workflow.is_main_process:
    try:
        from snakemake_executor_plugin_slurm import Executor as _SlurmExecutor
    except ImportError:
        _SlurmExecutor = None
    _interval = getattr(_SlurmExecutor, "next_seconds_between_status_checks", None)
    if isinstance(_interval, property) and _interval.fset is not None:

        def _capped(self, value, _set=_interval.fset):
            cap = self.workflow.remote_execution_settings.seconds_between_status_checks
            _set(self, value if value is None or not cap else min(value, cap))

        _SlurmExecutor.next_seconds_between_status_checks = _interval.setter(_capped)


# A cluster job's Snakemake removes the job's old outputs just before it runs the job
# (snakemake.jobs.Job.prepare).  It may start, or reach that point, after the main
# Snakemake was killed (a job from the queue; in a Snakemake group, `--groups`, one
# nested Snakemake runs after another): there it stops first (the job fails, its old
# outputs and log untouched).  The check is made at that moment, not when this file is
# read: a job's Snakemake spends seconds between the two.  The kill can still land just
# after the check, so the old outputs are only set aside (hpfebe.suite.old_outputs): put
# back when the job fails (the job, seeing its parent gone, stops), dropped once the
# job's new outputs have passed Snakemake's checks.
if not workflow.is_main_process:
    from hpfebe.suite import old_outputs
    from hpfebe.suite.watch import parent_gone_from_env
    from snakemake.exceptions import WorkflowError
    from snakemake.io import is_flagged
    from snakemake.jobs import Job as _Job

    async def _remove_existing_output(self, _remove=_Job.remove_existing_output):
        if parent_gone_from_env():
            raise WorkflowError(
                f"the Snakemake that submitted this job has ended: {self.rule.name} does "
                "not run and its old outputs are kept (after an interrupted run: "
                "snakemake --unlock, then rerun)")
        old_outputs.set_aside(self.jobid, [f for f in self.output
                                           if not is_flagged(f, "update")])
        await _remove(self)                     # (the log, and nothing else is left)

    async def _postprocess(self, *args, _post=_Job.postprocess, **kwargs):
        error = kwargs.get("error", False)
        try:           # (raises if the outputs are wrong: then called again with error)
            await _post(self, *args, **kwargs)
        finally:       # (after it: without keep-incomplete it removes a failed job's files)
            if error:
                old_outputs.restore(self.jobid)
        old_outputs.drop(self.jobid)

    _Job.remove_existing_output = _remove_existing_output
    _Job.postprocess = _postprocess


_HEARTBEAT_STOP = threading.Event()


def _heartbeat(path):
    beat = 0
    while not _HEARTBEAT_STOP.wait(1.0):
        beat += 1
        try:
            path.write_text(f"{beat}\n")
        except OSError:       # a full or briefly unavailable file system: try again
            pass


def _end_heartbeat(path):
    _HEARTBEAT_STOP.set()
    path.unlink(missing_ok=True)


# Local runs: a job server (hpfebe.jobserver) imports numpy, scipy, matplotlib,
# scikit-fem and hpfebe once and forks a process per job; `python -m hpfebe` in a job
# hands its command to it (HPFEBE_JOBSERVER, inherited, not part of any command: the
# same jobs rerun with or without it) and runs it itself when the server cannot take it
# (another environment).  Each job's process start-up (interpreter and imports, about
# 2 s) was half of a quick run.  `--config jobserver=false` turns it off.
JOBSERVER = config.get("jobserver", True)
if str(JOBSERVER).lower() in ("true", "false"):   # (--config gives the text)
    JOBSERVER = str(JOBSERVER).lower() == "true"
else:
    raise ValueError(f"config key 'jobserver' must be true or false, got {JOBSERVER!r}")
_JOBSERVER_PROC = []


def _start_jobserver():
    import subprocess
    import tempfile

    sock = Path(tempfile.gettempdir(), f"hpfebe-jobs-{os.getuid()}-{os.getpid()}.sock")
    logfile = Path(".snakemake", "hpfebe", "jobserver.log")
    logfile.parent.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, **{v: "1" for v in THREAD_VARS}, **ALLOC_VARS}  # as every job's
    with open(logfile, "w") as log:
        proc = subprocess.Popen([sys.executable, "-m", "hpfebe.jobserver",
                                 "--socket", str(sock)], stdin=subprocess.PIPE,
                                stdout=log, stderr=log, env=env)
    _JOBSERVER_PROC.append(proc)
    os.environ["HPFEBE_JOBSERVER"] = str(sock)
    os.environ["HPFEBE_JOBSERVER_PID"] = str(proc.pid)
    atexit.register(_stop_jobserver)


def _stop_jobserver():
    for proc in _JOBSERVER_PROC:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=15)
            except Exception:
                proc.kill()
    _JOBSERVER_PROC.clear()
    os.environ.pop("HPFEBE_JOBSERVER", None)


onsuccess:
    _stop_jobserver()


onerror:
    _stop_jobserver()


onstart:
    if not workflow.non_local_exec and workflow.is_main_process and JOBSERVER:
        _start_jobserver()
    if workflow.non_local_exec:      # (known here, not yet when this file is read)
        _hb = Path(".snakemake", "hpfebe", f"heartbeat.{socket.gethostname()}.{os.getpid()}")
        _hb.parent.mkdir(parents=True, exist_ok=True)
        for _old in _hb.parent.glob(f"heartbeat.{socket.gethostname()}.*"):  # kill -9
            if not Path("/proc", _old.suffix[1:]).exists():
                _old.unlink(missing_ok=True)
        _hb.write_text("0\n")
        os.environ["HPFEBE_HEARTBEAT"] = str(_hb.resolve())
        threading.Thread(target=_heartbeat, args=(_hb,), name="hpfebe-heartbeat",
                         daemon=True).start()
        atexit.register(_end_heartbeat, _hb)


def artefact_outputs(artefacts):
    out = []
    for a in artefacts:
        out += [f"{RESULTS}/{a}.csv", f"{RESULTS}/{a}.json"]
        if a.startswith("figure_"):
            out.append(f"{RESULTS}/{a}.png")
    return out


ALL_RESULTS = [p for e in REGISTRY for p in artefact_outputs(e.artefacts)]

# The numba kernels are compiled once, by the first job (`hpfebe compile`), and loaded
# from numba's on-disk cache by every job that calls them (hpfebe.suite.registry: a
# module with NUMBA = False runs beside that job).  Without it the first two jobs of a
# fresh machine compile the same kernels at once.  The stamp is an `ancient` input of
# every numba job, always (an input set that depended on the state of results/ made
# every job rerun): it orders the first run and never makes a built job rerun.
NUMBA_STAMP = f"{LOGS}/numba_cache.json"


def numba_input(*exps):
    return [ancient(NUMBA_STAMP)] if any(e.numba for e in exps) else []


# Longest jobs first (two jobs on two cores: the run ends when its longest job does):
# the job's wall time measured by its last run (results/<artefact>.json) if that run had
# this run's configuration (quick or full: a quick run's times misordered the next full
# run, 95.4 s against 90.4 s), else the figure recorded in config/job_times.yaml
# (tools/job_times.py writes it from a full run).  The recorded figures also size a
# cluster job (runtime, mem_mb): the SLURM profile takes them from here.
JOB_TIMES_FILE = Path(workflow.basedir) / "config" / "job_times.yaml"


def _recorded():
    import yaml

    if not JOB_TIMES_FILE.is_file():
        return {}, {}
    doc = yaml.safe_load(JOB_TIMES_FILE.read_text()) or {}
    return doc.get("wall_s", {}), doc.get("peak_mb", {})


RECORDED_WALL_S, RECORDED_PEAK_MB = _recorded()


def _job_times():
    times = {}
    for job in REGISTRY.jobs:
        try:
            run = json.loads(Path(f"{RESULTS}/{job.artefacts[0]}.json").read_text())[
                "provenance"]["run"]
            if bool(run.get("quick")) != QUICK:
                raise ValueError("measured in the other configuration")
            times[job.rule] = float(run["module_wall_time_s"])
        except (OSError, ValueError, KeyError, TypeError):
            times[job.rule] = float(RECORDED_WALL_S.get(job.rule, 0.0))
    return times


JOB_TIMES = _job_times()
_ORDER = sorted(JOB_TIMES, key=lambda r: -JOB_TIMES[r])


def priority_of(rule):
    return len(_ORDER) - _ORDER.index(rule) if JOB_TIMES.get(rule) else 0


# SLURM bundles (profiles/slurm sets `config: [bundles=profiles/slurm/bundles.yaml]`):
# the jobs of a bundle are one rule, `bundle_<name>`, whose one command runs them one
# after another in one process (`hpfebe run RULE RULE ...`).  On a cluster each job
# costs a SLURM job, or in a Snakemake group a nested Snakemake per job (about 1.5 s)
# besides the interpreter start and imports of each job (about 2.5 s): for the jobs of
# the quick run, which compute for about a second, that was two thirds of a SLURM run.
# A bundle reruns as a whole: an edit of one of its modules reruns its bundle-mates too
# (locally, without the profile, every job stays a rule of its own).
def _bundles():
    import yaml

    path = config.get("bundles")
    if not path:
        return {}
    doc = yaml.safe_load(Path(path).read_text()) or {}
    jobs = {j.rule for j in REGISTRY.jobs}
    seen = {}
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: a mapping of bundle names to lists of jobs expected")
    for name, rules in doc.items():
        if not str(name).isidentifier() or not isinstance(rules, list) or not rules:
            raise ValueError(f"{path}: bundle {name!r} must be a name with a list of jobs")
        for r in rules:
            if r not in jobs:
                raise ValueError(f"{path}: bundle {name!r} names {r!r}, which is no job "
                                 "(snakemake --list-rules)")
            if r in seen:
                raise ValueError(f"{path}: {r!r} is in bundles {seen[r]!r} and {name!r}")
            seen[r] = name
    return {str(k): list(v) for k, v in doc.items()}


BUNDLES = _bundles()
BUNDLED = {r for rules in BUNDLES.values() for r in rules}
JOB_OF = {j.rule: j for j in REGISTRY.jobs}
# what SLURM runs as one job: a bundle (its jobs' times added up) or a job outside them
UNIT_TIMES = {**{r: t for r, t in JOB_TIMES.items() if r not in BUNDLED},
              **{f"bundle_{b}": sum(JOB_TIMES.get(r, 0.0) for r in rules)
                 for b, rules in BUNDLES.items()}}


def slurm_nice(unit):
    """The job's `sbatch --nice`: the number of SLURM jobs measured longer, times the
    number of jobs.  The SLURM executor does not pass Snakemake's priority on; SLURM
    starts jobs of equal priority in the order of submission, which is not this one, and
    (priority/basic) lowers each job's priority by 1 against the one before: a step of 1
    per place would not outweigh that."""
    wall = UNIT_TIMES.get(unit, 0.0)
    longer = sum(t > wall for t in UNIT_TIMES.values())
    return f"--nice={len(UNIT_TIMES) * longer if wall else len(UNIT_TIMES) ** 2}"


def runtime_min(*rules):
    """A cluster job's time limit, minutes: 5x the recorded wall time of its jobs (a
    slower node, a cold numba cache), at least 10 minutes; 60 with a job never measured."""
    walls = [RECORDED_WALL_S.get(r) for r in rules]
    if None in walls:
        return 60
    return max(10, math.ceil(5 * sum(float(w) for w in walls) / 60))


def mem_mb(*rules):
    """A cluster job's memory, MB: 1.5x the largest recorded peak of its jobs, at least
    1000; 4000 with a job never measured."""
    peaks = [RECORDED_PEAK_MB.get(r) for r in rules]
    if None in peaks:
        return 4000
    return max(1000, 100 * math.ceil(1.5 * max(float(m) for m in peaks) / 100))


localrules: all, report


rule all:
    input:
        "report/index.html",
        "report/report.md",


for _job in REGISTRY.jobs:
    if _job.rule in BUNDLED:
        continue
    _exp = _job.experiment

    rule:
        name: _job.rule
        input:
            sources=[str(p.relative_to(workflow.basedir)) for p in _exp.sources],
            numba=numba_input(_exp),
        output:
            artefact_outputs(_job.artefacts),
        log:
            f"{LOGS}/{_job.rule}.log",
        threads: 1
        priority: priority_of(_job.rule)
        resources:
            runtime=runtime_min(_job.rule),
            mem_mb=mem_mb(_job.rule),
            slurm_extra=slurm_nice(_job.rule),
        params:
            rule=_job.rule,     # (the shell string is evaluated when the job runs: no _job)
            flags=config_flags(_exp),
            # the rerun trigger for a config change: this module's merged section alone
            section=json.dumps(config.get(_exp.name) or {}, sort_keys=True),
        shell:
            f"{JOB_ENV} {PYTHON} -m hpfebe run {{params.rule}} --out {RESULTS} "
            "{params.flags} 2> {log}"


for _name, _rules in BUNDLES.items():
    _jobs = [JOB_OF[r] for r in _rules]
    _exps = list({j.experiment.name: j.experiment for j in _jobs}.values())

    rule:
        name: f"bundle_{_name}"
        input:
            sources=sorted({str(p.relative_to(workflow.basedir))
                            for e in _exps for p in e.sources}),
            numba=numba_input(*_exps),
        output:
            [p for j in _jobs for p in artefact_outputs(j.artefacts)],
        log:
            f"{LOGS}/bundle_{_name}.log",
        threads: 1
        priority: max(priority_of(r) for r in _rules)
        resources:
            runtime=runtime_min(*_rules),
            mem_mb=mem_mb(*_rules),
            slurm_extra=slurm_nice(f"bundle_{_name}"),
        params:
            rules=" ".join(_rules),
            flags=config_flags(*_exps),
            section=json.dumps({e.name: config.get(e.name) or {} for e in _exps},
                               sort_keys=True),
        shell:
            f"{JOB_ENV} {PYTHON} -m hpfebe run {{params.rules}} --out {RESULTS} "
            "{params.flags} 2> {log}"


rule numba_cache:
    output:
        NUMBA_STAMP,
    log:
        f"{LOGS}/numba_cache.log",
    threads: 1
    priority: 100
    shell:
        f"{JOB_ENV} {PYTHON} -m hpfebe compile --stamp {{output}} 2> {{log}}"


rule report:
    input:
        results=ALL_RESULTS,
        published=sorted(str(p) for p in Path("report/published").glob("*.csv")),
        builder=sorted(str(p) for p in Path("src/hpfebe/suite").rglob("*.py")),
    output:
        html="report/index.html",
        md="report/report.md",
    log:
        f"{LOGS}/report.log",
    shell:
        f"{JOB_ENV} {PYTHON} -m hpfebe report --results {RESULTS} --out report 2> {{log}}"
