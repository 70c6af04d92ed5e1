"""Issue 10 (reliability): wrong answers without an error, messages that name the real
cause, near-linear mesh validation, interrupted runs and damaged results."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM

ROOT = Path(__file__).resolve().parents[2]
SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


# --------------------------------------------------------------------------- orientation
def _side_x1(m):
    return np.isclose(m.a[:, 0], 1) & np.isclose(m.b[:, 0], 1)


def test_clockwise_polygon_keeps_side_labels_counts_and_degrees():
    m = BoundaryMesh.polygon([(0, 0), (0, 1), (1, 1), (1, 0)], n=[1, 2, 3, 4],
                             labels=["C", "N", "D", "N"], p=[1, 2, 3, 4])
    on = _side_x1(m)                       # side 2 joins (1, 1) and (1, 0)
    assert on.sum() == 3
    assert set(m.labels[on]) == {"D"} and set(m.degrees[on]) == {3}
    left = np.isclose(m.a[:, 0], 0) & np.isclose(m.b[:, 0], 0)
    assert left.sum() == 1 and m.labels[left][0] == "C" and m.degrees[left][0] == 1
    mid = 0.5 * (m.a + m.b)
    assert np.all(np.sum((mid - 0.5) * m.normals, axis=1) > 0)      # outward
    assert np.all(m.elements[1:, 0] == m.elements[:-1, 1])           # one ordered chain


def _neumann_error(mesh):
    """Relative L2 error of the Neumann data of u = x + 2y from its Dirichlet data."""
    from hpfebe.analysis import boundary_l2_error
    from hpfebe.bem import LaplaceBEM

    op = LaplaceBEM(mesh)
    g = op.V_space.interpolate(lambda x: x[:, 0] + 2 * x[:, 1])
    psi = op.Psi(g)
    flux = lambda x, n: n[:, 0] + 2 * n[:, 1]  # noqa: E731
    return boundary_l2_error(op.W_space, psi, flux) / boundary_l2_error(
        op.W_space, 0 * psi, flux)


def test_from_segments_orients_a_clockwise_outer_curve():
    sq = BoundaryMesh.polygon(SQUARE, n=3, p=2)
    cw = BoundaryMesh.from_segments(sq.nodes, sq.elements[:, ::-1], p=2)
    mid = 0.5 * (cw.a + cw.b)
    assert np.all(np.sum((mid - 0.5) * cw.normals, axis=1) > 0)
    assert _neumann_error(cw) < 1e-6


def test_join_orients_a_counter_clockwise_hole():
    outer = BoundaryMesh.polygon([(-2, -2), (2, -2), (2, 2), (-2, 2)], n=3, p=2)
    hole = BoundaryMesh.polygon(SQUARE, n=2, labels=list("ABCD"), p=2)   # CCW as built
    m = BoundaryMesh.join(outer, hole)
    inner = np.arange(m.n_elements) >= outer.n_elements
    mid = 0.5 * (m.a + m.b)
    # the hole's normals point into the hole (out of the annulus), labels kept per side
    assert np.all(np.sum((mid[inner] - 0.5) * m.normals[inner], axis=1) < 0)
    bottom = inner & np.isclose(mid[:, 1], 0)
    assert set(m.labels[bottom]) == {"A"}
    assert _neumann_error(m) < 1e-6


def test_plain_constructor_refuses_a_wrong_curve_naming_it():
    outer = BoundaryMesh.polygon([(-2, -2), (2, -2), (2, 2), (-2, 2)], n=1)
    hole = BoundaryMesh.polygon(SQUARE, n=1)
    nodes = np.vstack([outer.nodes, hole.nodes])
    elements = np.vstack([outer.elements, hole.elements + 4])
    with pytest.raises(ValueError, match=r"curve 1 \(elements 4..7.*hole.*clockwise"):
        BoundaryMesh(nodes, elements, ["N"] * 8, [1] * 8)
    with pytest.raises(ValueError, match=r"curve 0 .*outer boundary.*counter-clockwise"):
        BoundaryMesh(outer.nodes, outer.elements[:, ::-1], ["N"] * 4, [1] * 4)


# --------------------------------------------------------------------------- bad degrees
@pytest.mark.parametrize("call, match", [
    (lambda: BoundaryMesh.polygon(SQUARE, n=2, p=True), "boolean"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=2, p=[1, 2, True, 1]), "boolean"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=True), "n"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=2).with_degrees(2.7), "2.7"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=2).with_degrees(True), "boolean"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=2).with_degrees(np.nan), "integer"),
    (lambda: BoundaryMesh.polygon(SQUARE, n=1).with_degrees([1, 2]), "one degree per"),
    (lambda: BoundaryMesh(np.array(SQUARE, float), [[0, 1], [1, 2], [2, 3], [3, 0]],
                          ["N"] * 4, [1, 2.5, 1, 1]), "2.5"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (2, 0)], n=1), "zero area|collinear"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 1), (3, 3)], n=1), "zero area|collinear"),
])
def test_degrees_and_degenerate_polygons_refused(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_integral_float_degrees_still_accepted():
    m = BoundaryMesh.polygon(SQUARE, n=2, p=2.0)
    assert m.degrees.dtype == np.int64 and np.all(m.with_degrees(np.float64(3)).degrees == 3)


# --------------------------------------------------------------------------- validation cost
def test_mesh_validation_is_near_linear():
    """32k elements took 8-14 s with the O(N^2) crossing test; the grid makes it < 0.1 s."""
    BoundaryMesh.polygon(SQUARE, n=4)                            # numba warm-up
    n = 32000
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    nodes = np.column_stack([np.cos(th), np.sin(th)])
    seg = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    t0 = time.perf_counter()
    BoundaryMesh.from_segments(nodes, seg)
    BoundaryMesh.polygon(SQUARE, n=n // 4)
    assert time.perf_counter() - t0 < 2.0
    # a crossing is still found, far from the first element
    nodes2 = nodes.copy()
    nodes2[n // 2] = (1.5, 0.0)       # the element ending there crosses the arc at (1, 0)
    with pytest.raises(ValueError, match="self-intersecting"):
        BoundaryMesh.from_segments(nodes2, seg)


# --------------------------------------------------------------------------- Nitsche
@pytest.mark.parametrize("kw, match", [
    (dict(p_fe=0), r"p_fe must be an integer >= 1, got 0"),
    (dict(p_fe=True), r"p_fe must be"),
    (dict(p_fe=1.5), r"p_fe must be"),
    (dict(p_fe=2, p_be=0), r"p_be must be an integer >= 1, got 0"),
    (dict(p_fe=2, fe_h_inv=0), r"fe_h_inv must be a positive number"),
    (dict(p_fe=2, be_h_inv=float("nan")), r"be_h_inv must be a positive number"),
])
def test_nitsche_names_the_bad_argument(kw, match):
    from hpfebe.scenes.interface import problem
    from hpfebe.coupling.nitsche import NitscheFEBE

    args = dict(fe_h_inv=2, be_h_inv=3)
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        NitscheFEBE(problem("smooth"), **args)


# --------------------------------------------------------------------------- config (CLI)
def hpfebe(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "hpfebe", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize("make, match", [
    (lambda m: LameBEM(m, 1.0, "0.3"), "nu .*must be a .*number"),
    (lambda m: LameBEM(m, "1", 0.3), "E .*must be a .*number"),
    (lambda m: LameBEM(m, True, 0.3), "E .*must be a .*number"),
    (lambda m: LaplaceBEM(m, scale="2"), "scale"),
    (lambda m: LaplaceBEM(m, zero_flux="no"), "zero_flux"),    # "no" is truthy
    (lambda m: LameBEM(m, 1.0, 0.3, zero_force="False"), "zero_force"),
    (lambda m: LaplaceBEM(m).Psi(np.ones(3)), "U must have 8 rows"),
    (lambda m: LaplaceBEM(m).Psi(np.full(8, np.nan)), "U contains NaN"),
])
def test_boundary_operators_name_the_bad_argument(make, match):
    with pytest.raises(ValueError, match=match):
        make(BoundaryMesh.polygon(SQUARE, n=2, p=1))


@pytest.mark.parametrize("text, match", [
    ("bem_laplace:\n  n_per_side: \"16\"\n",
     r"bem_laplace\.n_per_side must be a list, got '16' \(set in .*bad\.yaml"),
    ("bem_laplace:\n  n_per_side: [2, \"4\"]\n",
     r"bem_laplace\.n_per_side\[1\] must be an integer, got '4' \(set in .*bad\.yaml"),
    ("quick: \"false\"\n", r"'quick' must be true or false, got 'false' .*bad\.yaml"),
    ("bem_laplace:\n  n_per_sid: [2]\n", r"unknown key\(s\) \['n_per_sid'\].*bad\.yaml"),
    ("bem_laplac:\n  n_per_side: [2]\n", r"did you mean 'bem_laplace'.*bad\.yaml"),
    ("bem_laplace: [1, 2]\n", r"section 'bem_laplace' must be a mapping.*bad\.yaml"),
])
def test_config_errors_name_the_key_and_the_file(tmp_path, text, match):
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    r = hpfebe("run", "figure_bem_laplace", "--config", str(ROOT / "config" / "config.yaml"),
               "--config", str(bad), "--out", str(tmp_path / "out"))
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    import re
    assert re.search(match, r.stderr), r.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


# --------------------------------------------------------------------------- damaged results
@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """One real quick run (bem_laplace) into a fresh folder holding a stale zero-length
    temporary file of a killed earlier run."""
    out = tmp_path_factory.mktemp("results")
    stale = out / ".figure_bem_laplace.csv.k1ll3d.tmp"
    stale.write_bytes(b"")
    r = hpfebe("-q", "run", "figure_bem_laplace", "--quick", "--out", str(out))
    assert r.returncode == 0, r.stderr
    return out, stale


def test_stale_temporaries_removed_and_files_recorded(quick_run):
    from hpfebe.suite.results import check_result

    out, stale = quick_run
    assert not stale.exists()
    assert not list(out.glob(".*.tmp"))
    doc = json.loads((out / "figure_bem_laplace.json").read_text())
    assert doc["has_figure"] and doc["n_rows"] > 0
    assert len(doc["files"]["csv"]["sha256"]) == 64 and doc["files"]["png"]["bytes"] > 0
    doc2, table, png = check_result(out, "figure_bem_laplace")
    assert len(table) == doc["n_rows"] and png.name == "figure_bem_laplace.png"


def _damaged_copy(quick_run, tmp_path, damage):
    import shutil

    out = tmp_path / "results"
    shutil.copytree(quick_run[0], out)
    damage(out)
    return out


def _truncate_csv(out):
    p = out / "figure_bem_laplace.csv"
    data = p.read_bytes()
    p.write_bytes(data[:len(data) // 2])


DAMAGE = {
    "json_not_object": (lambda out: (out / "figure_bem_laplace.json").write_text("[1, 2]\n"),
                        "not an object"),
    "json_string": (lambda out: (out / "figure_bem_laplace.json").write_text('"x"\n'),
                    "not an object"),
    "csv_truncated": (_truncate_csv, "bytes"),
    "csv_missing": (lambda out: (out / "figure_bem_laplace.csv").unlink(), "missing"),
    "png_empty": (lambda out: (out / "figure_bem_laplace.png").write_bytes(b""), "empty"),
    "png_missing": (lambda out: (out / "figure_bem_laplace.png").unlink(), "missing"),
}


@pytest.mark.parametrize("kind", sorted(DAMAGE))
def test_report_shows_damaged_results_and_uses_nothing(quick_run, tmp_path, kind):
    from hpfebe.suite.report import build_report

    damage, why = DAMAGE[kind]
    res = _damaged_copy(quick_run, tmp_path, damage)
    out = tmp_path / "report"
    build_report(res, out, ROOT / "report" / "published",
                 expected={"figure_bem_laplace": "bem_laplace"})
    md, html = (out / "report.md").read_text(), (out / "index.html").read_text()
    assert "| figure_bem_laplace | figure | bem_laplace | damaged |" in md
    assert why in md
    assert "data:image/png" not in html and "Reproduced table" not in md
    assert "Claims" not in md
    from hpfebe.suite.results import DamagedResult, check_result, read_result

    with pytest.raises(DamagedResult, match=why):
        check_result(res, "figure_bem_laplace")
    if (res / "figure_bem_laplace.csv").exists():
        with pytest.raises(ValueError, match="damaged"):
            read_result(res, "figure_bem_laplace")


def test_csv_edited_to_other_numbers_is_damaged(quick_run, tmp_path):
    """Same size, same rows and columns, another number: only the checksum sees it."""
    from hpfebe.suite.results import DamagedResult, check_result

    def edit(out):
        p = out / "figure_bem_laplace.csv"
        lines = p.read_text().splitlines(keepends=True)
        row = lines[1]
        i = next(k for k, ch in enumerate(row) if ch.isdigit() and ch != "9")
        lines[1] = row[:i] + str(int(row[i]) + 1) + row[i + 1:]
        p.write_text("".join(lines))

    res = _damaged_copy(quick_run, tmp_path, edit)
    with pytest.raises(DamagedResult, match="sha256"):
        check_result(res, "figure_bem_laplace")


# --------------------------------------------------------------------------- interrupted runs
SLOW_WRITER = r"""
import os, sys, time
from hpfebe.suite import watch
from hpfebe.suite.results import atomic_write
watch.install_signal_handlers()
watch.watch_parent_from_env()
def writer(f):
    f.write("x" * 10)
    print("writing", os.getpid(), flush=True)
    time.sleep(60)
