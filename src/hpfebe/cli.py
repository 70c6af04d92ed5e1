"""Command line: ``hpfebe list | run ARTEFACT | report``.

The experiment modules live in the repository's ``experiments/`` package, not in the
installed package: they are found relative to the repository root (the parent of
``src/`` for an editable install), else in the current directory.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
import time
from pathlib import Path

from .results import published_file_for

log = logging.getLogger("hpfebe")

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


class CLIError(Exception):
    """A user-facing error: printed without traceback, exit status 2."""


# --------------------------------------------------------------------------- locating
def find_root() -> Path:
    """The repository root: the directory holding ``experiments/registry.py``.

    Looked up in order: the parent of ``src/`` of this (editable) package, then the
    current working directory."""
    candidates = [Path(__file__).resolve().parents[2], Path.cwd()]
    for c in candidates:
        if (c / "experiments" / "registry.py").is_file():
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
    return importlib.import_module("experiments.registry")


def load_registry(root: Path):
    reg = _import_experiments(root)
    try:
        return reg.discover(root / "experiments")
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


def load_config(files: list[Path]) -> dict:
    import yaml

    cfg: dict = {}
    for f in files:
        if not f.is_file():
            raise CLIError(f"config file not found: {f}")
        with open(f, encoding="utf-8") as fh:
            data = yaml.safe_load(fh) or {}
        if not isinstance(data, dict):
            raise CLIError(f"config file {f} must hold a mapping at top level, "
                           f"got {type(data).__name__}")
        cfg = merge(cfg, data)
    return cfg


# --------------------------------------------------------------------------- commands
def cmd_list(args) -> int:
    root = find_root()
    registry = load_registry(root)
    published_dir = root / "report" / "published"
    rows = []
    for exp in registry:
        for a in exp.artefacts:
            pub = published_file_for(a, published_dir)
            rows.append((a, exp.name, pub.name if pub else "-"))
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
    w2 = max(len("module"), *(len(r[1]) for r in rows))
    print(f"{'artefact':<{w1}}  {'module':<{w2}}  published")
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


def cmd_run(args) -> int:
    root = find_root()
    registry = load_registry(root)
    try:
        exp = registry.find(args.artefact)
    except KeyError as exc:
        raise CLIError(exc.args[0]) from None

    if args.config:
        files = [Path(f) for f in args.config]
    else:
        files = [root / "config" / "config.yaml"]
        if args.quick:
            files.append(root / "config" / "quick.yaml")
    config = load_config(files)
    quick = bool(args.quick or config.get("quick", False))
    section = config.get(exp.name) or {}
    if not isinstance(section, dict):
        raise CLIError(f"config section {exp.name!r} must be a mapping, got {section!r}")
    out = Path(args.out) if args.out else root / "results"

    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from . import results as res

    module = importlib.import_module(exp.module)
    arts = tuple(getattr(module, "ARTEFACTS", ()))
    if arts != exp.artefacts:
        raise CLIError(f"{exp.path}: ARTEFACTS at import ({arts}) differs from the "
                       f"literal read by the registry ({exp.artefacts})")
    if not callable(getattr(module, "run", None)):
        raise CLIError(f"{exp.path} has no function run(config, quick=False)")

    log.info("running %s (%s) for %s%s", exp.name, ", ".join(exp.artefacts), args.artefact,
             " [quick]" if quick else "")
    t0 = time.perf_counter()
    results = module.run(section, quick=quick)
    wall = time.perf_counter() - t0
    log.info("%s finished in %.1f s", exp.name, wall)

    if not isinstance(results, (list, tuple)) or not all(
            isinstance(r, res.ArtefactResult) for r in results):
        raise ValueError(f"{exp.name}.run must return a list of ArtefactResult, got "
                         f"{type(results).__name__}")
    names = [r.name for r in results]
    if sorted(names) != sorted(exp.artefacts):
        raise ValueError(f"{exp.name}.run returned artefacts {names}, ARTEFACTS declares "
                         f"{list(exp.artefacts)}")
    published_dir = root / "report" / "published"
    for r in results:  # validate everything before writing anything
        res.validate(r)
        _check_published(r, published_dir)

    run_info = {
        "module": exp.name,
        "artefacts": list(exp.artefacts),
        "quick": quick,
        "config_files": [str(f) for f in files],
        "module_wall_time_s": round(wall, 3),
        "argv": sys.argv[1:],
    }
    for r in results:
        paths = res.write_result(r, out, section, run_info=run_info)
        log.info("wrote %s", ", ".join(str(p) for p in paths))
        if r.figure is not None:
            plt.close(r.figure)
    return EXIT_OK


def cmd_report(args) -> int:
    root = find_root()
    from .report import build_report

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

    sp = sub.add_parser("run", help="run the experiment module producing ARTEFACT "
                                    "(writes all artefacts of that module)")
    sp.add_argument("artefact", help="artefact id, e.g. table_2_1 (see `hpfebe list`); "
                                     "a module name works too")
    sp.add_argument("--quick", action="store_true",
                    help="CI-sized run: merge config/quick.yaml over config/config.yaml "
                         "and pass quick=True")
    sp.add_argument("--out", metavar="DIR", help="output directory (default: results/)")
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
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    level = logging.DEBUG if args.verbose else logging.WARNING if args.quiet else logging.INFO
    logging.basicConfig(level=level, stream=sys.stderr,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        datefmt="%H:%M:%S")
    if level > logging.DEBUG:  # numba's DEBUG chatter is never wanted at INFO
        logging.getLogger("numba").setLevel(logging.WARNING)
    os.environ.setdefault("MPLBACKEND", "Agg")
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_USAGE
    try:
        return args.func(args)
    except CLIError as exc:
        print(f"hpfebe: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("hpfebe: interrupted", file=sys.stderr)
        return 130
    except Exception:
        log.exception("hpfebe %s failed", args.command)
        return EXIT_FAILED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
