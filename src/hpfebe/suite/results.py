"""What an experiment hands back, and how it is written to ``results/``.

An experiment module returns a list of :class:`ArtefactResult` (one per thesis table or
figure it produces); :func:`write_result` turns each into

    <out>/<name>.csv    the table (published columns first, then dof, wall_time_s, ...)
    <out>/<name>.json   claims, notes, meta, keys, tolerances, published file, provenance
    <out>/<name>.png    the figure, if there is one
    <out>/vtu/<name>_<key>.vtu   its ParaView exports (``exports``), one per key; a key
                        exporting several load steps gives <name>_<key>_<k>.vtu, k = 0,
                        1, ..., and the collection <name>_<key>.pvd that plays them

Every file is written atomically (temporary file in the same directory, fsync,
``os.replace``): an interrupted run never leaves a half-written file under the final
name, and the temporary file is removed on any exception and, through
:func:`remove_temporaries`, by the command line's SIGTERM/SIGINT handler.  The JSON file
is written last, so a result is complete when its JSON exists.  The JSON records what
the result holds (``n_rows``, ``columns``, ``has_figure`` and, under ``files``, the size
and sha256 of the CSV and PNG written); :func:`check_result` compares the files against
it, so that a truncated, replaced or emptied file is found "damaged" and never used.

Claims (:class:`Claim`, their kinds and the helpers that build the recurring ones) are
in :mod:`hpfebe.suite.claims`; :func:`validate` checks them with the rest of a result.

This is an edge module: no numerics, only data containers and file writing.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import platform
import subprocess
import tempfile
from dataclasses import dataclass, field
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd

from .claims import Claim, validate_claims

__all__ = [
    "ArtefactResult",
    "validate",
    "write_result",
    "read_result",
    "check_result",
    "DamagedResult",
    "atomic_write",
    "remove_temporaries",
    "provenance",
    "artefact_kind",
    "TOLERANCE_KINDS",
    "VTU_DIR",
]

#: tolerance kinds: ("factor", f) - reproduced/published within [1/f, f];
#: ("abs", a) - |reproduced - published| <= a
TOLERANCE_KINDS = ("factor", "abs")

#: packages whose versions are recorded in every result's provenance
PROVENANCE_PACKAGES = ("numpy", "scipy", "numba", "scikit-fem", "pandas", "matplotlib",
                       "hpfebe")


@dataclass
class ArtefactResult:
    """One thesis artefact (table or figure) as reproduced.

    Parameters
    ----------
    name : str
        the artefact id as in EXPERIMENTS.md, e.g. "table_2_1"
    table : pandas.DataFrame
        the published columns first (same names as report/published/<file>.csv), then
        dof, wall_time_s, ...
    figure : matplotlib.figure.Figure, optional
        required for ``figure_*`` artefacts
    published : str, optional
        the file name in report/published/, e.g. "table_2_1_nitsche_smooth_h_BE.csv"
    keys : tuple of str
        the columns joining the reproduced with the published table
    tolerances : dict
        column -> ("factor", 2.0) or ("abs", 0.15)
    claims : list of Claim
        the thesis's statements, checked
    notes : str
        choices and explanations shown in the report
    meta : dict
        timings (jit_s, run_s), dof, iterations, ...; ``allow_nan_columns`` lists the
        float columns that may contain NaN (e.g. the first rate of a sweep)
    exports : dict
        {key: meshio.Mesh or [(time, meshio.Mesh), ...]}: meshes with fields for
        ParaView (built with :mod:`hpfebe.io.vtu`), ``key`` an identifier.  One mesh is
        written as ``<out>/vtu/<name>_<key>.vtu``; a list of (load step or time, mesh)
        pairs, times increasing, as ``<out>/vtu/<name>_<key>_<k>.vtu`` (k = 0, 1, ...)
        with the ParaView collection ``<out>/vtu/<name>_<key>.pvd``
        (:func:`hpfebe.io.write_vtu_series`)
    """

    name: str
    table: pd.DataFrame
    figure: Any = None
    published: str | None = None
    keys: tuple[str, ...] = ()
    tolerances: dict[str, tuple[str, float]] = field(default_factory=dict)
    claims: list[Claim] = field(default_factory=list)
    notes: str = ""
    meta: dict = field(default_factory=dict)
    exports: dict[str, Any] = field(default_factory=dict)


# --------------------------------------------------------------------------- provenance
def _repo_root() -> Path:
    """The repository holding this (editable) package: parent of ``src/``."""
    return Path(__file__).resolve().parents[2]


def _git(*args: str, cwd: Path) -> str | None:
    try:
        out = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True,
                             timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def _version(pkg: str) -> str:
    try:
        return metadata.version(pkg)
    except metadata.PackageNotFoundError:
        return "not installed"


def provenance(config: dict | None = None, run_info: dict | None = None) -> dict:
    """Where a result comes from: git commit (or "unknown"), whether the work tree had
    uncommitted changes, package and Python versions, the config used, the UTC date,
    the host's CPU count and the thread-count environment variables."""
    root = _repo_root()
    commit = _git("rev-parse", "HEAD", cwd=root)
    status = _git("status", "--porcelain", "--untracked-files=no", cwd=root) if commit else None
    try:
        affinity = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        affinity = None
    prov = {
        "git_commit": commit or "unknown",
        "git_dirty": (status is not None) if commit else None,
        "packages": {pkg: _version(pkg) for pkg in PROVENANCE_PACKAGES},
        "python": platform.python_version(),
        "platform": platform.platform(),
        "config": config if config is not None else {},
        "date_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "host_cpu_count": os.cpu_count(),
        "cpus_available": affinity,
        "threads_env": {k: os.environ.get(k) for k in (
            "NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
            "MKL_NUM_THREADS")},
    }
    if run_info:
        prov["run"] = run_info
    return prov


