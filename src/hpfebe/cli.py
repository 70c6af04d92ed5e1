"""Command line: ``hpfebe list | run ARTEFACT | report``.

The experiment modules live in the repository's ``experiments/`` package, not in the
installed package: they are found relative to the repository root (the parent of
``src/`` for an editable install), else in the current directory.
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import os
import re
import sys
import time
from pathlib import Path

from .suite.published import published_file_for
from .suite.watch import (ParentGone, Terminated, check_terminated, install_signal_handlers,
                          terminated_cause, watch_parent_from_env)

log = logging.getLogger("hpfebe")

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2

#: loggers of dependencies kept at WARNING unless -v (scikit-fem logs every assembly at
#: INFO: 132 of 138 lines of a job log before)
NOISY_LOGGERS = ("numba", "skfem", "matplotlib", "PIL", "h5py", "meshio")


class CLIError(Exception):
    """A user-facing error: printed without traceback, exit status 2."""


# --------------------------------------------------------------------------- JIT time
class JitTimer:
    """Wall time a run spends in numba's JIT, from numba's own events
    (``numba.core.event``), outermost events only (nested compiles are not counted twice):

    * ``compile_s``: the ``numba:compile`` events - new machine code (a cold numba cache,
      or a changed source);
    * ``jit_s``: the ``numba:compiler_lock`` holds - compiling, typing and loading
      compiled functions from the on-disk cache (the warm-start cost).

    Use as a context manager; :meth:`as_dict` gives the numbers recorded in a result's
    ``provenance.run`` (``jit_compile_s``, ``jit_s``).  Without numba both stay 0."""

    def __init__(self):
        self.compile_s = 0.0
        self.jit_s = 0.0
        self._listeners = []

    def _listener(self, attr):
        try:
            import numba.core.event as ev
        except ImportError:    # pragma: no cover - numba is a dependency
            return None
        timer = self

        class _Outermost(ev.Listener):
            depth, start = 0, 0.0

            def on_start(self, event):
                if self.depth == 0:
                    self.start = time.perf_counter()
                self.depth += 1

            def on_end(self, event):
                self.depth -= 1
                if self.depth == 0:
                    setattr(timer, attr, getattr(timer, attr)
                            + time.perf_counter() - self.start)

        return ev, _Outermost()

    def __enter__(self):
        for kind, attr in (("numba:compile", "compile_s"),
                           ("numba:compiler_lock", "jit_s")):
            got = self._listener(attr)
            if got is not None:
                ev, lis = got
                ev.register(kind, lis)
                self._listeners.append((ev, kind, lis))
        return self

    def __exit__(self, *exc):
        for ev, kind, lis in self._listeners:
            ev.unregister(kind, lis)
        self._listeners.clear()
        return False

    def as_dict(self) -> dict:
        return {"jit_compile_s": round(self.compile_s, 3), "jit_s": round(self.jit_s, 3)}


# --------------------------------------------------------------------------- interrupted runs
def remove_stale_temporaries(out: Path, artefacts) -> list[Path]:
    """Temporary files ``.<artefact>.<ext>.*.tmp`` left in ``out`` by a run that was
    killed outright (SIGKILL: no handler can clean up); removed before a new run of the
    same module writes there."""
    stale = []
    if out.is_dir():
        for a in artefacts:
            stale += [p for p in out.glob(f".{a}.*.tmp") if p.is_file()]
            stale += [p for p in (out / "vtu").glob(f".{a}_*") if p.is_file()]  # io.vtu
    for p in stale:
        try:
            p.unlink()
            log.info("removed stale temporary file %s (an interrupted run)", p)
        except OSError:
            pass
    return stale


# --------------------------------------------------------------------------- locating
def find_root() -> Path:
    """The repository root: the directory holding ``experiments/__init__.py``.

    Looked up in order: the parent of ``src/`` of this (editable) package, then the
    current working directory."""
    candidates = [Path(__file__).resolve().parents[2], Path.cwd()]
    for c in candidates:
        if (c / "experiments" / "__init__.py").is_file():
            return c
    raise CLIError(
        "cannot find the experiments/ package. Looked in: "
        + ", ".join(str(c) for c in candidates)
        + ". Install the package editable from a checkout (pip install -e '.[dev]') "
        "or run hpfebe from the repository root.")


def _import_experiments(root: Path):
    """Import the ``experiments`` package of ``root`` (and make sure it is that one)."""
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    pkg = importlib.import_module("experiments")
    where = Path(getattr(pkg, "__file__", "") or "").resolve().parent
    if where != (root / "experiments").resolve():
        raise CLIError(f"'import experiments' found {where}, not {root / 'experiments'}: "
                       "another package named 'experiments' shadows the suite's")
    return pkg


def load_registry(root: Path):
    from .suite.registry import discover

    _import_experiments(root)
    try:
        return discover(root / "experiments")
    except (ValueError, SyntaxError) as exc:
        raise CLIError(f"experiment registry: {exc}") from exc


# --------------------------------------------------------------------------- config
def merge(base: dict, over: dict) -> dict:
    """Recursive merge: nested dicts merged, other values of ``over`` replace."""
    out = dict(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merge(out[k], v)
        else:
            out[k] = v
    return out


def read_config_files(files: list[Path]) -> list[tuple[Path, dict]]:
    """Each config file's mapping, in order (CLIError for a missing file, bad YAML or a
    top level that is not a mapping)."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)     # libyaml: 10x faster
    out = []
    for f in files:
        if not f.is_file():
            raise CLIError(f"config file not found: {f}")
        try:
            with open(f, encoding="utf-8") as fh:
                data = yaml.load(fh, Loader=loader) or {}
        except yaml.YAMLError as exc:
            raise CLIError(f"config file {f} is not valid YAML: {exc}") from None
        if not isinstance(data, dict):
            raise CLIError(f"config file {f} must hold a mapping at top level, "
                           f"got {type(data).__name__}")
        out.append((f, data))
    return out


