"""Sphinx configuration of the hpfebe documentation.

Build with ``sphinx-build -W docs docs/_build`` (warnings are errors).  The example
gallery (``examples/``) is executed by sphinx-gallery at build time; each script also runs
in the default ``pytest`` (``tests/examples``) at a small size.
"""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import hpfebe  # noqa: E402

project = "hpfebe"
author = "hpfebe contributors"
copyright = "2026, hpfebe contributors"
release = version = hpfebe.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "sphinx-mathjax-offline",        # MathJax shipped with the pages: math renders offline
]

templates_path = ["_templates"]
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]
html_theme = "furo"
html_title = f"hpfebe {release}"

autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"          # the docstrings say the types (numpy style)
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_param = False       # no automatic cross-references from plain-text types
napoleon_use_keyword = False

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
}

# the docstrings use the thesis's notation in plain text (V_hp, W_hp, ...): do not let
# `_hp` be read as an RST reference by napoleon's parameter parsing
nitpicky = False
suppress_warnings = ["autosummary.import_cycle"]


# ---------------------------------------------------------------- the API reference
# One page per top-level subpackage, listing exactly its ``__all__`` (the public API):
# regenerated at every build so that the reference follows the code.
SUBPACKAGES = ["geometry", "spaces", "quadrature", "bem", "fem", "constitutive", "bodies",
               "coupling", "contact", "solvers", "adaptivity", "analysis", "scenes", "io",
               "suite"]


def _api_pages():
    import importlib
    out = Path(__file__).parent / "api"
    out.mkdir(exist_ok=True)
    index = ["API reference", "=============", "",
             "Every name below is public: it is in the ``__all__`` of ``hpfebe`` or of a",
             "top-level subpackage ``hpfebe.<sub>``.  The names of ``hpfebe.__all__``",
             "(importable as ``from hpfebe import X``) are:", "",
             ", ".join(f":obj:`~hpfebe.{_API_HOME(n)}.{n}`" for n in hpfebe.__all__
                       if n != "__version__"), "",
             ".. toctree::", "   :maxdepth: 1", ""]
    for sub in SUBPACKAGES:
        mod = importlib.import_module(f"hpfebe.{sub}")
        names = list(getattr(mod, "__all__", []))
        title = f"hpfebe.{sub}"
        lines = [title, "=" * len(title), "", f".. automodule:: hpfebe.{sub}",
                 "   :no-members:", ""]
        if names:
            lines += [".. autosummary::", "   :toctree: ../generated", "   :nosignatures:",
                      ""] + [f"   hpfebe.{sub}.{n}" for n in names]
        text = "\n".join(lines) + "\n"
        page = out / f"{sub}.rst"
        if not page.exists() or page.read_text() != text:
            page.write_text(text)
        index.append(f"   {sub}")
    text = "\n".join(index) + "\n"
    if not (out / "index.rst").exists() or (out / "index.rst").read_text() != text:
        (out / "index.rst").write_text(text)


def _API_HOME(name):
    return hpfebe._API[name]


_api_pages()


# ---------------------------------------------------------------- plain-text docstrings
# Most docstrings of the core are written as plain text with the thesis's notation
# (|x|, ||u||, a_k, ...), not as reStructuredText.  A docstring that docutils cannot
# parse cleanly (after napoleon) is shown verbatim, as a literal block under its
# escaped first line, so that ``-W`` holds and nothing is lost or mangled.
import io as _io  # noqa: E402
import re as _re  # noqa: E402

from docutils import nodes as _nodes  # noqa: E402
from docutils.core import publish_doctree as _publish_doctree  # noqa: E402

_SPHINX_ONLY = ("Unknown interpreted text role", "Unknown directive type",
                "No role entry", "No directive entry", 'Unknown target name')
_ROLE = _re.compile(r":(?:[\w-]+:)+`")   # a Sphinx role -> docutils' own title-reference


def _renders(lines) -> bool:
    text = _ROLE.sub(":title-reference:`", "\n".join(lines))
    try:
        tree = _publish_doctree(text, settings_overrides={
            "report_level": 2, "halt_level": 5, "warning_stream": _io.StringIO(),
            "file_insertion_enabled": False, "raw_enabled": False})
    except Exception:
        return False
    if any(True for _ in tree.findall(_nodes.problematic)):
        return False
    for msg in tree.findall(_nodes.system_message):
        if msg["level"] >= 2 and not any(s in msg.astext() for s in _SPHINX_ONLY):
            return False
    return True


def _escape(line: str) -> str:
    return _re.sub(r"([\\*|`_<>\[\]:])", r"\\\1", line)


def _plain_docstring(app, what, name, obj, options, lines):
    if not lines or _renders(lines):
        return
    import inspect
    raw = (inspect.getdoc(obj) or "\n".join(lines)).splitlines()
    n_head = next((k for k, r in enumerate(raw) if not r.strip()), len(raw))
    if n_head > 3 or any(r[:1].isspace() for r in raw[:n_head]):
        n_head = 1                      # the first line only, if no short paragraph
    first, rest = " ".join(r.strip() for r in raw[:n_head]), raw[n_head:]
    while rest and not rest[0].strip():
        rest = rest[1:]
    lines[:] = [_escape(first), ""]
    if rest:
        lines += ["::", ""] + ["    " + r for r in rest] + [""]


def setup(app):
    app.connect("autodoc-process-docstring", _plain_docstring, priority=900)