# --------------------------------------------------------------------------- atomic I/O
def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: temporary files of atomic writes in progress (removed by remove_temporaries)
_ACTIVE_TEMPORARIES: set[str] = set()


def remove_temporaries() -> list[str]:
    """Remove the temporary files of atomic writes in progress (for a signal handler:
    the process is about to exit).  Returns the paths removed."""
    removed = []
    for tmp in list(_ACTIVE_TEMPORARIES):
        try:
            os.unlink(tmp)
            removed.append(tmp)
        except OSError:
            pass
        _ACTIVE_TEMPORARIES.discard(tmp)
    return removed


def atomic_write(path: Path | str, writer: Callable[[Any], None], mode: str = "w") -> Path:
    """Write ``path`` atomically: ``writer(f)`` fills a temporary file in the same
    directory, which is flushed, fsync'ed and renamed over ``path``.  If anything
    raises (``BaseException``: also KeyboardInterrupt, SystemExit and the command line's
    signal exits), the temporary file is removed and ``path`` is left as it was; while
    the write is in progress the temporary file is registered for
    :func:`remove_temporaries`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    _ACTIVE_TEMPORARIES.add(tmp)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
        with os.fdopen(fd, mode, **({} if "b" in mode else {"encoding": "utf-8",
                                                             "newline": ""})) as f:
            writer(f)
            f.flush()
            os.fsync(f.fileno())
        from .watch import before_rename

        before_rename(path)   # the job watch: no rename once the parent Snakemake is gone
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    finally:
        _ACTIVE_TEMPORARIES.discard(tmp)
    try:  # make the rename itself durable (best effort, not on every platform)
        dfd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass
    return path


def _jsonable(obj):
    """Plain JSON types; non-finite floats become the strings "NaN"/"Infinity"/
    "-Infinity" (explicit, and the file stays valid JSON)."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_jsonable(v) for v in obj.tolist()]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        if math.isnan(x):
            return "NaN"
        if math.isinf(x):
            return "Infinity" if x > 0 else "-Infinity"
        return x
    if obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, Path):
        return str(obj)
    return str(obj)