try:
    atomic_write(sys.argv[1], writer)
except watch.Terminated as exc:
    sys.exit(128 + exc.signum)
"""


def _gone(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except OSError:
        return True


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="POSIX signals")
def test_sigterm_removes_the_temporary_file(tmp_path):
    target = tmp_path / "table_9_9.csv"
    p = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)],
                         stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().startswith("writing")
    assert len(list(tmp_path.glob(".*.tmp"))) == 1
    p.send_signal(signal.SIGTERM)
    assert p.wait(timeout=30) == 128 + signal.SIGTERM
    assert not target.exists() and not list(tmp_path.glob(".*.tmp"))


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="Linux /proc")
def test_job_stops_when_its_parent_is_killed(tmp_path):
    """Snakemake killed outright (SIGKILL): its job stops within seconds instead of
    running on as an orphan, and leaves no temporary file."""
    target = tmp_path / "table_9_9.csv"
    parent_code = ("import os, subprocess, sys, time\n"
                   "env = dict(os.environ, HPFEBE_PARENT_PID=str(os.getpid()))\n"
                   f"subprocess.Popen([sys.executable, '-c', {SLOW_WRITER!r}, "
                   f"{str(target)!r}], env=env)\n"
                   "time.sleep(120)\n")
    parent = subprocess.Popen([sys.executable, "-c", parent_code], stdout=subprocess.PIPE,
                              text=True)
    line = parent.stdout.readline()
    assert line.startswith("writing"), line
    child = int(line.split()[1])
    parent.kill()
    parent.wait(timeout=10)
    t0 = time.time()
    while not _gone(child) and time.time() - t0 < 20:
        time.sleep(0.1)
    assert _gone(child), "the job outlived its parent"
    assert not target.exists() and not list(tmp_path.glob(".*.tmp"))


HEARTBEAT_WRITER = SLOW_WRITER.replace(
    "watch.watch_parent_from_env()",
    "watch.watch_heartbeat(sys.argv[2], timeout=1.5, interval=0.1)")


def test_job_stops_when_the_heartbeat_stops(tmp_path):
    """A cluster job on another node than its Snakemake watches the heartbeat file that
    the Snakemake rewrites every second (Snakefile, onstart): when the file stops
    changing, the job stops and leaves no temporary file."""
    heartbeat = tmp_path / "heartbeat"
    heartbeat.write_text("0\n")
    target = tmp_path / "table_9_9.csv"
    p = subprocess.Popen([sys.executable, "-c", HEARTBEAT_WRITER, str(target),
                          str(heartbeat)], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().startswith("writing")
    for beat in range(1, 9):               # 4 s of heartbeats: the job runs on
        heartbeat.write_text(f"{beat}\n")
        time.sleep(0.5)
        assert p.poll() is None, "the job stopped while the heartbeat went on"
    t0 = time.monotonic()
    assert p.wait(timeout=30) == 128 + signal.SIGTERM
    assert time.monotonic() - t0 < 1.5 + 2
    assert not target.exists() and not list(tmp_path.glob(".*.tmp"))


def test_job_on_another_host_watches_the_heartbeat(tmp_path):
    """The Snakemake runs on another host (HPFEBE_PARENT_HOST): its pid means nothing
    here, the heartbeat file decides; one last written a minute ago stops the job
    before it computes, although the pid given is alive on this host."""
    heartbeat = tmp_path / "heartbeat"
    heartbeat.write_text("1\n")
    old = time.time() - 60
    os.utime(heartbeat, (old, old))
    env = dict(os.environ, HPFEBE_PARENT_PID=str(os.getpid()),
               HPFEBE_PARENT_HOST="elsewhere.invalid", HPFEBE_HEARTBEAT=str(heartbeat))
    r = subprocess.run([sys.executable, "-m", "hpfebe", "run", "figure_bem_laplace",
                        "--quick", "--out", str(tmp_path / "out")], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "s old" in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("p", [True, 2.7, 0, np.nan, "2"])
def test_basis_degree_never_truncated(p):
    from hpfebe.spaces import lagrange_values, legendre_values

    for f in (lagrange_values, legendre_values):
        with pytest.raises(ValueError, match="degree p must be an integer"):
            f(p, np.zeros(3))


def test_snakefile_refuses_a_string_quick(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text('quick: "false"\n')
    r = subprocess.run([sys.executable, "-m", "snakemake", "-n", "--configfile", str(bad)],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode != 0
    assert "'quick' must be true or false, got 'false'" in r.stdout + r.stderr


def test_job_of_a_dead_snakemake_does_not_start(tmp_path):
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    env = dict(os.environ, HPFEBE_PARENT_PID=str(p.pid))
    r = subprocess.run([sys.executable, "-m", "hpfebe", "run", "figure_bem_laplace",
                        "--quick", "--out", str(tmp_path / "out")], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "has ended" in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()


def test_a_signal_inside_a_compiled_kernel_is_still_a_termination():
    """SIGTERM's Terminated raised while numba called back into Python reaches the CLI as
    a SystemError caused by it: found in the chain (exit 128 + signal, not 1)."""
    from hpfebe.suite.watch import terminated_cause as _terminated_cause
    from hpfebe.suite.watch import Terminated

    try:
        try:
            raise Terminated(15)
        except Terminated as inner:
            raise SystemError("returned a result with an exception set") from inner
    except SystemError as exc:
        found = _terminated_cause(exc)
    assert isinstance(found, Terminated) and found.signum == 15
    assert _terminated_cause(ValueError("other")) is None


def test_a_signal_swallowed_by_a_finalizer_still_ends_the_run(monkeypatch):
    """SIGTERM's Terminated raised inside a __del__ is printed and dropped by Python (the
    job then ran to its end and wrote its results: found by the job server's signal
    test); check_terminated, called before every write, raises it again."""
    import gc

    from hpfebe.suite import watch

    monkeypatch.setattr(watch, "RECEIVED", [])

    class Finalized:
        def __del__(self):
            watch._on_signal(signal.SIGTERM, None)

    Finalized()                  # the handler runs in __del__: "Exception ignored"
    gc.collect()
    with pytest.raises(watch.Terminated) as exc:
        watch.check_terminated()
    assert exc.value.signum == signal.SIGTERM


def test_a_swallowed_signal_ends_a_sweep_at_its_next_case(monkeypatch):
    """The sweeps' progress() checks for a signal before each case: a job whose SIGTERM
    was swallowed stops there instead of computing to its end."""
    from hpfebe.suite import watch
    from hpfebe.suite.progressbar import progress

    monkeypatch.setattr(watch, "RECEIVED", [])
    done = []
    with pytest.raises(watch.Terminated):
        for k in progress(range(5), desc="cases"):
            done.append(k)
            if k == 1:
                try:                      # library code with a broad except swallows it
                    watch._on_signal(signal.SIGTERM, None)
                except BaseException:     # noqa: BLE001
                    pass
    assert done == [0, 1]