def load_config(files: list[Path], per_file=None) -> dict:
    """The merged configuration of ``files`` (or of their ``per_file`` mappings, read;
    copied: the run never changes what ``where_set`` reports)."""
    import copy

    cfg: dict = {}
    for _, data in per_file or read_config_files(files):
        cfg = merge(cfg, copy.deepcopy(data))
    return cfg


def where_set(per_file: list[tuple[Path, dict]], path: str | None) -> str:
    """Which config files set the dotted ``path`` (``"scene.key[2]"``): for messages."""
    files = [str(f) for f, _ in per_file]
    if not path:
        return "config files: " + ", ".join(files)
    parts = re.sub(r"\[\d+\]", "", path).split(".")
    hits = []
    for f, data in per_file:
        node = data
        for key in parts:
            if not isinstance(node, dict) or key not in node:
                break
            node = node[key]
        else:
            hits.append(str(f))
    if not hits:
        return (f"{parts[-1]!r} is not set in {', '.join(files)}: a default of the "
                "experiment")
    last = f"; {hits[-1]} wins" if len(hits) > 1 else ""
    return f"set in {', '.join(hits)}{last}"


def check_top_level(per_file: list[tuple[Path, dict]], config: dict, modules) -> bool:
    """The merged config's top level: ``quick`` a real bool (``"false"`` is not false),
    every section a mapping, a section name close to a module name but not one of them
    (a misspelling) an error; returns ``quick``."""
    from .suite.registry import unknown_sections

    quick = config.get("quick", False)
    if not isinstance(quick, bool):
        raise CLIError(f"config key 'quick' must be true or false, got {quick!r} "
                       f"({where_set(per_file, 'quick')})")
    for key in modules:
        value = config.get(key)
        if value is not None and not isinstance(value, dict):
            raise CLIError(f"config section {key!r} must be a mapping, got {value!r} "
                           f"({where_set(per_file, key)})")
    for key, close in unknown_sections(config, modules):
        if close:
            raise CLIError(f"config section {key!r} is not an experiment module; did you "
                           f"mean {close!r}? ({where_set(per_file, key)})")
        log.warning("config section %r belongs to no experiment module (%s); ignored",
                    key, where_set(per_file, key))
    return quick