# --------------------------------------------------------------------------- validation
def validate(result: ArtefactResult) -> None:
    """Check a result against the contract; ``ValueError`` names what is wrong."""
    name = result.name
    if not isinstance(name, str) or not name or any(c in name for c in "/\\ ."):
        raise ValueError(f"result name must be a plain artefact id like 'table_2_1', "
                         f"got {name!r}")
    if not isinstance(result.table, pd.DataFrame):
        raise ValueError(f"{name}: table must be a pandas.DataFrame, got "
                         f"{type(result.table).__name__}")
    cols = [str(c) for c in result.table.columns]
    if len(set(cols)) != len(cols):
        dup = sorted({c for c in cols if cols.count(c) > 1})
        raise ValueError(f"{name}: duplicate table columns {dup}")
    for k in result.keys:
        if k not in cols:
            raise ValueError(f"{name}: key column {k!r} is not in the table (columns: {cols})")
    for col, tol in result.tolerances.items():
        if col not in cols:
            raise ValueError(f"{name}: tolerance column {col!r} is not in the table "
                             f"(columns: {cols})")
        if (not isinstance(tol, (tuple, list)) or len(tol) != 2
                or tol[0] not in TOLERANCE_KINDS):
            raise ValueError(f"{name}: tolerance for {col!r} must be ('factor', f) or "
                             f"('abs', a), got {tol!r}")
        if not (isinstance(tol[1], (int, float)) and math.isfinite(tol[1]) and tol[1] >= 0
                and (tol[0] != "factor" or tol[1] >= 1)):
            raise ValueError(f"{name}: tolerance value for {col!r} must be finite, >= 0 "
                             f"(>= 1 for 'factor'), got {tol[1]!r}")
    if result.tolerances and result.published and not result.keys:
        raise ValueError(f"{name}: tolerances against a published table need join keys")
    if result.published is not None and (
            not isinstance(result.published, str) or "/" in result.published):
        raise ValueError(f"{name}: published must be a file name in report/published/, "
                         f"got {result.published!r}")
    validate_claims(name, result.claims)
    allowed = set(result.meta.get("allow_nan_columns", ()))
    unknown = allowed - set(cols)
    if unknown:
        raise ValueError(f"{name}: allow_nan_columns names columns not in the table: "
                         f"{sorted(unknown)}")
    for col in result.table.columns:
        s = result.table[col]
        if str(col) in allowed:
            continue
        bad = s.isna()  # NaN in float columns, NaN/None/NA in text or nullable ones
        if bad.any():
            raise ValueError(
                f"{name}: column {col!r} has NaN (missing values) in {int(bad.sum())} "
                f"row(s) (first row "
                f"{int(np.flatnonzero(bad.to_numpy())[0])}); NaN is allowed only in "
                "columns listed in meta['allow_nan_columns'] and explained in notes")
    if name.startswith("figure_") and result.figure is None:
        raise ValueError(f"{name}: figure artefacts must return a figure")
    _validate_exports(name, result.exports)


def _validate_exports(name: str, exports) -> None:
    """``exports`` = {identifier: meshio.Mesh or non-empty [(time, meshio.Mesh), ...]
    with finite, strictly increasing times}; ValueError naming the key otherwise."""
    if not isinstance(exports, dict):
        raise ValueError(f"{name}: exports must be a dict {{key: meshio.Mesh}}, got "
                         f"{type(exports).__name__}")
    if not exports:
        return
    import meshio

    for key, value in exports.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise ValueError(f"{name}: exports key {key!r} must be an identifier "
                             "(it is part of a file name)")
        if isinstance(value, meshio.Mesh):
            continue
        steps = list(value) if isinstance(value, (list, tuple)) else None
        if not steps or not all(isinstance(s, (list, tuple)) and len(s) == 2
                                and isinstance(s[1], meshio.Mesh) for s in steps):
            raise ValueError(f"{name}: exports[{key!r}] must be a meshio.Mesh or a non-empty "
                             "list of (time, meshio.Mesh) pairs (a load-step series), got "
                             f"{type(value).__name__}")
        times = [s[0] for s in steps]
        if not all(isinstance(t, (int, float, np.integer, np.floating))
                   and not isinstance(t, (bool, np.bool_)) and math.isfinite(t)
                   for t in times) or np.any(np.diff(np.asarray(times, float)) <= 0):
            raise ValueError(f"{name}: exports[{key!r}]: the times of a series must be "
                             f"finite numbers, strictly increasing, got {times!r}")


