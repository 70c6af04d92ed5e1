"""The local job server (hpfebe.jobserver) and its client (``python -m hpfebe``
with HPFEBE_JOBSERVER set): the same output and exit code as without it, a refused
environment runs the command itself, signals reach the job, a killed client stops it,
and the server ends when its standard input (the Snakemake that started it) closes."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hpfebe.jobserver import import_time_env

ROOT = Path(__file__).resolve().parents[2]
THREADS = {v: "1" for v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                            "MKL_NUM_THREADS")}


def _env(**extra):
    env = {k: v for k, v in os.environ.items() if not k.startswith("HPFEBE_JOBSERVER")}
    env.update(THREADS, MPLBACKEND="Agg")
    env.update(extra)
    return env


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("jobserver")
    sock, log = tmp / "jobs.sock", tmp / "server.log"
    with open(log, "w") as fh:
        proc = subprocess.Popen([sys.executable, "-m", "hpfebe.jobserver", "--socket",
                                 str(sock)], stdin=subprocess.PIPE, stdout=fh, stderr=fh,
                                env=_env(), cwd=ROOT)
    deadline = time.monotonic() + 300
    while not sock.exists():
        assert proc.poll() is None, log.read_text()
        assert time.monotonic() < deadline, "the job server did not start in 300 s"
        time.sleep(0.1)
    yield {"sock": sock, "log": log, "proc": proc,
           "env": _env(HPFEBE_JOBSERVER=str(sock), HPFEBE_JOBSERVER_PID=str(proc.pid))}
    proc.terminate()
    proc.wait(timeout=30)


def _hpfebe(*args, env, **kw):
    return subprocess.run([sys.executable, "-m", "hpfebe", *args], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=300, **kw)


def _jobs_in_log(server) -> int:
    return server["log"].read_text().count(": exit ")


def test_a_command_runs_in_the_server_with_the_same_output(server):
    direct = _hpfebe("list", env=_env())
    before = _jobs_in_log(server)
    served = _hpfebe("list", env=server["env"])
    assert served.returncode == direct.returncode == 0, served.stderr
    assert served.stdout == direct.stdout and "table_2_1" in served.stdout
    assert _jobs_in_log(server) == before + 1


def test_the_exit_code_and_the_error_pass_through(server):
    direct = _hpfebe("run", "no_such_artefact", env=_env())
    served = _hpfebe("run", "no_such_artefact", env=server["env"])
    assert direct.returncode == served.returncode == 2
    assert "unknown artefact 'no_such_artefact'" in served.stderr
    usage = _hpfebe("run", env=server["env"])            # argparse: SystemExit(2)
    assert usage.returncode == 2 and "usage:" in usage.stderr


def test_another_environment_is_refused_and_runs_itself(server):
    before = server["log"].read_text().count("refused")
    env = {**server["env"], "OMP_NUM_THREADS": "2"}
    r = _hpfebe("list", env=env)
    assert r.returncode == 0 and "table_2_1" in r.stdout
    assert server["log"].read_text().count("refused") == before + 1
    assert "OMP_NUM_THREADS" in server["log"].read_text()


def test_without_a_server_the_command_runs_itself(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    env = _env(HPFEBE_JOBSERVER=str(tmp_path / "none.sock"), HPFEBE_JOBSERVER_PID=dead)
    t0 = time.monotonic()
    r = _hpfebe("list", env=env)
    assert r.returncode == 0 and "table_2_1" in r.stdout
    assert time.monotonic() - t0 < 60       # (no wait for a server that is not starting)


def _long_job(server, out):
    """A client running a long job (Example 1, full configuration) in the server."""
    before = server["log"].read_text().count("job ")
    proc = subprocess.Popen([sys.executable, "-m", "hpfebe", "run", "ch4_plasticity__ex1",
                             "--out", str(out)], env=server["env"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while server["log"].read_text().count("job ") == before:
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.05)
    line = server["log"].read_text().splitlines()[-1]
    return proc, int(line.split("job ")[1].split(":")[0])


def _gone(pid, timeout=60.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def test_a_signal_to_the_client_reaches_the_job(server, tmp_path):
    proc, job = _long_job(server, tmp_path / "out")
    time.sleep(1.0)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "terminated by signal 15" in err
    assert _gone(job)
    assert not any((tmp_path / "out").glob("*.json"))


def test_a_killed_client_stops_its_job(server, tmp_path):
    proc, job = _long_job(server, tmp_path / "out")
    proc.kill()
    proc.wait(timeout=30)
    assert _gone(job), "the job of a killed client kept running"
    assert f"job {job}: its client is gone" in server["log"].read_text()


def test_the_server_ends_when_its_input_closes(tmp_path):
    sock = tmp_path / "s.sock"
    proc = subprocess.Popen([sys.executable, "-m", "hpfebe.jobserver", "--socket",
                             str(sock)], stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, env=_env(), text=True)
    deadline = time.monotonic() + 300
    while not sock.exists():
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.1)
    proc.stdin.close()
    assert proc.wait(timeout=30) == 0
    assert "stopped" in proc.stderr.read()
    assert not sock.exists()


def test_import_time_variables():
    env = {"PYTHONPATH": "a", "NUMBA_CACHE_DIR": "b", "OMP_NUM_THREADS": "1", "HOME": "/x",
           "HPFEBE_PARENT_PID": "1", "MALLOC_TRIM_THRESHOLD_": "1"}
    # glibc reads MALLOC_* at the process start: a job forked from the server has the
    # server's allocator settings
    assert set(import_time_env(env)) == {"PYTHONPATH", "NUMBA_CACHE_DIR", "OMP_NUM_THREADS",
                                         "MALLOC_TRIM_THRESHOLD_"}
