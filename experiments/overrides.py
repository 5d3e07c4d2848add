"""``--set KEY=VALUE``: one field of a frozen config dataclass from the command line.

``KEY`` is a dotted field path (``planner.neuralparker_footprint.samples``); ``VALUE`` is read as JSON (``5``,
``0.15``, ``true``, ``null``, ``[[128, 2, "policy"]]``) and, when that fails, as a plain string
(``ensemble``, ``checkpoints/site_np.pt``). A field holding a config with named presets (``preset(name)``, e.g.
`np_policy.config.NeuralParkerConfig`) takes a preset name: ``planner.neuralparker_footprint=paper``. Lists become
tuples, strings become paths where the field is a path; the value must have the field's type and pass the config's
own checks. Any mistake is one ConfigError naming the key, what was expected and what came.
"""

from __future__ import annotations

import dataclasses
import json
import typing
from pathlib import Path
from typing import Any

from np_policy.config import check_types
from np_sim.errors import ConfigError


def _value(text: str) -> Any:
    try:
        value = json.loads(text)
    except json.JSONDecodeError:
        return text
    return _tuples(value)


def _tuples(value: Any) -> Any:
    return tuple(_tuples(v) for v in value) if isinstance(value, list) else value


def _field_value(owner: type, name: str, text: str) -> Any:
    """``text`` as a value of field ``name`` of the dataclass ``owner``."""
    hint = typing.get_type_hints(owner)[name]
    options = typing.get_args(hint) or (hint,)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        if not hasattr(hint, "preset"):
            raise ConfigError(f"{owner.__name__}.{name}: a group of settings; set one of its fields "
                              f"({', '.join(f.name for f in dataclasses.fields(hint))}) with {name}.FIELD=VALUE")
        return hint.preset(text)
    value = _value(text)
    if Path in options and isinstance(value, str):
        return Path(value)
    check_types(owner, {name: value})
    return value


def override(config: Any, key: str, text: str) -> Any:
    """``config`` with the field at the dotted ``key`` set from ``text`` (module docstring)."""
    head, _, rest = key.partition(".")
    names = [f.name for f in dataclasses.fields(config)]
    if head not in names:
        raise ConfigError(f"{type(config).__name__}: unknown key {head!r}; expected one of {names}")
    current = getattr(config, head)
    if rest:
        if not dataclasses.is_dataclass(current):
            raise ConfigError(f"{type(config).__name__}.{head}: a single setting, it has no field {rest!r}")
        value = override(current, rest, text)
    else:
        value = _field_value(type(config), head, text)
    try:
        return dataclasses.replace(config, **{head: value})
    except (ValueError, TypeError) as error:
        raise ConfigError(str(error)) from error


def apply_overrides(config: Any, items: list[str]) -> Any:
    """``config`` with every ``KEY=VALUE`` of ``items`` applied in order; ConfigError naming the item otherwise."""
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise ConfigError(f"--set {item}: expected KEY=VALUE (e.g. planner.neuralparker_footprint.samples=16)")
        try:
            config = override(config, key.strip(), text.strip())
        except ConfigError as error:
            raise ConfigError(f"--set {item}: {error}") from error
    return config
