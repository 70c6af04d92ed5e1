"""What an experiment's ``run`` repeats around the numerics: the scenes asked for, the
parameters of a config section with subsections, the seconds a call takes.

    prm = from_config_sections(Params, config, "ch2_convergence",
                               smooth=SmoothParams, singular=SingularParams)
    (_, jit_s) = timed(warm_up, prm)
    return [r for name in select_scenes(SCENES, scenes, "ch2_convergence")
            for r in SCENE_RUNS[name](prm, jit_s)]
"""

from __future__ import annotations

import time
from dataclasses import replace

from .params import from_config

__all__ = ["select_scenes", "from_config_sections", "timed"]


def select_scenes(SCENES: dict, scenes, module: str) -> tuple[str, ...]:
    """The scenes of ``SCENES`` asked for in ``scenes`` (``None``: all), in the order of
    ``SCENES``; a ``ValueError`` names the unknown ones and the known ones of
    ``module``."""
    scenes = tuple(SCENES) if scenes is None else tuple(scenes)
    unknown = sorted(set(scenes) - set(SCENES))
    if unknown:
        raise ValueError(f"unknown scene(s) {unknown} of {module}; known: {list(SCENES)}")
    return tuple(name for name in SCENES if name in scenes)


def from_config_sections(cls, config: dict | None, scene: str, **sections):
    """``cls`` from the config section ``config`` of ``scene``
    (:func:`hpfebe.suite.params.from_config`) whose subsections are parameter objects of
    their own: ``sections`` maps a field of ``cls`` (= the subsection's key) to its
    class, built from the subsection (``scene.<key>`` in error messages)."""
    section = dict(config or {})
    subs = {key: from_config(sub, section.pop(key, None), scene=f"{scene}.{key}")
            for key, sub in sections.items()}
    return replace(from_config(cls, section, scene=scene), **subs)


def timed(fn, *args, **kwargs):
    """(fn(*args, **kwargs), its wall time in seconds by :func:`time.perf_counter`)."""
    t0 = time.perf_counter()
    value = fn(*args, **kwargs)
    return value, time.perf_counter() - t0
