"""numba's cache keyed on the kernels' sources (hpfebe._numba_cache)."""

import os
import subprocess
import sys

from hpfebe import _numba_cache as nc


def _package(tmp_path, callee="return x + 1"):
    pkg = tmp_path / "pkg"
    pkg.mkdir(exist_ok=True)
    (pkg / "caller.py").write_text("import numba\n@numba.njit(cache=True)\n"
                                   "def f(x):\n    return g(x)\n")
    (pkg / "callee.py").write_text(f"import numba\n@numba.njit\ndef g(x):\n    {callee}\n")
    (pkg / "plain.py").write_text("x = 1\n")
    return pkg


def test_an_edit_of_a_callee_changes_the_cache(tmp_path):
    """numba keys caller.f on caller.py alone; the digest covers callee.py too, so the
    edited callee gets a fresh cache instead of the caller's stale machine code."""
    pkg = _package(tmp_path)
    before = nc.sources_digest(pkg)
    (pkg / "plain.py").write_text("x = 2\n")          # no numba in it: same cache
    assert nc.sources_digest(pkg) == before
    _package(tmp_path, callee="return x + 2")
    assert nc.sources_digest(pkg) != before


def test_the_workflow_layers_count_only_with_a_kernel_of_their_own(tmp_path):
    """cli.py and suite/ sit above every kernel (tools/check_imports.py): editing them,
    numba in their text, leaves the cache; a jitted function of their own counts."""
    pkg = _package(tmp_path)
    (pkg / "suite").mkdir()
    (pkg / "cli.py").write_text("# times numba's JIT\n")
    before = nc.sources_digest(pkg)
    (pkg / "cli.py").write_text("# times numba's JIT, edited\n")
    (pkg / "suite" / "warmup.py").write_text("# calls every numba kernel once\n")
    assert nc.sources_digest(pkg) == before
    assert [p.name for p, _ in nc.kernel_sources(pkg)] == ["callee.py", "caller.py"]
    (pkg / "suite" / "warmup.py").write_text("import numba\nf = numba.njit(lambda x: x)\n")
    assert nc.sources_digest(pkg) != before


def test_root_kept_across_processes(tmp_path, monkeypatch):
    """A user's NUMBA_CACHE_DIR is the root; a child process of an hpfebe process (it
    inherits the digest directory) derives the same directory, not one nested in it."""
    import numba

    monkeypatch.setenv(nc.ENV, str(tmp_path / "mine"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)  # restored
    cache = nc.configure()
    assert cache.parent == tmp_path / "mine" and cache.name.startswith(nc.PREFIX)
    child = subprocess.run([sys.executable, "-c", "import os, hpfebe; "
                            f"print(os.environ[{nc.ENV!r}])"], env=dict(os.environ),
                           capture_output=True, text=True, check=True)
    assert child.stdout.strip() == str(cache)


def test_remove_stale_keeps_the_newest(tmp_path, monkeypatch):
    monkeypatch.setenv(nc.ENV, str(tmp_path))
    dirs = [tmp_path / f"{nc.PREFIX}{k}" for k in range(5)]
    for k, d in enumerate(dirs):
        d.mkdir()
        os.utime(d, (1000 + k, 1000 + k))
    assert sorted(nc.remove_stale(keep=3)) == dirs[:2]
    assert sorted(tmp_path.iterdir()) == dirs[2:]


def test_a_fresh_checkout_is_not_ready(tmp_path):
    """A new checkout of the same sources has the same digest directory but new mtimes,
    and numba then drops every cached kernel: the ready mark's stamps must change."""
    pkg = _package(tmp_path)
    before, digest = nc.source_stamps(pkg), nc.sources_digest(pkg)
    assert [s[0] for s in before] == ["callee.py", "caller.py"]    # the numba files only
    os.utime(pkg / "callee.py", (1e9, 1e9))                         # content unchanged
    assert nc.sources_digest(pkg) == digest
    assert nc.source_stamps(pkg) != before
