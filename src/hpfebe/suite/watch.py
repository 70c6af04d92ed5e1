"""The job watch: a run started by Snakemake stops when that Snakemake is gone.

Snakemake killed outright (``kill -9``: no handler runs) must not leave its jobs running
on as orphans that write into ``results/``.  The Snakefile names the main Snakemake in
the environment of every job (:data:`PARENT_PID_ENV`, :data:`PARENT_HOST_ENV` and, for
cluster runs, :data:`HEARTBEAT_ENV`); :func:`watch_parent_from_env` starts the watch that
fits (the pid on the Snakemake's own host, its heartbeat file on another host), and

* a daemon thread polls the parent every second and, once it is gone, ends the run
  with SIGTERM (:func:`install_signal_handlers`: temporaries removed, exit 143);
* :func:`before_rename`, the hook that every atomic write calls just before its rename
  (:func:`hpfebe.suite.results.atomic_write`, the VTU export), checks the parent once
  more at that moment and aborts the write (:class:`Terminated`, no rename) when it is
  gone: no result file lands after the parent's death, however short the poll is.  What
  is left is the few microseconds between that check and the rename; on another host,
  the heartbeat's timeout (:data:`HEARTBEAT_TIMEOUT_S`).

A run whose parent is already gone when it starts does not run (:class:`ParentGone`).
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import threading
import time
from pathlib import Path
from typing import Callable

log = logging.getLogger("hpfebe")


class ParentGone(Exception):
    """The Snakemake named by the environment has ended before this run started: the
    run does not start (the command line prints it and exits with status 2)."""


#: environment variables naming the Snakemake whose death stops a run (set by the
#: Snakefile in the main Snakemake; a cluster job inherits them through the nested
#: Snakemakes that run it): its process id, its host, and (cluster runs) the heartbeat
#: file it rewrites every second, watched by a job on another host
PARENT_PID_ENV = "HPFEBE_PARENT_PID"
PARENT_HOST_ENV = "HPFEBE_PARENT_HOST"
HEARTBEAT_ENV = "HPFEBE_HEARTBEAT"
#: seconds without a change of the heartbeat file after which its Snakemake is taken for
#: dead (it is rewritten every second; a shared file system may show a change late)
HEARTBEAT_TIMEOUT_S = 10.0


class Terminated(BaseException):
    """Raised in the main thread by the SIGTERM/SIGHUP handler (a BaseException, like
    KeyboardInterrupt, so that no ``except Exception`` swallows it); exit 128 + signum."""

    def __init__(self, signum: int, why: str = ""):
        super().__init__(signum)
        self.signum, self.why = signum, why


#: the signals the handler received: the exception it raises can be swallowed (raised
#: inside a finalizer, ``__del__``, Python prints "Exception ignored" and goes on), so
#: :func:`check_terminated` raises it again before anything is written
RECEIVED: list[int] = []


def _on_signal(signum, frame):  # noqa: ARG001 - signal handler signature
    from .results import remove_temporaries

    RECEIVED.append(signum)
    remove_temporaries()
    raise Terminated(signum)


def check_terminated() -> None:
    """Raise :class:`Terminated` if a SIGTERM/SIGHUP arrived, even one whose exception
    was swallowed where it was raised (:data:`RECEIVED`)."""
    if RECEIVED:
        raise Terminated(RECEIVED[0])


def install_signal_handlers() -> None:
    """SIGTERM and SIGHUP end a run like Ctrl-C does: the temporary files of atomic
    writes in progress are removed, no result file is left half written, and the exit
    status is 128 + signal number.  (SIGINT raises KeyboardInterrupt, which
    :func:`hpfebe.suite.results.atomic_write` cleans up the same way; exit 130.)"""
    for sig in (signal.SIGTERM, getattr(signal, "SIGHUP", None)):
        if sig is not None:
            signal.signal(sig, _on_signal)


def _start_time(pid: int) -> str | None:
    """Start time of process ``pid`` (Linux /proc), to tell it from a reused pid."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return None if fields[0] in ("Z", "X") else fields[19]
    except (OSError, IndexError):
        return None


def _alive(pid: int, start: str | None) -> bool:
    """Process ``pid`` runs and (Linux) is the one that had start time ``start``: a
    zombie (killed, not yet reaped by its parent) counts as ended."""
    if os.path.isdir("/proc"):
        return start is not None and _start_time(pid) == start
    return pid_exists(pid)


