"""The client side of the local job server (:mod:`hpfebe.jobserver`): standard
library only (and :mod:`hpfebe.suite.watch`, which is too), so that ``python -m hpfebe`` decides in a few milliseconds whether a
server of the same tree and environment will run the command.

``python -m hpfebe ARGS`` with ``HPFEBE_JOBSERVER`` set (the workflow sets it for its
local jobs, Snakefile ``onstart``) hands ``ARGS``, its working directory, its environment
and its standard streams (the file descriptors, ``SCM_RIGHTS``) to the server, which
forks a process that already imported numpy, scipy, matplotlib, the JIT and hpfebe, and
runs ``hpfebe.cli.main(ARGS)`` there: the same command, the same exit code, the same
log, without the 1.5-2 s of interpreter start and imports per job.  A signal to the
client (Snakemake stopping a job) goes to that process; a killed client makes the server
stop it.  Whenever the server cannot take the command (none running, another
environment, another tree) :func:`delegate` returns None and the caller runs the command
itself, as without a server.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import struct
import sys
import time

from .suite.watch import pid_exists     # (standard library only, as this module)

#: the socket of the server, and its pid (while it starts, the socket is not there yet)
ENV_SOCKET = "HPFEBE_JOBSERVER"
ENV_PID = "HPFEBE_JOBSERVER_PID"
#: how long a client waits for a server that is still starting (imports: about 2 s)
START_WAIT_S = 60.0
FORWARDED = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)


def _connect(path: str, pid: int | None) -> socket.socket | None:
    """A connection to the server, waiting while it starts; None if there is none."""
    deadline = time.monotonic() + START_WAIT_S
    while True:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            s.connect(path)
            return s
        except OSError:
            s.close()
        if pid is None or not pid_exists(pid) or time.monotonic() > deadline:
            return None
        time.sleep(0.02)


def send_message(sock: socket.socket, obj, fds=()) -> None:
    """One length-prefixed JSON message (with ``fds`` attached to its first bytes)."""
    data = json.dumps(obj).encode()
    data = struct.pack("!I", len(data)) + data
    sent = socket.send_fds(sock, [data], list(fds)) if fds else sock.send(data)
    if sent < len(data):
        sock.sendall(data[sent:])


def read_line(sock: socket.socket, buf: bytearray):
    """The next newline-terminated JSON reply of the server, or None at end of stream."""
    while b"\n" not in buf:
        try:
            chunk = sock.recv(4096)
        except InterruptedError:      # (a forwarded signal; PEP 475 retries, but be safe)
            continue
        if not chunk:
            return None
        buf += chunk
    line, _, rest = bytes(buf).partition(b"\n")
    buf[:] = rest
    return json.loads(line)


def delegate(argv: list[str]) -> int | None:
    """Run ``hpfebe ARGV`` in the job server and return its exit code, or None when no
    server takes it (then run it here).  Standard streams and signals as module doc."""
    path = os.environ.get(ENV_SOCKET)
    if not path:
        return None
    pid = os.environ.get(ENV_PID, "")
    sock = _connect(path, int(pid) if pid.isdigit() else None)
    if sock is None:
        return None
    with sock:
        try:
            send_message(sock, {"argv": list(argv), "argv0": sys.argv[0], "cwd": os.getcwd(),
                                "env": dict(os.environ), "executable": sys.executable},
                         fds=(0, 1, 2))
        except OSError:
            return None
        buf = bytearray()
        reply = read_line(sock, buf)
        if reply is None or "refused" in reply:
            return None            # (the server logs why: another environment, ...)
        child = int(reply["pid"])

        def forward(signum, frame):  # noqa: ARG001 - signal handler signature
            try:
                os.kill(child, signum)
            except ProcessLookupError:
                pass

        for s in FORWARDED:
            signal.signal(s, forward)
        reply = read_line(sock, buf)
    if reply is None:
        print("hpfebe: error: the job server ended before the job did", file=sys.stderr)
        return 1
    code = int(reply["exit"])
    if code < 0:                   # the job died of a signal: so does its client
        signal.signal(-code, signal.SIG_DFL)
        os.kill(os.getpid(), -code)
    return code
