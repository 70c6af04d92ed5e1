"""Which experiment module produces which artefact.

The registry reads ``ARTEFACTS`` from every ``experiments/*.py`` *without importing the
modules* (``ast``): the Snakefile builds its rules from it in milliseconds, and a module
that fails to import (work in progress, missing dependency) still gets its rule and fails
only when it runs.  Standard library only (the Snakefile imports it from the checkout's
``src/`` before anything else of hpfebe).

A file is an experiment module if it is not private (``_*.py``) and
assigns a tuple of string literals to ``ARTEFACTS`` at module level.  An experiment may
also be a package, ``experiments/<name>/__init__.py`` (scene, claims and figures in
modules beside it): its ``__init__.py`` holds ``ARTEFACTS``, ``SCENES`` and ``run``.  Other files
(helpers shared by experiments) are ignored.  A module that calls no numba kernel says so
with ``NUMBA = False`` (a literal; default True): the workflow runs it beside the job that
compiles the kernels instead of after it.

A module whose artefacts come from independent computations declares them as scenes, a
literal dict ``SCENES = {"name": ("artefact", ...), ...}`` whose values partition
``ARTEFACTS``; its ``run(config, quick=False, scenes=None)`` then computes only the
scenes asked for.  Every scene is one workflow job (:attr:`Job.rule`: the module name for
a module without SCENES, ``<module>__<scene>`` otherwise), so that asking for one
artefact computes only its scene and independent scenes run on different cores.

The workflow inputs of a job are its module file (every file of a package) and the
``experiments/`` files it imports (``from experiments.X import ...`` / ``import
experiments.X``, followed through those files): :attr:`Experiment.sources`.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Experiment", "Job", "Registry", "discover", "unknown_sections", "RESERVED",
           "SCENE_SEP"]

#: names that cannot be module names (they are Snakemake rules of their own)
RESERVED = frozenset({"all", "report", "numba_cache"})

_ARTEFACT_RE = re.compile(r"^[a-z][a-z0-9_]*$")
_SCENE_RE = re.compile(r"^[a-z][a-z0-9]*(_[a-z0-9]+)*$")

#: between module and scene in a job's rule name: ``ch4_plasticity__example1``
SCENE_SEP = "__"


@dataclass(frozen=True)
class Experiment:
    name: str                    # module name = config section
    path: Path                   # the module file
    artefacts: tuple[str, ...]   # artefact ids, first one used by `hpfebe run`
    numba: bool = True           # calls numba kernels (waits for `hpfebe compile`)
    #: scene name -> its artefacts (``None``: the module has no SCENES, one job)
    scenes: tuple[tuple[str, tuple[str, ...]], ...] | None = None
    #: the module file and the experiments/ files it imports (workflow inputs)
    sources: tuple[Path, ...] = ()

    @property
    def module(self) -> str:
        return f"experiments.{self.name}"

    @property
    def jobs(self) -> tuple[Job, ...]:
        """One workflow job per scene (one job for a module without SCENES)."""
        if self.scenes is None:
            return (Job(self, None, self.artefacts),)
        return tuple(Job(self, s, arts) for s, arts in self.scenes)


@dataclass(frozen=True)
class Job:
    """One workflow job: a scene of an experiment module (or the whole module)."""

    experiment: Experiment
    scene: str | None            # None: the module has no SCENES
    artefacts: tuple[str, ...]

    @property
    def rule(self) -> str:
        """Snakemake rule name: the module name, or ``<module>__<scene>``."""
        e = self.experiment
        return e.name if self.scene is None else f"{e.name}{SCENE_SEP}{self.scene}"


@dataclass(frozen=True)
class Registry:
    experiments: tuple[Experiment, ...]

    def __iter__(self):
        return iter(self.experiments)

    @property
    def jobs(self) -> tuple[Job, ...]:
        return tuple(j for e in self.experiments for j in e.jobs)

    @property
    def artefacts(self) -> dict[str, Experiment]:
        """artefact id -> the experiment producing it (ordered by module, then as
        listed in ARTEFACTS)."""
        return {a: e for e in self.experiments for a in e.artefacts}

    def find(self, name: str) -> Experiment:
        """The experiment producing artefact ``name`` (a module or job name works too)."""
        return self.find_jobs(name)[0].experiment

    def find_jobs(self, name: str) -> tuple[Job, ...]:
        """The jobs to run for ``name``: an artefact id (its scene's job), a job's rule
        name (``<module>__<scene>``), or a module name (all its jobs)."""
        for j in self.jobs:
            if name in j.artefacts or name == j.rule:
                return (j,)
        for e in self.experiments:
            if e.name == name:
                return e.jobs
        known = ", ".join(sorted(self.artefacts)) or "(none)"
        raise KeyError(f"unknown artefact {name!r}; known artefacts: {known}")


def _per_file(fn):
    """Memoise ``fn(path, ...)`` on the file's (path, inode, mtime, size): a process that
    discovers the registry again (the job server's forked jobs) parses only what changed."""
    memo: dict = {}

    def cached(path: Path, *args):
        st = path.stat()
        key = (str(path), st.st_ino, st.st_mtime_ns, st.st_size, *map(str, args))
        if key not in memo:
            memo[key] = fn(path, *args)
        return memo[key]
    cached.__doc__ = fn.__doc__
    return cached


@_per_file
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


def _scenes_of(path: Path, assigned: dict[str, ast.expr], artefacts: tuple[str, ...]
               ) -> tuple[tuple[str, tuple[str, ...]], ...] | None:
    """SCENES of a module file (None if it defines none), checked to partition
    ``artefacts``."""
    if "SCENES" not in assigned:
        return None
    try:
        scenes = ast.literal_eval(assigned["SCENES"])
    except ValueError:
        raise ValueError(f"{path}: SCENES must be a literal dict of scene name -> tuple "
                         "of artefact ids") from None
    if not isinstance(scenes, dict) or not scenes:
        raise ValueError(f"{path}: SCENES must be a non-empty dict, got {scenes!r}")
    seen: dict[str, str] = {}
    out = []
    for name, arts in scenes.items():
        if not isinstance(name, str) or not _SCENE_RE.match(name):
            raise ValueError(f"{path}: scene name {name!r} must be lower case letters and "
                             "digits, words joined by single underscores")
        if isinstance(arts, str):
            arts = (arts,)
        if not isinstance(arts, (tuple, list)) or not arts or not all(
                isinstance(a, str) for a in arts):
            raise ValueError(f"{path}: SCENES[{name!r}] must be a non-empty tuple of "
                             f"artefact ids, got {arts!r}")
        for a in arts:
            if a not in artefacts:
                raise ValueError(f"{path}: SCENES[{name!r}] names {a!r}, which is not in "
                                 "ARTEFACTS")
            if a in seen:
                raise ValueError(f"{path}: artefact {a!r} is in scenes {seen[a]!r} and "
                                 f"{name!r}")
            seen[a] = name
        out.append((name, tuple(arts)))
    missing = [a for a in artefacts if a not in seen]
    if missing:
        raise ValueError(f"{path}: artefacts {missing} are in no scene of SCENES")
    return tuple(out)


def _module_files(name: str, directory: Path) -> tuple[Path, ...]:
    """The files of the experiments/ module ``name``: ``name.py``, or every file of the
    package ``name/``; () if there is neither."""
    if (directory / f"{name}.py").is_file():
        return (directory / f"{name}.py",)
    if (directory / name / "__init__.py").is_file():
        return tuple(sorted((directory / name).rglob("*.py")))
    return ()


@_per_file
def _imported_names(path: Path, depth: int) -> frozenset[str]:
    """Names of the ``experiments/`` modules that ``path`` (``depth`` folders below
    experiments/) imports at any level, whether they exist or not."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0 and node.module and node.module.startswith("experiments."):
                names.add(node.module.split(".")[1])
            elif node.level == 0 and node.module == "experiments":
                names.update(a.name for a in node.names)
            elif node.level == depth + 1:           # relative to experiments/ itself
                names.update([node.module.split(".")[0]] if node.module
                             else [a.name for a in node.names])
        elif isinstance(node, ast.Import):
            names.update(a.name.split(".")[1] for a in node.names
                         if a.name.startswith("experiments."))
    return frozenset(names)


def _imported_experiments(path: Path, directory: Path) -> set[str]:
    """Names of the ``experiments/`` modules that ``path`` imports (at any level)."""
    depth = len(path.relative_to(directory).parts) - 1    # 0: experiments/x.py
    return {m for m in _imported_names(path, depth) if _module_files(m, directory)}


def _sources(name: str, directory: Path) -> tuple[Path, ...]:
    """The files of module ``name`` and of every experiments/ module they import,
    transitively: the module's own files first, the imported ones sorted."""
    own = _module_files(name, directory)
    seen, todo = {name}, [name]
    while todo:
        for f in _module_files(todo.pop(), directory):
            for m in _imported_experiments(f, directory):
                if m not in seen:
                    seen.add(m)
                    todo.append(m)
    return (*own, *sorted(f for m in seen - {name} for f in _module_files(m, directory)))


def unknown_sections(config: dict, modules) -> list[tuple[str, str | None]]:
    """Top-level keys of a merged config that are neither a workflow key (``quick``,
    ``bundles``: the SLURM profile's bundles file, ``jobserver``: the local job server)
    nor a module name, each with the module name it is a likely misspelling of (or
    None)."""
    import difflib

    modules = sorted(modules)
    out = []
    for key in config:
        if key not in ("quick", "bundles", "jobserver") and key not in modules:
            close = difflib.get_close_matches(str(key), modules, n=1, cutoff=0.8)
            out.append((str(key), close[0] if close else None))
    return out


def discover(directory: Path | str) -> Registry:
    """All experiment modules in ``directory`` (the checkout's ``experiments/``), sorted
    by name.  Raises ValueError if two modules claim the same artefact or a module name
    is reserved."""
    directory = Path(directory)
    if not directory.is_dir():
        raise FileNotFoundError(f"experiments directory not found: {directory}")
    found: list[Experiment] = []
    owner: dict[str, str] = {}
    candidates = [*directory.glob("*.py"), *directory.glob("*/__init__.py")]
    for path in sorted(candidates, key=lambda p: (p.parent.name if p.name == "__init__.py"
                                                 else p.stem)):
        name = path.parent.name if path.name == "__init__.py" else path.stem
        if name.startswith("_"):
            continue
        assigned = _assignments(path)
        arts = _artefacts_of(path, assigned)
        if arts is None:
            continue
        if name in RESERVED or not name.isidentifier() or SCENE_SEP in name:
            raise ValueError(f"{path}: module name {name!r} is not allowed "
                             f"(reserved: {sorted(RESERVED)}; must be an identifier "
                             f"without {SCENE_SEP!r})")
        for a in arts:
            if a in owner:
                raise ValueError(f"artefact {a!r} is claimed by both experiments/"
                                 f"{owner[a]} and experiments/{name}")
            owner[a] = name
        found.append(Experiment(name=name, path=path, artefacts=arts,
                                numba=_numba_flag(path, assigned),
                                scenes=_scenes_of(path, assigned, arts),
                                sources=_sources(name, directory)))
    return Registry(tuple(found))
