"""A local job server for the workflow: one process that imports the scientific stack
and hpfebe once, and forks a process per job (:mod:`hpfebe.jobclient` is the other
side).

Every job of ``snakemake -j2`` is a fresh ``python -m hpfebe run JOB``: about 2 s of
interpreter start and imports (numpy, scipy, pandas, matplotlib, scikit-fem, the JIT,
hpfebe), against 0.3-4 s of computing per job in the quick configuration, so that half
of a quick run was start-up.  The Snakefile (``onstart``, local runs only; a cluster's
jobs run elsewhere) starts ``python -m hpfebe.jobserver --socket PATH`` and puts
``HPFEBE_JOBSERVER=PATH`` into the environment the jobs inherit (not into their
commands: the commands, and so what Snakemake reruns, are the same with or without it).

A request is refused, and the client runs the command itself, when its environment
differs from the server's in anything read at import time (``PYTHON*``, ``NUMBA_*``,
``OMP_*``, ``OPENBLAS_*``, ``MKL_*``: thread counts, the kernel cache of this source tree,
the module path) or it comes from another interpreter.  A forked job takes the client's
working directory, environment, arguments and standard streams, runs
``hpfebe.cli.main``, runs the exit handlers and ends; its exit code (or the signal it
died of) goes back to the client.  The server forks from one thread (no lock of another
thread can be held in the child), calls no compiled kernel itself (no thread pool runs
in it; while idle it loads numba's cached kernels, :func:`cached_kernels`, so that the
jobs need not), and ends with its parent (Snakemake; also after a SIGKILL of it), on
SIGTERM, or when its standard input closes; it stops its jobs first.
"""

from __future__ import annotations

import argparse
import atexit
import gc
import importlib
import io
import json
import os
import pkgutil
import selectors
import signal
import socket
import struct
import sys
import time
import traceback

from .jobclient import read_line  # noqa: F401  (the protocol: one module defines both)

#: environment variables read at import time (MALLOC_: at the process start, by glibc's
#: allocator): a client must agree on all of them
IMPORT_TIME_PREFIXES = ("PYTHON", "NUMBA_", "OMP_", "OPENBLAS_", "MKL_", "MALLOC_")
MAX_REQUEST = 1 << 22


def import_time_env(env) -> dict:
    return {k: v for k, v in env.items() if k.startswith(IMPORT_TIME_PREFIXES)}


def preload() -> float:
    """Import what the jobs import (every module of hpfebe, with its dependencies), read
    the experiment registry and draw one figure (fonts, the Agg backend); returns the
    seconds it took."""
    t0 = time.perf_counter()
    import matplotlib

    matplotlib.use("Agg", force=True)
    import hpfebe

    for mod in pkgutil.walk_packages(hpfebe.__path__, "hpfebe."):
        if mod.name not in (__name__, "hpfebe.jobserver"):
            try:
                importlib.import_module(mod.name)
            except ImportError as exc:    # an optional dependency: the job imports it
                print(f"jobserver: not preloaded: {mod.name} ({exc})", file=sys.stderr)
    from .cli import CLIError, find_root
    from .suite.registry import discover

    try:                   # the registry's parsed files, kept (suite.registry._per_file)
        discover(find_root() / "experiments")
    except (CLIError, ValueError, SyntaxError, OSError) as exc:    # the job reports it
        print(f"jobserver: registry not preloaded ({exc})", file=sys.stderr)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 2))
    ax = fig.add_subplot()
    ax.loglog([1, 2], [1, 2], "o-", label="$h^{1/2}$")
    ax.set_xlabel("N")
    ax.legend()
    fig.savefig(io.BytesIO(), format="png")
    gc.collect()
    gc.freeze()            # the preloaded objects stay shared with the forked jobs
    return time.perf_counter() - t0


