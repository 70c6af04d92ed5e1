"""Parameter objects of the experiments: a frozen dataclass per scene, built from the
scene's config section with its types checked (no silent coercion: ``"16"`` is not an
int, ``"false"`` is not a bool, an unknown key is an error naming the key).

    @dataclass(frozen=True)
    class Params:
        E: float = 266926.0
        n_per_side: list[int] = (4, 8, 16)
        plane: str = "strain"

    prm = from_config(Params, section, scene="ch3_penalty")

Supported field types: bool, int, float (ints accepted), str, list[T] / tuple[T, ...] of
those (a YAML list; stored as a tuple), ``T | None``, and dict (taken as given).
"""

from __future__ import annotations

import dataclasses
import types
import typing

__all__ = ["from_config", "ConfigError"]


class ConfigError(ValueError):
    """A config value of the wrong type or an unknown key.

    ``path`` is the dotted config path of the offending key (e.g.
    ``"ch3_penalty.n_per_side[1]"``), so that the command line can say which config
    file set it."""

    def __init__(self, message: str, path: str | None = None):
        super().__init__(message)
        self.path = path


def _check(value, tp, where: str):
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        errors = []
        for a in inner:
            try:
                return _check(value, a, where)
            except ConfigError as e:
                errors.append(e)
        raise errors[0]
    if origin in (list, tuple):
        if isinstance(value, (str, bytes, dict)) or not isinstance(value, (list, tuple)):
            raise ConfigError(f"{where} must be a list, got {value!r}", where)
        elem = args[0] if args else typing.Any
        return tuple(_check(v, elem, f"{where}[{i}]") for i, v in enumerate(value))
    if tp is typing.Any:
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where} must be true or false, got {value!r}", where)
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where} must be an integer, got {value!r}", where)
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{where} must be a number, got {value!r}", where)
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where} must be a string, got {value!r}", where)
        return value
    if tp is dict or origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{where} must be a mapping, got {value!r}", where)
        return value
    raise TypeError(f"unsupported parameter type {tp!r} for {where}")


def from_config(cls, section: dict | None, scene: str = "config"):
    """An instance of the dataclass ``cls`` from ``section`` (missing keys keep their
    defaults); ConfigError names the scene and key of any unknown or mistyped value."""
    section = {} if section is None else section
    if not isinstance(section, dict):
        raise ConfigError(f"config section {scene!r} must be a mapping, got {section!r}",
                          scene)
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls) if f.init}
    unknown = sorted(set(section) - names)
    if unknown:
        raise ConfigError(f"config section {scene!r}: unknown key(s) {unknown}; "
                          f"allowed: {sorted(names)}", f"{scene}.{unknown[0]}")
    values = {k: _check(v, hints[k], f"{scene}.{k}") for k, v in section.items()}
    try:
        return cls(**values)
    except ConfigError:
        raise
    except ValueError as e:          # a range check of the parameter object
        raise ConfigError(f"config section {scene!r}: {e}", scene) from None
