"""numba's on-disk cache, keyed on the sources of every kernel.

numba keys a cached function on the contents of its own file only: a kernel that calls a
jitted function of another file (the BEM assembly calls :mod:`hpfebe.bem.integration` and
:mod:`hpfebe.bem.kernels`; the mortar Uzawa kernel calls
:func:`hpfebe.constitutive.laws.tresca_return`) keeps the machine code of the callee it
was compiled with, and after an edit of the callee the old code runs, silently.  So
:func:`configure` points numba's cache at a directory named by a digest of every source
file of the package that uses numba: an edit of any of them gives a fresh cache (the
kernels compile once more, about a minute of CPU), an unchanged tree finds its own.

The directory is ``<root>/hpfebe-<digest>``, with ``<root>`` the ``NUMBA_CACHE_DIR`` the
user set, else ``$XDG_CACHE_HOME/hpfebe/numba`` (``~/.cache/hpfebe/numba``).  Every
process of one source tree (the workflow's jobs, the tests) computes the same name, so
``hpfebe compile`` readies the kernels for all of them, and keeps the three digest
directories it readied last (:func:`remove_stale`).
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
#: the environment variable numba reads (before numba is imported)
ENV = "NUMBA_CACHE_DIR"
PREFIX = "hpfebe-"


#: the package's units above every kernel (module doc), relative to the package
ABOVE_KERNELS = ("scenes", "suite", "__init__.py", "__main__.py", "cli.py", "jobclient.py",
                 "jobserver.py")
#: a jitted function defined in a file (decorator or call)
_DEFINES_JIT = re.compile(rb"\b(njit|jit|vectorize|guvectorize|stencil|cfunc|overload|"
                          rb"register_jitable)\b\s*\(|@(numba\.)?(njit|jit|vectorize|"
                          rb"guvectorize|stencil|cfunc|overload|register_jitable)\b")


def kernel_sources(package: Path = PACKAGE):
    """(path, bytes) of the package's files that the kernels' machine code can depend on:
    every file that mentions numba, but those of :data:`ABOVE_KERNELS` that define no
    jitted function."""
    for path in sorted(package.rglob("*.py")):
        data = path.read_bytes()
        if b"numba" not in data:
            continue
        if (path.relative_to(package).parts[0] in ABOVE_KERNELS
                and not _DEFINES_JIT.search(data)):
            continue
        yield path, data


def sources_digest(package: Path = PACKAGE) -> str:
    """A digest of :func:`kernel_sources` (path and content), 16 hex digits."""
    h = hashlib.blake2b(digest_size=8)
    for path, data in kernel_sources(package):
        h.update(str(path.relative_to(package)).encode() + b"\0" + data + b"\0")
    return h.hexdigest()


def cache_root() -> Path:
    """Where the digest directories live: the ``NUMBA_CACHE_DIR`` the user set (or its
    parent, when it is already a digest directory: a child process of an hpfebe process
    inherits that), else ``$XDG_CACHE_HOME/hpfebe/numba``."""
    user = os.environ.get(ENV)
    if user:
        user = Path(user)
        return user.parent if user.name.startswith(PREFIX) else user
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "hpfebe" / "numba"


def configure() -> Path:
    """Point numba's cache at this source tree's directory and return it.  Called by
    ``import hpfebe``, before any kernel is defined."""
    cache = cache_root() / f"{PREFIX}{sources_digest()}"
    os.environ[ENV] = str(cache)
    if "numba" in sys.modules:           # numba imported before hpfebe: tell its config
        sys.modules["numba"].config.CACHE_DIR = str(cache)
    return cache


def remove_stale(keep: int = 3) -> list[Path]:
    """Remove the digest directories of the cache root but the ``keep`` most recently
    readied ones (``hpfebe compile`` touches the current one); returns them."""
    root = cache_root()
    dirs = sorted((d for d in root.glob(f"{PREFIX}*") if d.is_dir()),
                  key=lambda d: d.stat().st_mtime, reverse=True) if root.is_dir() else []
    current = Path(os.environ.get(ENV, ""))
    stale = [d for d in dirs[keep:] if d != current]
    for d in stale:
        shutil.rmtree(d, ignore_errors=True)
    return stale


def source_stamps(package: Path = PACKAGE) -> list:
    """numba's freshness stamp of every file of :func:`kernel_sources`: (path,
    mtime, size).  numba keeps a cached kernel only while its file's stamp is the one it
    was compiled with, so a fresh checkout of the same sources (same digest directory,
    new mtimes) recompiles everything: the ready mark must know it."""
    out = []
    for path, _ in kernel_sources(package):
        st = path.stat()
        out.append([str(path.relative_to(package)), st.st_mtime, st.st_size])
    return out


def ready_key() -> dict:
    """What ``hpfebe compile``'s ready mark records: the host, this checkout and its
    sources' stamps (two checkouts of one tree share the digest directory)."""
    return {**host_key(), "package": str(PACKAGE), "stamps": source_stamps()}


def host_key() -> dict:
    """What numba's cached machine code depends on besides the sources (the digest
    directory's name): the interpreter, numba and the CPU it was compiled for."""
    import platform

    import llvmlite.binding as llvm
    import numba

    return {"python": platform.python_version(), "numba": numba.__version__,
            "cpu": llvm.get_host_cpu_name(), "features": llvm.get_host_cpu_features()
            .flatten()}
