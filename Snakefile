# hpfebe: reproduce every experiment of the thesis and build the report.
#
#   snakemake -j2                                  full sweeps (config/config.yaml)
#   snakemake -j2 --configfile config/quick.yaml   CI-sized sweeps
#   snakemake -n                                   dry run: what would be (re)built
#   snakemake --profile profiles/slurm             on a SLURM cluster
#
# One rule per experiment module in experiments/ (rule name = module name), generated
# from the registry; each runs `python -m hpfebe run <first artefact>` and writes all
# artefacts of its module to results/.  A change of the module file or of a config file
# reruns it.  `rule report` builds report/index.html and report/report.md.

import os
import shlex
import sys
from pathlib import Path

configfile: "config/config.yaml"

sys.path.insert(0, workflow.basedir)
from experiments.registry import discover  # noqa: E402  (standard library only)

REGISTRY = discover(Path(workflow.basedir) / "experiments")
RESULTS = "results"
LOGS = f"{RESULTS}/logs"
QUICK = config.get("quick", False)
if not isinstance(QUICK, bool):  # "false" is a non-empty string, not false
    raise ValueError(f"config key 'quick' must be true or false, got {QUICK!r}")

# The config files in the order Snakemake merged them: config/config.yaml, then every
# --configfile given on the command line.  The CLI merges them the same way.
CONFIG_FILES = ["config/config.yaml"]
for _f in workflow.config_settings.configfiles:
    _f = Path(_f)
    try:
        _f = _f.resolve().relative_to(Path.cwd().resolve())
    except ValueError:
        pass
    if str(_f) not in CONFIG_FILES:
        CONFIG_FILES.append(str(_f))

# One thread per job (snakemake -j2 on 2 cores never oversubscribes): numba, OpenMP and
# BLAS pools are pinned to the job's thread count.
THREAD_ENV = " ".join(f"{v}={{threads}}" for v in (
    "NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"))
PYTHON = shlex.quote(sys.executable)

# Interrupted runs: every job watches the Snakemake process that started it (this one:
# the Snakefile is read by it) and stops when it is gone, even after a SIGKILL, instead
# of running on as an orphan that writes into results/; SIGTERM/SIGINT/SIGHUP to a job
# remove its temporary files (hpfebe.cli.install_signal_handlers).  After an interrupted
# run: `snakemake --unlock`, then rerun (see README, "Reliability").
WATCH_ENV = f"HPFEBE_PARENT_PID={os.getpid()}"


def artefact_outputs(artefacts):
    out = []
    for a in artefacts:
        out += [f"{RESULTS}/{a}.csv", f"{RESULTS}/{a}.json"]
        if a.startswith("figure_"):
            out.append(f"{RESULTS}/{a}.png")
    return out


ALL_RESULTS = [p for e in REGISTRY for p in artefact_outputs(e.artefacts)]

# The numba kernels are compiled once, by the first job (`hpfebe compile`), and loaded
# from numba's on-disk cache by every module that calls them (experiments/registry.py:
# a module with NUMBA = False runs beside that job).  Without it the first two jobs of a
# fresh machine compile the same kernels at once.  Only modules whose results are missing
# wait for the stamp (a pure ordering: the stamp never makes a built module rerun).
NUMBA_STAMP = f"{LOGS}/numba_cache.json"


def waits_for_numba(exp):
    return exp.numba and not all(Path(p).exists() for p in artefact_outputs(exp.artefacts))


# Longest modules first (two jobs on two cores: the run ends when its longest module
# does; the report's Timing table has the measured times).  Others get priority 0.
LONGEST_FIRST = ["ch4_plasticity", "ch4_section44", "ch2_convergence", "ch4_mortar",
                 "ch4_adaptive_fefe", "ch3_penalty_hp", "ch3_adaptive_bem"]


def priority_of(name):
    return len(LONGEST_FIRST) - LONGEST_FIRST.index(name) if name in LONGEST_FIRST else 0


localrules: all, report


rule all:
    input:
        "report/index.html",
        "report/report.md",


for _exp in REGISTRY:

    rule:
        name: _exp.name
        input:
            module=str(_exp.path.relative_to(workflow.basedir)),
            config=CONFIG_FILES,
            numba=[ancient(NUMBA_STAMP)] if waits_for_numba(_exp) else [],
        output:
            artefact_outputs(_exp.artefacts),
        log:
            f"{LOGS}/{_exp.name}.log",
        threads: 1
        priority: priority_of(_exp.name)
        params:
            artefact=_exp.artefacts[0],
            flags=" ".join((["--quick"] if QUICK else [])
                           + [f"--config {shlex.quote(f)}" for f in CONFIG_FILES]),
        shell:
            f"{WATCH_ENV} {THREAD_ENV} {PYTHON} -m hpfebe run {{params.artefact}} --out {RESULTS} "
            "{params.flags} 2> {log}"


rule numba_cache:
    output:
        NUMBA_STAMP,
    log:
        f"{LOGS}/numba_cache.log",
    threads: 1
    priority: 100
    shell:
        f"{WATCH_ENV} {THREAD_ENV} {PYTHON} -m hpfebe compile --stamp {{output}} 2> {{log}}"


rule report:
    input:
        results=ALL_RESULTS,
        published=sorted(str(p) for p in Path("report/published").glob("*.csv")),
        builder="src/hpfebe/report.py",
    output:
        html="report/index.html",
        md="report/report.md",
    log:
        f"{LOGS}/report.log",
    shell:
        f"{WATCH_ENV} {PYTHON} -m hpfebe report --results {RESULTS} --out report 2> {{log}}"
