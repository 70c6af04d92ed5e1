#!/usr/bin/env python
"""The figures of the layout (issue 24, DESIGN.md), printed by one command.

    python tools/check_layout.py            # print every figure; exit 1 if one fails
    python tools/check_layout.py --list     # also list every offender
    python tools/check_layout.py --open "experiments/ lines"   # a known open figure

Limits checked:

* src/hpfebe: no file over 600 lines, no class over 300 lines, no function over 100 lines
  except numba kernels (functions decorated with ``njit``/``jit``/``vectorize``; they are
  counted and named apart);
* experiments/: under 4000 lines in all, no file over 500 lines;
* no import cycle between the units of hpfebe and no import up the layers of DESIGN.md
  (``tools/check_imports.py``);
* experiments import only public names (``check_imports.py --experiments --strict``);
* the curated API: ``hpfebe.__all__`` has about 25 names (20-40 accepted).

A line is a line of the file (docstrings and comments included): what a reader reads.
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import check_imports  # noqa: E402

SRC = ROOT / "src" / "hpfebe"
EXPERIMENTS = ROOT / "experiments"
LIMITS = {"src_file": 600, "class": 300, "function": 100,
          "experiments_total": 4000, "experiment_file": 500}
KERNEL_DECORATORS = {"njit", "jit", "vectorize", "guvectorize", "stencil"}


def n_lines(path: Path) -> int:
    return len(path.read_text().splitlines())


def is_kernel(node) -> bool:
    for dec in node.decorator_list:
        target = dec.func if isinstance(dec, ast.Call) else dec
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
        if name in KERNEL_DECORATORS:
            return True
    return False


def definitions(path: Path):
    """(kind, qualified name, lines, is_kernel) of every class and function of a file."""
    tree = ast.parse(path.read_text())

    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                start = min([child.lineno] + [d.lineno for d in child.decorator_list])
                size = child.end_lineno - start + 1
                kind = "class" if isinstance(child, ast.ClassDef) else "function"
                name = f"{prefix}{child.name}"
                yield kind, name, size, kind == "function" and is_kernel(child)
                yield from walk(child, name + ".")

    yield from walk(tree, "")


def rel(path: Path) -> str:
    return str(path.relative_to(ROOT))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--list", action="store_true", help="list every offender")
    ap.add_argument("--open", action="append", default=[], metavar="WORDS",
                    help="a figure known to be over its limit (matched by words of its "
                         "name): printed as OPEN, not a failure; repeatable")
    args = ap.parse_args(argv)
    rows = []            # (figure, value, limit, ok, offenders)

    src_files = sorted(SRC.rglob("*.py"))
    big = [(rel(p), n) for p in src_files if (n := n_lines(p)) > LIMITS["src_file"]]
    rows.append(("src files over 600 lines", len(big), 0, not big, big))
    classes, functions, kernels = [], [], []
    for p in src_files:
        for kind, name, size, kernel in definitions(p):
            where = f"{rel(p)}:{name}"
            if kind == "class" and size > LIMITS["class"]:
                classes.append((where, size))
            elif kind == "function" and size > LIMITS["function"]:
                (kernels if kernel else functions).append((where, size))
    rows.append(("classes over 300 lines", len(classes), 0, not classes, classes))
    rows.append(("functions over 100 lines (not numba kernels)", len(functions), 0,
                 not functions, functions))
    rows.append(("numba kernels over 100 lines (allowed)", len(kernels), None, True, kernels))

    exp_files = sorted(EXPERIMENTS.rglob("*.py"))
    total = sum(n_lines(p) for p in exp_files)
    rows.append(("experiments/ lines in all", total, LIMITS["experiments_total"] - 1,
                 total < LIMITS["experiments_total"], []))
    big = [(rel(p), n) for p in exp_files if (n := n_lines(p)) > LIMITS["experiment_file"]]
    rows.append(("experiment files over 500 lines", len(big), 0, not big, big))

    cycles = check_imports.check_cycles(quiet=True)
    rows.append(("import cycles between hpfebe units", cycles, 0, cycles == 0, []))
    up = check_imports.layer_violations()
    rows.append(("imports up the layers of DESIGN.md", len(up), 0, not up, up))
    deep = check_imports.deep_imports()
    rows.append(("experiments' imports of non-public names", len(deep), 0, not deep, deep))

    sys.path.insert(0, str(ROOT / "src"))
    import hpfebe
    n_api = len([n for n in hpfebe.__all__ if not n.startswith("__")])
    rows.append(("names in hpfebe.__all__ (about 25)", n_api, "20-40", 20 <= n_api <= 40, []))

    width = max(len(r[0]) for r in rows)
    failed = n_open = 0
    for figure, value, limit, ok, offenders in rows:
        known = not ok and any(w in figure for w in args.open)
        mark = "ok  " if ok else ("OPEN" if known else "FAIL")
        failed += not ok and not known
        n_open += known
        lim = "" if limit is None else f"  (limit {limit})"
        print(f"{mark} {figure:<{width}} {value}{lim}")
        if offenders and (args.list or not ok):
            for item in offenders:
                print(f"       {item}" if isinstance(item, str) else
                      f"       {item[0]}  {item[1]} lines")
    print(f"{len(rows) - failed - n_open} of {len(rows)} figures within their limits"
          + (f", {n_open} known open" if n_open else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
