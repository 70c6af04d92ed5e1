"""The reproducibility suite around the solver core.  The solver packages never import
it; the CLI and the experiments do.

* :mod:`.results` - the results contract: :class:`ArtefactResult` (what an experiment
  hands back), its validation, provenance, atomic writes, and the checks that find a
  damaged result;
* :mod:`.claims` - :class:`Claim` with its kinds, and the helpers that build the claims
  that recur (:func:`rate_claim`, :func:`beats_uniform_claim`, :func:`range_claim`,
  :func:`joint_claim`);
* :mod:`.params` - typed experiment parameters from the config (:func:`from_config`);
* :mod:`.progressbar` - :func:`progress`, a progress bar only on a terminal;
* :mod:`.published` - the thesis's published numbers and their comparison with ours;
* :mod:`.report` - the report that sets every reproduced number beside the published
  one (:func:`build_report`);
* :mod:`.warmup` - the numba warm-up (:func:`compile_kernels`, ``hpfebe compile``);
* :mod:`.figures`, :mod:`.tables`, :mod:`.runs` - what the experiments repeat: figures
  with labels, grid and reference slopes; published tables and rates per group; scene
  selection, config subsections, timing.

The experiments import the public names from here (``from hpfebe.suite import Claim``).
They are imported on first use (PEP 562): the results and the report need pandas and
matplotlib, which the command line's ``hpfebe list`` does not.
"""

from importlib import import_module

#: public name -> the module of the suite that defines it
_API = {
    "ArtefactResult": "results", "write_result": "results", "read_result": "results",
    "check_result": "results", "DamagedResult": "results", "atomic_write": "results",
    "remove_temporaries": "results", "provenance": "results",
    "TOLERANCE_KINDS": "results",
    "Claim": "claims", "CLAIM_KINDS": "claims", "CELLS_PREFIX": "claims",
    "rate_claim": "claims", "beats_uniform_claim": "claims", "range_claim": "claims",
    "joint_claim": "claims",
    "from_config": "params", "ConfigError": "params",
    "progress": "progressbar",
    "published_file_for": "published", "compare": "published",
    "build_report": "report",
    "compile_kernels": "warmup",
    "new_figure": "figures", "style_axes": "figures", "reference_slope": "figures",
    "slope_line": "figures", "readable_log_ticks": "figures",
    "mesh_sequence_figure": "figures", "deformed_field_figure": "figures",
    "published_table": "tables", "grouped_rates": "tables", "published_ratio": "tables",
    "select_scenes": "runs", "from_config_sections": "runs", "timed": "runs",
}

__all__ = list(_API)


def __getattr__(name: str):
    try:
        module = _API[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(import_module(f"{__name__}.{module}"), name)
    globals()[name] = value          # later look-ups skip __getattr__
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