def pid_exists(pid: int) -> bool:
    """A process ``pid`` exists (signal 0; one of another user counts too)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _stop_when(gone, why: str, interval: float, grace: float):
    """A daemon thread that polls ``gone()`` every ``interval`` seconds and, when it is
    true, sends this process SIGTERM (see :func:`install_signal_handlers`); if the main
    thread has not ended ``grace`` seconds later (stuck in compiled code), the
    temporaries are removed and the process exits hard with status 143.  ``gone`` is
    also checked by :func:`before_rename`, just before each rename of a result file."""
    _WATCHES.append((gone, why))

    def loop():
        while not gone():
            time.sleep(interval)
        log.warning("%s: stopping this run", why)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(grace)
        from .results import remove_temporaries

        remove_temporaries()
        os._exit(128 + signal.SIGTERM)

    t = threading.Thread(target=loop, name="hpfebe-watch-parent", daemon=True)
    t.start()
    return t


def watch_parent(pid: int, interval: float = 1.0, grace: float = 30.0):
    """Stop this run when process ``pid`` ends (Snakemake killed, even by SIGKILL, must
    not leave its jobs running on as orphans writing into results/); see
    :func:`_stop_when`.  Returns the thread; ParentGone if ``pid`` is not running now (its
    Snakemake ended before this job started)."""
    start = _start_time(pid)
    if not _alive(pid, start):
        raise ParentGone(f"{PARENT_PID_ENV}={pid} names a process that has ended: the "
                       "Snakemake that started this job is gone, so the job does not run "
                       f"(to run the command by hand, leave out {PARENT_PID_ENV})")
    return _stop_when(lambda: not _alive(pid, start), f"parent process {pid} is gone",
                      interval, grace)


def _heartbeat_state(path: Path):
    """What changes at each heartbeat: the file's content and mtime (the content is read,
    not only stat'ed: opening a file revalidates NFS's cached attributes)."""
    try:
        with open(path, "rb") as f:
            return f.read(64), os.fstat(f.fileno()).st_mtime_ns
    except OSError:
        return None


def watch_heartbeat(path: Path, timeout: float = HEARTBEAT_TIMEOUT_S,
                    interval: float = 1.0, grace: float = 30.0):
    """Stop this run when the heartbeat file ``path`` has not changed for ``timeout``
    seconds (by this host's clock): the Snakemake on another host that rewrites it every
    second is gone.  ParentGone if the file is missing or was last written more than
    ``timeout`` seconds ago (by the file server's clock) when the job starts."""
    path = Path(path)
    try:
        age = time.time() - path.stat().st_mtime
    except OSError:
        age = None
    if age is None or age > timeout:
        raise ParentGone(f"{HEARTBEAT_ENV}={path} is " + ("missing" if age is None else
                       f"{age:.0f} s old") + ": the Snakemake that started this job is "
                       f"gone, so the job does not run (to run the command by hand, leave "
                       f"out {PARENT_PID_ENV})")
    last = [_heartbeat_state(path), time.monotonic()]

    def gone():
        state = _heartbeat_state(path)
        if state is not None and state != last[0]:
            last[:] = [state, time.monotonic()]
        return time.monotonic() - last[1] > timeout

    return _stop_when(gone, f"the heartbeat {path} stopped {timeout:.0f} s ago",
                      interval, grace)


def watch_parent_from_env() -> None:
    """The job watch: the parent Snakemake's pid where it runs on this host (the local
    executor; a cluster job on the submit host), else its heartbeat file (a cluster job
    on another node; the file is on the file system shared with it)."""
    value = os.environ.get(PARENT_PID_ENV)
    if not value:
        return
    try:
        pid = int(value)
    except ValueError:
        log.warning("%s=%r is not a process id; ignored", PARENT_PID_ENV, value)
        return
    host = os.environ.get(PARENT_HOST_ENV)
    if host and host != socket.gethostname():
        heartbeat = os.environ.get(HEARTBEAT_ENV)
        if heartbeat:
            watch_heartbeat(Path(heartbeat))
            log.info("this run stops when %s (the heartbeat of the Snakemake that started "
                     "it, on %s) stops", heartbeat, host)
        else:
            log.warning("the Snakemake that started this job runs on %s and writes no "
                        "heartbeat (%s): this job is not watched", host, HEARTBEAT_ENV)
        return
    if pid > 1 and pid != os.getpid():
        watch_parent(pid)
        log.info("this run stops when process %d (the Snakemake that started it) ends", pid)


def parent_gone_from_env() -> bool:
    """True if the Snakemake named by the environment has ended: its pid on this host,
    else its heartbeat file older than :data:`HEARTBEAT_TIMEOUT_S` (by the file server's
    clock).  False without the variables (a run by hand).  The Snakefile asks it in a
    cluster job's Snakemake before that removes a job's old outputs."""
    value = os.environ.get(PARENT_PID_ENV)
    try:
        pid = int(value) if value else None
    except ValueError:
        pid = None
    if pid is None:
        return False
    host = os.environ.get(PARENT_HOST_ENV)
    if host and host != socket.gethostname():
        heartbeat = os.environ.get(HEARTBEAT_ENV)
        try:
            return bool(heartbeat) and time.time() - os.stat(heartbeat).st_mtime > \
                HEARTBEAT_TIMEOUT_S
        except OSError:
            return True
    return not _alive(pid, _start_time(pid))


#: the watches started in this process, as (gone, why): checked again by before_rename
_WATCHES: list[tuple[Callable[[], bool], str]] = []


def before_rename(path) -> None:
    """The hook called just before each rename that makes a result file appear
    (:func:`hpfebe.suite.results.atomic_write`, the VTU export): if a watched parent is
    gone, raise :class:`Terminated` (SIGTERM) so that the write is aborted and its
    temporary file removed, instead of the file landing after the parent's death (the
    watch thread polls only every second).  Without a watch (a run by hand, the tests)
    it does nothing."""
    for gone, why in _WATCHES:
        if gone():
            log.warning("%s: %s not written, stopping this run", why, path)
            raise Terminated(signal.SIGTERM, f"{why}: {path} was not written")


def terminated_cause(exc: BaseException):
    """The Terminated behind ``exc``: the signal handler's exception, raised while a
    numba kernel called back into Python (unpickling a constant), reaches Python as a
    SystemError whose context is the Terminated."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, Terminated):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None