# --------------------------------------------------------------------------- commands
def cmd_list(args) -> int:
    root = find_root()
    registry = load_registry(root)
    published_dir = root / "report" / "published"
    rows = []
    for job in registry.jobs:
        for a in job.artefacts:
            pub = published_file_for(a, published_dir)
            rows.append((a, job.rule, pub.name if pub else "-"))
    claimed = set(registry.artefacts)
    if published_dir.is_dir():
        for f in sorted(published_dir.glob("*.csv")):
            parts = f.stem.split("_")
            if len(parts) >= 3 and parts[0] in ("table", "figure"):
                a = "_".join(parts[:3])
                if a not in claimed:
                    rows.append((a, "(not implemented)", f.name))
                    claimed.add(a)
    if not rows:
        print("no experiment modules found in", root / "experiments")
        return EXIT_OK
    w1 = max(len("artefact"), *(len(r[0]) for r in rows))
    w2 = max(len("job"), *(len(r[1]) for r in rows))
    print(f"{'artefact':<{w1}}  {'job':<{w2}}  published")
    for a, m, p in rows:
        print(f"{a:<{w1}}  {m:<{w2}}  {p}")
    return EXIT_OK


def _check_published(result, published_dir: Path) -> None:
    """The published file named by a result exists and has its key and compared
    columns (so that the report can join them)."""
    if not result.published:
        return
    import pandas as pd

    path = published_dir / result.published
    if not path.is_file():
        raise ValueError(f"{result.name}: published file {result.published!r} not found in "
                         f"{published_dir}")
    cols = list(pd.read_csv(path, comment="#", nrows=0).columns)
    missing = [c for c in (*result.keys, *result.tolerances) if c not in cols]
    if missing:
        raise ValueError(f"{result.name}: columns {missing} are not in {result.published} "
                         f"(its columns: {cols})")
    shared = [c for c in result.table.columns if c in cols]
    if list(result.table.columns[:len(shared)]) != shared:
        log.warning("%s: the published columns %s should come first in the table",
                    result.name, shared)


#: where ``hpfebe run --quick`` writes without ``--out``: quick results never replace the
#: full ones in results/ (the workflow's quick run names results/ itself, with --out)
QUICK_OUT = Path("results") / "quick"


def _peak_rss_mb() -> float | None:
    """The process's peak resident memory so far, MB (Linux: ru_maxrss in kB)."""
    try:
        import resource
    except ImportError:            # pragma: no cover - not on Windows
        return None
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)


def _call_run(module, exp, job, section: dict, quick: bool):
    """``module.run`` for one job: with ``scenes=(scene,)`` for a module with SCENES."""
    if job.scene is None:
        return module.run(section, quick=quick)
    return module.run(section, quick=quick, scenes=(job.scene,))


def _jobs_of(registry, names) -> list:
    """The jobs of ``names`` (artefact ids, job rules, module names) in order, each once."""
    jobs = []
    for name in names:
        try:
            found = registry.find_jobs(name)
        except KeyError as exc:
            raise CLIError(exc.args[0]) from None
        jobs += [j for j in found if j not in jobs]
    return jobs


def _module_of(exp):
    """The experiment module of ``exp``, checked against what the registry read."""
    module = importlib.import_module(exp.module)
    arts = tuple(getattr(module, "ARTEFACTS", ()))
    if arts != exp.artefacts:
        raise CLIError(f"{exp.path}: ARTEFACTS at import ({arts}) differs from the "
                       f"literal read by the registry ({exp.artefacts})")
    if not callable(getattr(module, "run", None)):
        raise CLIError(f"{exp.path} has no function run(config, quick=False)")
    return module


def cmd_run(args) -> int:
    """``hpfebe run NAME [NAME ...]``: the jobs of every name, one after another in this
    process (a SLURM bundle runs its jobs so: one interpreter start and one set of imports
    for all of them; profiles/slurm/bundles.yaml)."""
    root = find_root()
    registry = load_registry(root)
    jobs = _jobs_of(registry, args.artefact)

    if args.config:
        files = [Path(f) for f in args.config]
    else:
        files = [root / "config" / "config.yaml"]
        if args.quick:
            files.append(root / "config" / "quick.yaml")
    per_file = read_config_files(files)
    config = load_config(files, per_file)
    quick = check_top_level(per_file, config, [e.name for e in registry]) or args.quick
    if args.out:
        out = Path(args.out)
    elif quick:
        out = root / QUICK_OUT
        log.info("quick run: writing to %s (results/ keeps the full results; give --out "
                 "to write elsewhere)", out)
    else:
        out = root / "results"

    import matplotlib

    matplotlib.use("Agg", force=True)  # figures are plain Figure objects (no pyplot)

    modules = {}
    for job in jobs:            # every module imported and checked before any job runs
        if job.experiment.name not in modules:
            modules[job.experiment.name] = _module_of(job.experiment)
    for job in jobs:
        _run_job(job, modules[job.experiment.name], config, per_file, files, out, quick,
                 " ".join(args.artefact), root)
    return EXIT_OK