def cached_kernels():
    """(dispatcher, signature) of every overload in numba's on-disk cache of hpfebe's
    kernels that this process has not loaded: what the server loads while it is idle
    (:meth:`JobServer.serve`), so that a forked job finds it in memory (measured: 95
    kernels in 1.0 s; 0.2-0.4 s a job).  Not the parallel ones: loading one launches
    numba's thread pool, which a fork must not inherit.  It reads numba's private cache
    index: anything unexpected stops the loading (the jobs then load their kernels
    themselves, as without it)."""
    from numba.core.registry import CPUDispatcher

    seen = set()
    for name, mod in sorted(sys.modules.items()):
        if not name.startswith("hpfebe.") or mod is None:
            continue
        for disp in list(vars(mod).values()):
            if (not isinstance(disp, CPUDispatcher) or id(disp) in seen
                    or disp.targetoptions.get("parallel")):   # loading starts its threads
                continue
            seen.add(id(disp))
            try:
                cache = disp._cache
                index = cache._cache_file._load_index()     # {} when stale or absent
                codegen = disp.targetctx.codegen()
                sigs = [key[0] for key in index
                        if key[1:] == cache._index_key(key[0], codegen)[1:]]
            except AttributeError:          # NullCache (cache=False), or another numba
                continue
            yield from ((disp, sig) for sig in sigs if sig not in disp.overloads)


def _recv_request(conn: socket.socket):
    """(request dict, [stdin, stdout, stderr] fds) of a client (jobclient.send_message)."""
    conn.settimeout(10.0)
    data, fds, _, _ = socket.recv_fds(conn, 65536, 3)
    if len(data) < 4:
        raise ValueError("short request")
    (n,) = struct.unpack("!I", data[:4])
    if n > MAX_REQUEST:
        raise ValueError(f"request of {n} bytes")
    data = bytearray(data[4:])
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ValueError("request cut short")
        data += chunk
    conn.settimeout(None)
    return json.loads(bytes(data)), list(fds)