# --------------------------------------------------------------------------- writing
def write_result(result: ArtefactResult, out_dir: Path | str, config: dict | None = None,
                 *, run_info: dict | None = None) -> list[Path]:
    """Write a result into ``out_dir``, every file atomically.

    Parameters
    ----------
    result : ArtefactResult
        validated first (:func:`validate`)
    out_dir : str or Path
        the results folder
    config : dict, optional
        the config used (into the provenance)
    run_info : dict, optional
        quick flag, config files, wall time of the run (into the provenance)

    Returns
    -------
    list of Path
        the files written, in order: ``<out>/<name>.csv``, ``<name>.png`` (if there is
        a figure), the exports (``<out>/vtu/<name>_<key>.vtu``, and for a series its
        VTU files and ``.pvd``), and ``<name>.json`` last (a result is complete when
        its JSON exists).

    Raises
    ------
    ValueError
        naming the column, if a float column has NaN that is not in
        ``result.meta['allow_nan_columns']``, and for any other breach of the contract.
    """
    validate(result)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []

    table = result.table.copy()
    table.columns = [str(c) for c in table.columns]
    csv_bytes = table.to_csv(index=False).encode("utf-8")
    written.append(atomic_write(out / f"{result.name}.csv", lambda f: f.write(csv_bytes),
                                mode="wb"))
    files = {"csv": _file_record(written[-1].name, csv_bytes), "png": None}

    png = out / f"{result.name}.png"
    if result.figure is not None:
        from .figures import png_bytes as figure_png     # matplotlib: only with a figure

        png_bytes = figure_png(result.figure, dpi=120)
        written.append(atomic_write(png, lambda f: f.write(png_bytes), mode="wb"))
        files["png"] = _file_record(png.name, png_bytes)
    elif png.exists():  # a stale figure from an earlier run would be mistaken as current
        png.unlink()

    exports = _write_exports(result, out)
    written += exports

    doc = {
        "name": result.name,
        "kind": artefact_kind(result.name),
        "published": result.published,
        "keys": list(result.keys),
        "tolerances": {k: [v[0], v[1]] for k, v in result.tolerances.items()},
        "claims": [{"text": c.text, "holds": c.holds, "evidence": c.evidence,
                    "kind": c.kind, "id": c.id, "explains": list(c.explains)}
                   for c in result.claims],
        "notes": result.notes,
        "meta": result.meta,
        "columns": list(table.columns),
        "n_rows": int(len(table)),
        "has_figure": result.figure is not None,
        "files": files,
        "exports": [p.relative_to(out).as_posix() for p in exports],
        "provenance": provenance(config, run_info),
    }
    text = json.dumps(_jsonable(doc), indent=2, allow_nan=False) + "\n"
    written.append(atomic_write(out / f"{result.name}.json", lambda f: f.write(text)))
    return written


#: the folder of ``results/`` that holds the ParaView exports
VTU_DIR = "vtu"


def _write_exports(result: ArtefactResult, out: Path) -> list[Path]:
    """The exports of ``result`` written into ``<out>/vtu/`` (atomically, the job watch
    asked before every rename): ``<name>_<key>.vtu`` for one mesh, the VTU files of a
    series and its ``.pvd`` collection (last) for a list of (time, mesh)."""
    if not result.exports:
        return []
    import meshio

    from ..io.vtu import write_vtu, write_vtu_series
    from .watch import before_rename

    folder = out / VTU_DIR
    paths: list[Path] = []
    for key, value in result.exports.items():
        stem = f"{result.name}_{key}"
        if isinstance(value, meshio.Mesh):
            paths.append(write_vtu(folder / f"{stem}.vtu", value, before_rename=before_rename))
        else:
            paths += write_vtu_series(folder / f"{stem}.pvd", value,
                                      before_rename=before_rename)
    return paths


def artefact_kind(name: str) -> str:
    """'table' for table_*, 'figure' for figure_*, else 'other'."""
    if name.startswith("table_"):
        return "table"
    if name.startswith("figure_"):
        return "figure"
    return "other"