def _run_job(job, module, config, per_file, files, out, quick, asked, root) -> None:
    """Run one job and write its artefacts (validated first, all of them)."""
    from .suite import results as res
    from .suite.params import ConfigError

    exp = job.experiment
    section = config.get(exp.name) or {}
    remove_stale_temporaries(out, job.artefacts)
    log.info("running %s (%s) for %s%s", job.rule, ", ".join(job.artefacts), asked,
             " [quick]" if quick else "")
    t0 = time.perf_counter()
    try:
        with JitTimer() as jit:
            results = _call_run(module, exp, job, section, quick)
    except ConfigError as exc:
        raise CLIError(f"config: {exc} ({where_set(per_file, exc.path)})") from None
    wall = time.perf_counter() - t0
    log.info("%s finished in %.1f s (numba: %.1f s compiling, %.1f s in the JIT in all)",
             job.rule, wall, jit.compile_s, jit.jit_s)

    if not isinstance(results, (list, tuple)) or not all(
            isinstance(r, res.ArtefactResult) for r in results):
        raise ValueError(f"{exp.name}.run must return a list of ArtefactResult, got "
                         f"{type(results).__name__}")
    names = [r.name for r in results]
    if sorted(names) != sorted(job.artefacts):
        what = f"scene {job.scene!r} declares" if job.scene else "ARTEFACTS declares"
        raise ValueError(f"{exp.name}.run returned artefacts {names}, {what} "
                         f"{list(job.artefacts)}")
    published_dir = root / "report" / "published"
    for r in results:  # validate everything before writing anything
        res.validate(r)
        _check_published(r, published_dir)

    run_info = {
        "module": exp.name,
        "job": job.rule,
        "scene": job.scene,
        "artefacts": list(job.artefacts),
        "quick": quick,
        "config_files": [str(f) for f in files],
        "module_wall_time_s": round(wall, 3),
        "peak_rss_mb": _peak_rss_mb(),      # of the process so far (a bundle: its jobs')
        **jit.as_dict(),
        "argv": sys.argv[1:],
    }
    for r in results:
        check_terminated()      # a signal whose exception a finalizer swallowed
        paths = res.write_result(r, out, section, run_info=run_info)
        log.info("wrote %s", ", ".join(str(p) for p in paths))


def cmd_report(args) -> int:
    root = find_root()
    from .suite.report import build_report

    results_dir = Path(args.results) if args.results else root / "results"
    out = Path(args.out) if args.out else root / "report"
    published_dir = Path(args.published) if args.published else root / "report" / "published"
    try:
        registry = load_registry(root)
        expected = {a: e.name for a, e in registry.artefacts.items()}
    except CLIError as exc:
        log.warning("%s; reporting only what is in %s", exc, results_dir)
        expected = {}
    paths = build_report(results_dir, out, published_dir, expected=expected)
    for p in paths:
        log.info("wrote %s", p)
    return EXIT_OK


def cmd_compile(args) -> int:
    """Compile (or load from numba's cache) every numba kernel once; with --stamp FILE,
    record the times in FILE (JSON, written atomically: the workflow's numba_cache rule).
    A complete warm-up leaves ``ready.json`` in the cache directory of this source tree:
    a later call on the same host and the same checkout (numba's source stamps) finds it
    and returns at once (``--force`` runs the warm-up again; a kernel missing from the
    cache would still compile where it is called, as without the warm-up)."""
    import hashlib

    from . import _numba_cache
    from .suite import warmup
    from .suite.results import atomic_write

    cache = Path(os.environ[_numba_cache.ENV])
    ready, key = cache / "ready.json", _numba_cache.ready_key()
    # and what the warm-up runs (outside the digest: it defines no kernel)
    key["warmup"] = hashlib.blake2b(Path(warmup.__file__).read_bytes(),
                                    digest_size=8).hexdigest()
    try:
        done = not args.force and json.loads(ready.read_text()) == key
    except (OSError, ValueError):
        done = False
    with JitTimer() as jit:
        t0 = time.perf_counter()
        steps = {} if done else warmup.compile_kernels()
        wall = time.perf_counter() - t0
    if done:
        log.info("numba kernels ready: compiled before into %s (--force: again)", cache)
    else:
        log.info("numba kernels ready in %.1f s (compiling %.1f s; cache %s): %s", wall,
                 jit.compile_s, cache, ", ".join(f"{k} {v:.2f} s" for k, v in steps.items()))
        if cache.is_dir():
            atomic_write(ready, lambda f: json.dump(key, f))
    if cache.is_dir():
        os.utime(cache)                  # readied now: kept by remove_stale
    for old in _numba_cache.remove_stale():
        log.info("removed the numba cache of an older source tree: %s", old)
    if args.stamp:
        record = dict(wall_s=round(wall, 3), steps_s={k: round(v, 3) for k, v in steps.items()},
                      **jit.as_dict())
        atomic_write(Path(args.stamp), lambda f: json.dump(record, f, indent=1))
    return EXIT_OK


