"""Which experiment module produces which artefact.

The registry reads ``ARTEFACTS`` from every ``experiments/*.py`` *without importing the
modules* (``ast``): the Snakefile builds its rules from it in milliseconds, and a module
that fails to import (work in progress, missing dependency) still gets its rule and fails
only when it runs.  Standard library only.

A file is an experiment module if it is not private (``_*.py``), is not this file, and
assigns a tuple of string literals to ``ARTEFACTS`` at module level.  Other files
(helpers shared by experiments) are ignored.  A module that calls no numba kernel says so
with ``NUMBA = False`` (a literal; default True): the workflow runs it beside the job that
compiles the kernels instead of after it.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Experiment", "Registry", "discover", "EXPERIMENTS_DIR", "RESERVED"]

EXPERIMENTS_DIR = Path(__file__).resolve().parent

#: names that cannot be module names (they are Snakemake rules of their own)
RESERVED = frozenset({"all", "report", "registry"})

_ARTEFACT_RE = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class Experiment:
    name: str                    # module name = Snakemake rule name = config section
    path: Path                   # the module file
    artefacts: tuple[str, ...]   # artefact ids, first one used by `hpfebe run`
    numba: bool = True           # calls numba kernels (waits for `hpfebe compile`)

    @property
    def module(self) -> str:
        return f"experiments.{self.name}"


@dataclass(frozen=True)
class Registry:
    experiments: tuple[Experiment, ...]

    def __iter__(self):
        return iter(self.experiments)

    @property
    def artefacts(self) -> dict[str, Experiment]:
        """artefact id -> the experiment producing it (ordered by module, then as
        listed in ARTEFACTS)."""
        return {a: e for e in self.experiments for a in e.artefacts}

    def find(self, name: str) -> Experiment:
        """The experiment producing artefact ``name`` (a module name works too)."""
        arts = self.artefacts
        if name in arts:
            return arts[name]
        for e in self.experiments:
            if e.name == name:
                return e
        known = ", ".join(sorted(arts)) or "(none)"
        raise KeyError(f"unknown artefact {name!r}; known artefacts: {known}")


def _assignments(path: Path) -> dict[str, ast.expr]:
    """The module-level assignments ``NAME = value`` of a file (not executed)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found = {}
    for node in tree.body:
        targets, value = [], None
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        for t in targets:
            if isinstance(t, ast.Name):
                found[t.id] = value
    return found


def _numba_flag(path: Path, assigned: dict[str, ast.expr]) -> bool:
    if "NUMBA" not in assigned:
        return True
    try:
        flag = ast.literal_eval(assigned["NUMBA"])
    except ValueError:
        flag = None
    if not isinstance(flag, bool):
        raise ValueError(f"{path}: NUMBA must be the literal True or False")
    return flag


def _artefacts_of(path: Path, assigned: dict[str, ast.expr] | None = None
                  ) -> tuple[str, ...] | None:
    """ARTEFACTS of a module file, or None if it does not define one."""
    assigned = _assignments(path) if assigned is None else assigned
    if "ARTEFACTS" not in assigned:
        return None
    try:
        arts = ast.literal_eval(assigned["ARTEFACTS"])
    except ValueError:
        raise ValueError(f"{path}: ARTEFACTS must be a literal tuple of strings") from None
    if isinstance(arts, str):
        arts = (arts,)
    if not isinstance(arts, (tuple, list)) or not arts or not all(
            isinstance(a, str) for a in arts):
        raise ValueError(f"{path}: ARTEFACTS must be a non-empty tuple of strings, "
                         f"got {arts!r}")
    for a in arts:
        if not _ARTEFACT_RE.match(a):
            raise ValueError(f"{path}: artefact id {a!r} must be lower case letters, "
                             "digits and underscores (e.g. 'table_2_1')")
    if len(set(arts)) != len(arts):
        raise ValueError(f"{path}: ARTEFACTS lists an artefact twice: {arts!r}")
    return tuple(arts)


def discover(directory: Path | str | None = None) -> Registry:
    """All experiment modules in ``directory`` (default: this package), sorted by name.
    Raises ValueError if two modules claim the same artefact or a module name is
    reserved."""
    directory = Path(directory) if directory is not None else EXPERIMENTS_DIR
    if not directory.is_dir():
        raise FileNotFoundError(f"experiments directory not found: {directory}")
    found: list[Experiment] = []
    owner: dict[str, str] = {}
    for path in sorted(directory.glob("*.py")):
        name = path.stem
        if name.startswith("_") or name == "registry":
            continue
        assigned = _assignments(path)
        arts = _artefacts_of(path, assigned)
        if arts is None:
            continue
        if name in RESERVED or not name.isidentifier():
            raise ValueError(f"{path}: module name {name!r} is not allowed "
                             f"(reserved: {sorted(RESERVED)}; must be an identifier)")
        for a in arts:
            if a in owner:
                raise ValueError(f"artefact {a!r} is claimed by both experiments/"
                                 f"{owner[a]}.py and experiments/{name}.py")
            owner[a] = name
        found.append(Experiment(name=name, path=path, artefacts=arts,
                                numba=_numba_flag(path, assigned)))
    return Registry(tuple(found))
