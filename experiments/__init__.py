"""Experiment modules: one per thesis scene, each producing one or more artefacts.

The contract
============

A module ``experiments/<scene>.py`` reproduces one computation of the thesis and may
produce several artefacts from it (a sweep shared by table_2_1, table_2_2 and figure_2_2
is computed once)::

    \"\"\"Which thesis section and equations; every choice made where the thesis is
    silent (these choices are also repeated in the results' ``notes``).\"\"\"

    from hpfebe.suite import ArtefactResult, Claim, progress

    ARTEFACTS = ("table_2_1", "table_2_2", "figure_2_2")   # ids as in EXPERIMENTS.md

    def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
        ...

Rules
-----
* ``ARTEFACTS`` is a literal tuple of strings at module level (it is read without
  importing the module, see :mod:`hpfebe.suite.registry`).  An artefact belongs to
  exactly one module.  ``table_*`` artefacts produce ``results/<id>.csv`` and
  ``.json``; ``figure_*`` artefacts must also return a figure (``results/<id>.png``).
* ``config`` is the module's own section of ``config/config.yaml`` (key = module name);
  with ``--quick`` (Snakemake: ``--configfile config/quick.yaml``) the section of
  ``config/quick.yaml`` is merged over it (nested dicts merged, other values replaced).
  A missing section gives ``{}``.  ``quick`` is True in quick mode, for anything the
  config does not already say.
* ``run`` returns one :class:`hpfebe.suite.results.ArtefactResult` per entry of
  ``ARTEFACTS`` (no more, no fewer).  It does not write files: ``hpfebe run`` validates
  all results first and then writes them (:func:`hpfebe.suite.results.write_result`), so a
  contract breach never leaves half a set.  Meshes and fields for ParaView go into
  ``ArtefactResult.exports`` ({key: meshio.Mesh}, built with :mod:`hpfebe.io.vtu`) and
  are written as ``results/vtu/<id>_<key>.vtu`` ({key: [(load step, mesh), ...]}: one
  VTU per step and a ``.pvd`` series).
* ``table``: the published columns first, with the same names as in
  ``report/published/<published>``, then what else was measured (``dof``,
  ``wall_time_s``, iterations ...).  ``keys`` are the columns joining it with the
  published table; ``tolerances`` map value columns to ``("factor", f)`` (ratio
  within [1/f, f]) or ``("abs", a)`` (|difference| <= a).  Only columns listed in
  ``tolerances`` are compared in the report.
* NaN in a float column is an error unless the column is listed in
  ``meta["allow_nan_columns"]`` and explained in ``notes`` (e.g. the first rate of a
  sweep, a solver that did not converge).
* ``claims``: checked statements, each with ``holds`` = True / False / None (not
  decidable here, e.g. evaluated over zero converged runs: never True) and the measured
  ``evidence``, and a ``kind`` (:data:`hpfebe.suite.claims.CLAIM_KINDS`): ``thesis`` (a
  statement the thesis makes; the report's summary counts these), ``explanation`` (our
  computed test of a cause for a difference: one that could have failed, and survives
  the changes it should not depend on), ``hypothesis`` (a coincidence or reading not
  derived), ``beyond`` (beyond the thesis).  An explanation or hypothesis names what it
  explains in ``explains``: the ``id`` of claims of the same artefact and cells
  (``"cells:*"``, ``"cells:<column>"``, ``"cells:<column>[key=value]"``).  An artefact
  that differs is "explained" only when every off cell and failed thesis claim is
  linked to an explanation that holds.
* ``meta``: timings (``jit_s``, ``run_s``), dof, iterations, ...  ``run_s`` is shown
  as the artefact's wall time in the report.
* Progress bars: ``for x in progress(items, desc=...)`` (quiet unless stderr is a TTY).
  Logging: ``logging.getLogger(__name__)``; ``hpfebe run`` shows INFO on stderr.
* Numerics belong in the core (``hpfebe``); plotting in the experiment (matplotlib,
  Agg backend is set by the CLI; create figures with ``matplotlib.figure.Figure`` or
  ``plt.subplots`` - the CLI closes them after writing).  The patterns every experiment
  repeats are in the suite: :mod:`hpfebe.suite.figures` (``new_figure``, ``style_axes``,
  reference slopes, ``mesh_sequence_figure``, ``deformed_field_figure``),
  :mod:`hpfebe.suite.tables` (``published_table``, ``published_ratio``, ``grouped_rates``),
  :mod:`hpfebe.suite.runs` (``select_scenes``, ``from_config_sections``, ``timed``).  The
  scene itself (geometry, parameters, sweeps, the rows of the result tables, the choices
  where the thesis is silent) lives in :mod:`hpfebe.scenes`; the experiment keeps
  ``ARTEFACTS``/``SCENES``, ``run()``, the claims and the figures.

* Scenes: a module whose artefacts come from independent computations declares them,
  ``SCENES = {"scene": ("artefact", ...), ...}``, a literal dict whose values partition
  ``ARTEFACTS``, and takes ``run(config, quick=False, scenes=None)``: it computes only
  the scenes asked for (``None``: all) and returns the results of their artefacts.  Each
  scene is one workflow job (rule ``<module>__<scene>``, see
  :mod:`hpfebe.suite.registry`); artefacts that share an expensive computation belong to
  one scene.

Running: ``hpfebe run <artefact> [--quick]`` (the scene producing the artefact runs and
writes all its artefacts), or ``snakemake -j2`` for everything.  ``experiments/bem_laplace.py`` is a
complete small example.
"""