def _run_child(request: dict, fds: list[int]) -> None:
    """In the forked process: become the client's command and end (never returns)."""
    code = 1
    try:
        for s in (signal.SIGTERM, signal.SIGHUP, signal.SIGCHLD):
            signal.signal(s, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
            os.close(fd)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        sys.argv = [request.get("argv0", sys.argv[0]), *request["argv"]]
        from hpfebe.cli import main

        try:
            code = main(request["argv"])
        except SystemExit as exc:          # argparse: --help, usage errors
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if isinstance(exc.code, str):
                print(exc.code, file=sys.stderr)
        atexit._run_exitfuncs()
    except BaseException:                  # noqa: BLE001 - report it as Python would
        traceback.print_exc()
        code = 1
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:               # noqa: BLE001 - a closed pipe
                pass
        os._exit(code if isinstance(code, int) else 1)


class JobServer:
    """The server loop (module doc): accept, check, fork; report exits; stop jobs whose
    client went away."""

    def __init__(self, path: str):
        self.path = path
        self.env = import_time_env(os.environ)
        self.parent = os.getppid()
        self.jobs: dict[int, tuple[socket.socket, int]] = {}   # pid -> (conn, pidfd)
        self.sel = selectors.DefaultSelector()
        self.stopping = False
        self.loaded = 0

    def log(self, msg: str) -> None:
        print(f"{time.strftime('%H:%M:%S')} jobserver: {msg}", file=sys.stderr, flush=True)

    def refuse_reason(self, request: dict) -> str:
        if request.get("executable") != sys.executable:
            return f"another interpreter ({request.get('executable')})"
        theirs = import_time_env(request.get("env", {}))
        diff = sorted(k for k in set(theirs) | set(self.env)
                      if theirs.get(k) != self.env.get(k))
        return f"another environment ({', '.join(diff)})" if diff else ""

    def accept(self, listener: socket.socket) -> None:
        conn, _ = listener.accept()
        fds = []
        try:
            request, fds = _recv_request(conn)
            why = self.refuse_reason(request)
            if why or len(fds) != 3:
                self.log(f"refused {request.get('argv')}: {why or 'no standard streams'}")
                conn.sendall(json.dumps({"refused": why}).encode() + b"\n")
                raise ValueError(why)
            sys.stdout.flush()
            sys.stderr.flush()
            pid = os.fork()
            if pid == 0:
                self.sel.close()
                listener.close()
                conn.close()
                for other, pidfd in self.jobs.values():
                    other.close()
                    os.close(pidfd)
                _run_child(request, fds)
            for fd in fds:
                os.close(fd)
            fds = []
            pidfd = os.pidfd_open(pid)
            self.jobs[pid] = (conn, pidfd)
            self.sel.register(pidfd, selectors.EVENT_READ, ("exit", pid))
            self.sel.register(conn, selectors.EVENT_READ, ("client", pid))
            conn.sendall(json.dumps({"pid": pid}).encode() + b"\n")
            self.log(f"job {pid}: {' '.join(request['argv'])}")
        except (OSError, ValueError) as exc:
            for fd in fds:
                os.close(fd)
            if not isinstance(exc, ValueError):
                self.log(f"request failed: {exc}")
            conn.close()

    def reap(self, pid: int) -> None:
        conn, pidfd = self.jobs.pop(pid)
        _, status = os.waitpid(pid, 0)
        code = os.waitstatus_to_exitcode(status)
        for key in (pidfd, conn):
            try:
                self.sel.unregister(key)
            except (KeyError, ValueError):    # (the client's end: unregistered when it went)
                pass
        os.close(pidfd)
        self.log(f"job {pid}: exit {code}")
        try:
            conn.sendall(json.dumps({"exit": code}).encode() + b"\n")
        except OSError:
            pass
        conn.close()

    def client_event(self, pid: int) -> None:
        conn, _ = self.jobs[pid]
        try:
            gone = not conn.recv(1, socket.MSG_PEEK)
        except OSError:
            gone = True
        if gone:                 # the client was killed: so is its job (module doc)
            self.sel.unregister(conn)
            self.log(f"job {pid}: its client is gone, stopping it")
            os.kill(pid, signal.SIGTERM)

    def load_next(self, kernels):
        """Load the next cached kernel of ``kernels``; the generator, or None when done."""
        try:
            disp, sig = next(kernels)
            disp.compile(sig)               # a cache hit (cached_kernels): no compiling
        except StopIteration:
            self.log(f"{self.loaded} cached kernels loaded")
            return None
        except Exception as exc:            # noqa: BLE001 - the jobs load their own
            self.log(f"loading cached kernels stopped after {self.loaded}: {exc!r}")
            return None
        self.loaded += 1
        return kernels

    def serve(self) -> None:
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        tmp = f"{self.path}.{os.getpid()}.tmp"
        listener.bind(tmp)
        listener.listen(64)
        os.replace(tmp, self.path)         # the socket appears ready, never half set up
        self.sel.register(listener, selectors.EVENT_READ, ("listen", None))
        if not sys.stdin.closed and not sys.stdin.isatty():
            self.sel.register(sys.stdin.fileno(), selectors.EVENT_READ, ("stdin", None))
        kernels = cached_kernels()
        try:
            while not self.stopping:
                events = self.sel.select(timeout=0.0 if kernels else 1.0)
                if not events and kernels:      # idle: load one cached kernel
                    kernels = self.load_next(kernels)
                for key, _ in events:
                    kind, pid = key.data
                    if kind == "listen":
                        self.accept(listener)
                    elif kind == "exit":
                        self.reap(pid)
                    elif kind == "client":
                        self.client_event(pid)
                    elif kind == "stdin" and not os.read(key.fd, 4096):
                        self.stopping = True
                if os.getppid() != self.parent:
                    self.log("the Snakemake that started this server is gone")
                    self.stopping = True
        finally:
            listener.close()
            try:
                os.unlink(self.path)
            except FileNotFoundError:
                pass
            for pid in list(self.jobs):
                try:
                    os.kill(pid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
            deadline = time.monotonic() + 10.0
            while self.jobs and time.monotonic() < deadline:
                for pid in list(self.jobs):
                    if os.waitpid(pid, os.WNOHANG)[0]:
                        self.jobs.pop(pid)
                time.sleep(0.05)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m hpfebe.jobserver",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--socket", required=True, help="path of the Unix socket to serve on")
    args = p.parse_args(argv)
    server = JobServer(args.socket)

    def stop(signum, frame):  # noqa: ARG001 - signal handler signature
        server.stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C reaches the jobs; Snakemake
    server.log(f"preloaded in {preload():.1f} s")  # then stops this server (SIGTERM)
    server.serve()
    server.log("stopped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