# --------------------------------------------------------------------------- main
def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    p = argparse.ArgumentParser(
        prog="hpfebe",
        description="Reproduce the experiments of the thesis on hp FE/BE coupling and "
                    "contact, and report them beside the published numbers.")
    p.add_argument("--version", action="version", version=f"hpfebe {__version__}")
    p.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    p.add_argument("-q", "--quiet", action="store_true", help="warnings only")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    sp = sub.add_parser("list", help="list every artefact, its module and published file")
    sp.set_defaults(func=cmd_list)

    sp = sub.add_parser("run", help="run the scene producing ARTEFACT (writes every "
                                    "artefact of that scene); several run one after "
                                    "another in this process")
    sp.add_argument("artefact", nargs="+",
                    help="artefact id, e.g. table_2_1 (see `hpfebe list`); a job name "
                         "(module__scene) or a module name (all its scenes) works too")
    sp.add_argument("--quick", action="store_true",
                    help="CI-sized run: merge config/quick.yaml over config/config.yaml "
                         "and pass quick=True")
    sp.add_argument("--out", metavar="DIR", help="output directory (default: results/, "
                                                 "results/quick/ for a quick run)")
    sp.add_argument("--config", metavar="FILE", action="append",
                    help="config file; repeat to merge several in order (default: "
                         "config/config.yaml, plus config/quick.yaml with --quick)")
    sp.set_defaults(func=cmd_run)

    sp = sub.add_parser("report", help="build report/index.html and report/report.md "
                                       "from the results")
    sp.add_argument("--results", metavar="DIR", help="results directory (default: results/)")
    sp.add_argument("--out", metavar="DIR", help="report directory (default: report/)")
    sp.add_argument("--published", metavar="DIR",
                    help="published tables (default: report/published/)")
    sp.set_defaults(func=cmd_report)

    sp = sub.add_parser("compile", help="compile the numba kernels once (a fresh machine's "
                                        "first run; later runs load them from the cache)")
    sp.add_argument("--stamp", metavar="FILE", help="write the times to FILE (JSON)")
    sp.add_argument("--force", action="store_true",
                    help="run the warm-up even if this tree's kernels were readied before")
    sp.set_defaults(func=cmd_compile)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    level = logging.DEBUG if args.verbose else logging.WARNING if args.quiet else logging.INFO
    logging.basicConfig(level=level, stream=sys.stderr,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        datefmt="%H:%M:%S")
    if level > logging.DEBUG:  # dependencies' chatter is never wanted at INFO (job logs
        for name in NOISY_LOGGERS:  # carry our messages; -v shows everything)
            logging.getLogger(name).setLevel(logging.WARNING)
    os.environ.setdefault("MPLBACKEND", "Agg")
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_USAGE
    install_signal_handlers()
    try:
        watch_parent_from_env()
        return args.func(args)
    except (CLIError, ParentGone) as exc:
        print(f"hpfebe: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        from .suite.results import remove_temporaries

        remove_temporaries()
        print("hpfebe: interrupted (no result file was left half written)", file=sys.stderr)
        return 130
    except Terminated as exc:
        return _terminated(exc)
    except Exception as exc:
        cause = terminated_cause(exc)
        if cause is not None:     # raised inside a compiled kernel's callback
            return _terminated(cause)
        log.exception("hpfebe %s failed", args.command)
        return EXIT_FAILED


def _terminated(exc: Terminated) -> int:
    from .suite.results import remove_temporaries

    remove_temporaries()
    why = f": {exc.why}" if exc.why else ""
    print(f"hpfebe: terminated by signal {exc.signum}{why} (no result file was left "
          "half written)", file=sys.stderr)
    return 128 + exc.signum



if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
