"""A job's old outputs are set aside, not removed, until the job has succeeded.

Snakemake removes a job's old outputs just before it runs the job
(``snakemake.jobs.Job.remove_existing_output``).  When the main Snakemake dies between
that moment and the job's end (``kill -9`` of it while a cluster job's Snakemake is still
starting: the job then stops, :mod:`hpfebe.suite.watch`), the job wrote nothing new and
the old results were gone.  The Snakefile's patch instead moves them under
``.snakemake/hpfebe/old-outputs/`` (a rename: same file system, the file's mtime kept),
puts them back when the job fails, whatever the reason, and drops them only once
Snakemake has checked the job's new outputs.  A failed job's outputs are therefore
all-or-nothing: the old complete set, or (first run) what the job wrote.
"""

from __future__ import annotations

import atexit
import errno
import os
import shutil
from pathlib import Path

#: where a job's old outputs wait, below the working directory
OLD_OUTPUTS_DIR = Path(".snakemake", "hpfebe", "old-outputs")

#: the outputs set aside in this process and not yet restored or dropped, by job key:
#: (the key's folder, [(output, its copy set aside)])
_ASIDE: dict[object, tuple[Path, list[tuple[Path, Path]]]] = {}


def _move(src: Path, dst: Path) -> None:
    try:
        os.replace(src, dst)
    except OSError as exc:            # another file system: copy, keeping the mtime
        if exc.errno != errno.EXDEV:
            raise
        shutil.move(src, dst)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def set_aside(key, outputs, root: Path | None = None) -> list[Path]:
    """Move the existing files (or directories) among ``outputs`` out of the way, for the
    job ``key``; return the ones moved.  A second call for the same key first puts back
    what the first set aside (a job restarted by Snakemake)."""
    restore(key)
    base = Path(root or OLD_OUTPUTS_DIR, f"{os.getpid()}-{key}")
    moved = []
    for out in map(Path, outputs):
        if not out.exists() and not out.is_symlink():
            continue
        rel = out.relative_to(out.anchor) if out.is_absolute() else out
        aside = base / rel
        aside.parent.mkdir(parents=True, exist_ok=True)
        _remove(aside)
        _move(out, aside)
        _ASIDE.setdefault(key, (base, []))[1].append((out, aside))
        moved.append(out)
    return moved


def restore(key) -> list[Path]:
    """Put back the outputs set aside for ``key`` (the job failed), replacing what the
    failed job wrote; return them."""
    base, pairs = _ASIDE.pop(key, (None, []))
    for out, aside in pairs:
        if out.exists() or out.is_symlink():
            _remove(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        _move(aside, out)
    if base is not None:
        shutil.rmtree(base, ignore_errors=True)
    return [out for out, _aside in pairs]


def drop(key) -> None:
    """Delete the outputs set aside for ``key`` (the job succeeded)."""
    base, _pairs = _ASIDE.pop(key, (None, []))
    if base is not None:
        shutil.rmtree(base, ignore_errors=True)


def restore_all() -> None:
    """Put back everything still set aside (this Snakemake ends without a job's end
    being seen: an exception, a signal that lets ``atexit`` run)."""
    for key in list(_ASIDE):
        restore(key)


atexit.register(restore_all)
