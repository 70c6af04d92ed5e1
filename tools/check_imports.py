#!/usr/bin/env python
"""Import layering of src/hpfebe: no cycle between its subpackages and top-level modules,
and every import goes down the layers of DESIGN.md.

Every import statement of every module is read (``ast``; module level and inside
functions alike, absolute and relative) and mapped to the *unit* it reaches: the
top-level subpackage (``hpfebe.contact``) or top-level module (``hpfebe.plastic_be``)
of hpfebe; ``hpfebe`` itself is the root ``__init__``.  ``from hpfebe import x`` reaches
the unit ``x`` when ``x`` is a subpackage or module, the root otherwise.  Imports within
one unit are not edges.  A strongly connected set of units (Tarjan) is a cycle; each is
printed with one shortest cycle through it and the file:line of every edge on it.

The layers (:data:`LAYERS`, bottom first, as DESIGN.md lists them): a unit may import only
units of lower layers.  An import up the list (``solvers`` importing ``contact``) is a
layering violation, printed with its file:line; a unit missing from :data:`LAYERS` is an
error (a new subpackage gets its place in DESIGN.md and here).

    python tools/check_imports.py                 # exit 1 if any cycle or violation
    python tools/check_imports.py --graph         # also print every edge
    python tools/check_imports.py --experiments   # deep imports in experiments/

``--experiments`` lists each ``from hpfebe.<...> import name`` of experiments/*.py whose
name is not in the ``__all__`` of ``hpfebe`` or of a top-level subpackage's ``__init__``
(and each ``import hpfebe.<deep>``); it reports them and, for now, exits 0 (``--strict``
makes it exit 1).
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import defaultdict, deque
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the layers of DESIGN.md ("The core, as data flows through it"), bottom first; the root
#: ``hpfebe`` (its lazy curated API reaches every layer) sits on top with the CLI
LAYERS = (("_numba_cache", "checks"), ("geometry", "quadrature"), ("spaces",), ("constitutive",), ("solvers",), ("bem",),
          ("fem",), ("analysis",), ("bodies",), ("coupling",), ("contact",), ("adaptivity",),
          ("io",), ("scenes",), ("suite",), ("cli", "__main__", "jobclient", "jobserver", "hpfebe"))
PKG = ROOT / "src" / "hpfebe"
PKG_NAME = "hpfebe"


def module_name(path: Path) -> str:
    """Dotted name of a file under src/hpfebe ('hpfebe.contact.mortar', 'hpfebe.contact')."""
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def unit_of(dotted: str) -> str | None:
    """The top-level unit of a dotted hpfebe name: 'hpfebe.contact.laws' -> 'contact';
    'hpfebe' -> 'hpfebe' (the root __init__); None outside hpfebe."""
    parts = dotted.split(".")
    if parts[0] != PKG_NAME:
        return None
    if len(parts) == 1:
        return PKG_NAME
    return parts[1]


def top_units() -> set[str]:
    """Names of the top-level subpackages and modules of hpfebe."""
    out = set()
    for p in PKG.iterdir():
        if p.is_dir() and (p / "__init__.py").exists():
            out.add(p.name)
        elif p.suffix == ".py" and p.name != "__init__.py":
            out.add(p.stem)
    return out


def resolve_from(node: ast.ImportFrom, here: str, package: bool) -> str:
    """Absolute module of ``from <...> import ...`` in module ``here``."""
    if node.level == 0:
        return node.module or ""
    base = here.split(".") if package else here.split(".")[:-1]
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(path: Path):
    """(line, absolute target module, imported names or None) for every import in path."""
    here = module_name(path)
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield node.lineno, a.name, None
        elif isinstance(node, ast.ImportFrom):
            yield node.lineno, resolve_from(node, here, is_package(path)), \
                [a.name for a in node.names]


def edges() -> dict[tuple[str, str], list[str]]:
    """(unit, unit) -> ['file:line', ...] for every import between two units."""
    units = top_units()
    out: dict[tuple[str, str], list[str]] = defaultdict(list)
    for path in sorted(PKG.rglob("*.py")):
        src = unit_of(module_name(path))
        rel = path.relative_to(ROOT)
        for line, target, names in imports_of(path):
            dst = unit_of(target)
            if dst is None:
                continue
            dsts = {dst}
            if dst == PKG_NAME and names is not None:
                # from hpfebe import geometry, BoundaryMesh: a submodule or the root facade
                dsts = {n if n in units else PKG_NAME for n in names}
            for d in dsts:
                if d != src:
                    out[(src, d)].append(f"{rel}:{line}")
    return out


def strongly_connected(nodes, succ) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one node."""
    index, low, stack, on, comps = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(succ[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(sorted(comp))

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return comps


def shortest_cycle(start: str, comp: set[str], succ) -> list[str]:
    """A shortest cycle start -> ... -> start inside comp (breadth first)."""
    prev = {start: None}
    queue = deque([start])
    while queue:
        v = queue.popleft()
        for w in sorted(succ[v] & comp):
            if w == start:
                path = [v]
                while prev[path[-1]] is not None:
                    path.append(prev[path[-1]])
                return path[::-1] + [start]  # path ends at start: prev[start] is None
            if w not in prev:
                prev[w] = v
                queue.append(w)
    return []


def check_cycles(show_graph: bool = False, quiet: bool = False) -> int:
    """Number of import cycles (strongly connected sets of units); printed unless quiet."""
    e = edges()
    succ = defaultdict(set)
    nodes = set()
    for a, b in e:
        succ[a].add(b)
        nodes |= {a, b}
    if show_graph:
        for (a, b), where in sorted(e.items()):
            print(f"{a} -> {b}: {', '.join(where)}")
    comps = strongly_connected(nodes, succ)
    if quiet:
        return len(comps)
    if not comps:
        print(f"no import cycle between the {len(top_units())} units of hpfebe "
              f"({len(e)} unit edges)")
        return 0
    for comp in comps:
        cset = set(comp)
        print(f"import cycle among {len(comp)} units: {', '.join(comp)}")
        # one shortest cycle through each unit, each printed once
        seen = set()
        for start in comp:
            cyc = shortest_cycle(start, cset, succ)
            key = frozenset(zip(cyc, cyc[1:]))
            if not cyc or key in seen:
                continue
            seen.add(key)
            print("  " + " -> ".join(cyc))
            for a, b in zip(cyc, cyc[1:]):
                print(f"    {a} -> {b}: {', '.join(e[(a, b)])}")
    return len(comps)


def public_names() -> dict[str, set[str]]:
    """'hpfebe' and 'hpfebe.<subpackage>' -> the names of their ``__all__`` (imported from
    this tree's src/: the root's ``__all__`` is computed, not a literal)."""
    import importlib
    sys.path.insert(0, str(PKG.parent))
    names = [PKG_NAME] + [module_name(i) for i in sorted(PKG.glob("*/__init__.py"))]
    return {n: set(getattr(importlib.import_module(n), "__all__", ())) for n in names}


def deep_imports() -> list[str]:
    """Each import of a non-public hpfebe name in experiments/ (packages included), as
    'file:line: from ... import name  (public: ...)'."""
    return _deep_imports()[0]


def _deep_imports():
    public = public_names()
    where = {}                                   # public name -> the facades exporting it
    for mod, names in public.items():
        for n in names:
            where.setdefault(n, []).append(mod)
    deep, by_module = [], defaultdict(int)
    for path in sorted((ROOT / "experiments").rglob("*.py")):
        rel = path.relative_to(ROOT)
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module \
                    and node.module.split(".")[0] == PKG_NAME:
                names = public.get(node.module)
                for a in node.names:
                    if names is None or a.name not in names:
                        hint = (f"  (public: {', '.join(where[a.name])})"
                                if a.name in where else "")
                        deep.append(f"{rel}:{node.lineno}: from {node.module} import "
                                    f"{a.name}{hint}")
                        by_module[node.module] += 1
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.split(".")[0] == PKG_NAME and a.name not in public:
                        deep.append(f"{rel}:{node.lineno}: import {a.name}")
                        by_module[a.name] += 1
    return deep, by_module


def check_experiments(strict: bool = False) -> int:
    deep, by_module = _deep_imports()
    for d in deep:
        print(d)
    print("deep imports by module: " + ", ".join(
        f"{m} {k}" for m, k in sorted(by_module.items(), key=lambda t: (-t[1], t[0]))))
    hinted = sum("(public:" in d for d in deep)
    print(f"{hinted} of them are public names imported by a deep path")
    print(f"{len(deep)} deep imports (names outside the __all__ of hpfebe and of its "
          f"subpackages) in experiments/")
    return 1 if (strict and deep) else 0


def layer_violations() -> list[str]:
    """Each unit edge that goes up the layers (or reaches a unit with no layer), with the
    file:line of its imports."""
    rank = {u: i for i, layer in enumerate(LAYERS) for u in layer}
    out = [f"unit {u!r} has no layer: add it to LAYERS (tools/check_imports.py) and "
           f"to DESIGN.md" for u in sorted(top_units() | {PKG_NAME}) if u not in rank]
    for (a, b), where in sorted(edges().items()):
        if a in rank and b in rank and rank[b] > rank[a]:
            out.append(f"{a} (layer {rank[a]}) imports {b} (layer {rank[b]}): "
                       f"{', '.join(where)}")
    return out


def check_layers() -> int:
    bad = layer_violations()
    for line in bad:
        print(line)
    print(f"{len(bad)} layering violations ({len(LAYERS)} layers)")
    return len(bad)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--graph", action="store_true", help="print every unit edge")
    ap.add_argument("--experiments", action="store_true",
                    help="report deep imports in experiments/*.py (exit 0 unless --strict)")
    ap.add_argument("--strict", action="store_true", help="with --experiments: exit 1 on any")
    args = ap.parse_args(argv)
    if args.experiments:
        return check_experiments(args.strict)
    cycles = check_cycles(args.graph)
    return 1 if (cycles or check_layers()) else 0


if __name__ == "__main__":
    sys.exit(main())
