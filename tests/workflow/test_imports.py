"""The package's import layering and faces (issue 24): no import cycle between the
subpackages and top-level modules of hpfebe (tools/check_imports.py, function-level imports
included); every name of ``hpfebe.__all__`` and of each subpackage's ``__all__`` resolves."""

import importlib
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import hpfebe

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "check_imports.py"
SUBPACKAGES = sorted(m.name for m in pkgutil.iter_modules(hpfebe.__path__) if m.ispkg)


def test_no_import_cycle():
    out = subprocess.run([sys.executable, str(TOOL)], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "no import cycle" in out.stdout


def test_tool_finds_a_function_level_cycle(tmp_path, monkeypatch):
    """The checker sees an import inside a function and reports the cycle with file:line."""
    spec = importlib.util.spec_from_file_location("check_imports", TOOL)
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    pkg = tmp_path / "src" / "hpfebe"
    (pkg / "a").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a" / "__init__.py").write_text("from ..b import f\n")
    (pkg / "b.py").write_text("def f():\n    from .a import g\n")
    monkeypatch.setattr(tool, "ROOT", tmp_path)
    monkeypatch.setattr(tool, "PKG", pkg)
    assert tool.check_cycles() == 1
    assert tool.edges()[("b", "a")] == ["src/hpfebe/b.py:2"]


def test_experiments_check_reports_and_passes():
    out = subprocess.run([sys.executable, str(TOOL), "--experiments"], capture_output=True,
                         text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "deep imports" in out.stdout


def test_curated_api_resolves():
    assert 20 <= len(hpfebe.__all__) <= 35
    missing = [n for n in hpfebe.__all__ if getattr(hpfebe, n, None) is None]
    assert not missing
    assert "BoundaryMesh" in dir(hpfebe)
    with pytest.raises(AttributeError):
        hpfebe.no_such_name  # noqa: B018


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_subpackage_all_resolves(name):
    mod = importlib.import_module(f"hpfebe.{name}")
    names = getattr(mod, "__all__", None)
    assert names, f"hpfebe.{name} has no __all__"
    assert len(set(names)) == len(names), f"hpfebe.{name}.__all__ has duplicates"
    missing = [n for n in names if not hasattr(mod, n)]
    assert not missing, f"hpfebe.{name}.__all__ names not defined: {missing}"


def test_scenes_import_lazily():
    """Issue 28: ``from hpfebe.scenes import interface`` (a Chapter 2 job's scene) imports
    that scene alone, not the other scenes (adaptive_bem pulls in the adaptivity,
    section44 the stamping scenes)."""
    code = ("import sys\n"
            "from hpfebe.scenes import interface\n"
            "loaded = sorted(m for m in sys.modules if m.startswith('hpfebe.'))\n"
            "print(' '.join(loaded))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    loaded = out.stdout.strip()
    assert "hpfebe.scenes.interface" in loaded.split()
    assert "hpfebe.scenes.adaptive_bem" not in loaded.split()
    assert "hpfebe.scenes.section44" not in loaded.split()
    assert "hpfebe.adaptivity" not in loaded


def test_scenes_names_are_their_modules_objects():
    from hpfebe import scenes
    from hpfebe.scenes import materials, stamping

    assert scenes.E is materials.E and scenes.touch is stamping.touch
    assert scenes.penalty is importlib.import_module("hpfebe.scenes.penalty")
    assert "section44_runs" in dir(scenes)
    with pytest.raises(AttributeError, match="no_such_scene"):
        scenes.no_such_scene  # noqa: B018