def _file_record(name: str, data: bytes) -> dict:
    return {"name": name, "bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}


class DamagedResult(ValueError):
    """A result whose files do not match what its JSON says it holds; ``problems``
    lists every mismatch."""

    def __init__(self, name: str, problems: list[str]):
        super().__init__(f"{name}: damaged result: " + "; ".join(problems))
        self.name, self.problems = name, problems


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _check_file(path: Path, record, what: str, problems: list[str]) -> bytes | None:
    """The bytes of ``path`` if it matches ``record`` (size and sha256 from the JSON;
    None = not recorded, by an older writer), else None with the mismatch in
    ``problems``."""
    if not path.is_file():
        problems.append(f"{what} file {path.name} is missing")
        return None
    data = path.read_bytes()
    if not data:
        problems.append(f"{what} file {path.name} is empty (0 bytes)")
        return None
    if isinstance(record, dict):
        if record.get("bytes") is not None and record.get("bytes") != len(data):
            problems.append(f"{what} file {path.name} has {len(data)} bytes, the JSON "
                            f"records {record.get('bytes')}")
            return None
        if record.get("sha256") and record["sha256"] != hashlib.sha256(data).hexdigest():
            problems.append(f"{what} file {path.name}: sha256 differs from the one "
                            "recorded in the JSON (changed after it was written)")
            return None
    return data


def check_result(results_dir: Path | str, name: str
                 ) -> tuple[dict, pd.DataFrame, Path | None] | None:
    """The checked JSON document, table and figure path (None if the result has no
    figure) of a written result; None if its JSON is missing (not built, or
    interrupted before the JSON was written).

    Raises :class:`DamagedResult` listing every mismatch if the JSON is not a JSON
    object, or the CSV/PNG do not match what the JSON records (size and sha256 of the
    files written, row count, columns, figure present; a PNG must be a PNG)."""
    d = Path(results_dir)
    js, csv, png = d / f"{name}.json", d / f"{name}.csv", d / f"{name}.png"
    if not js.exists():
        return None
    try:
        with open(js, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, ValueError) as exc:
        raise DamagedResult(name, [f"{js.name} is not valid JSON ({exc})"]) from None
    if not isinstance(doc, dict):
        raise DamagedResult(name, [f"{js.name} holds a JSON {type(doc).__name__}, not an "
                                   "object"])
    problems: list[str] = []
    for key, tp, what in (("claims", list, "a list"), ("meta", dict, "an object"),
                          ("provenance", dict, "an object"), ("notes", str, "a string"),
                          ("keys", list, "a list"), ("tolerances", dict, "an object"),
                          ("files", dict, "an object")):
        if doc.get(key) is not None and not isinstance(doc[key], tp):
            problems.append(f"{js.name}: {key!r} must be {what}, got "
                            f"{type(doc[key]).__name__}")
    run = doc["provenance"].get("run") if isinstance(doc.get("provenance"), dict) else None
    if run is not None and not isinstance(run, dict):
        problems.append(f"{js.name}: 'provenance.run' must be an object")
    if isinstance(doc.get("claims"), list) and not all(
            isinstance(c, dict) for c in doc["claims"]):
        problems.append(f"{js.name}: every claim must be an object")
    if problems:
        raise DamagedResult(name, problems)
    files = doc.get("files") if isinstance(doc.get("files"), dict) else {}
    data = _check_file(csv, files.get("csv"), "table", problems)
    table = None
    if data is not None:
        try:
            table = pd.read_csv(io.BytesIO(data))
        except Exception as exc:  # noqa: BLE001 - any parse failure is damage
            problems.append(f"table file {csv.name} cannot be read ({exc})")
    if table is not None:
        cols = doc.get("columns")
        if isinstance(cols, list) and [str(c) for c in table.columns] != cols:
            problems.append(f"table columns {list(table.columns)} differ from the JSON's "
                            f"{cols}")
        n = doc.get("n_rows")
        if isinstance(n, int) and len(table) != n:
            problems.append(f"table has {len(table)} rows, the JSON records {n}")
    png_path = None
    if doc.get("has_figure"):
        img = _check_file(png, files.get("png"), "figure", problems)
        if img is not None and not img.startswith(_PNG_SIGNATURE):
            problems.append(f"figure file {png.name} is not a PNG image")
        elif img is not None:
            png_path = png
    if problems:
        raise DamagedResult(name, problems)
    return doc, table, png_path


def read_result(results_dir: Path | str, name: str) -> tuple[dict, pd.DataFrame] | None:
    """The JSON document and the table of a written result, or None if either is
    missing (not built, or interrupted before the JSON was written); DamagedResult
    (a ValueError) if the files do not match what the JSON records (see
    :func:`check_result`)."""
    d = Path(results_dir)
    if not (d / f"{name}.json").exists() or not (d / f"{name}.csv").exists():
        return None
    doc, table, _ = check_result(d, name)
    return doc, table

