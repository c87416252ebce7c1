"""A lesson step's scene as a preset with ``--set`` overrides, validated by the preset model.

The app's *Set up* button and the tests go through the same :func:`load_scene`: the shipped
preset, each field value as a ``dotted.key=value`` override, then the model, so a step can
only set up what a preset file or ``shoal run --set`` could.
"""

from __future__ import annotations

import math
from typing import Any

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..limits import check_app_limits
from .model import Lesson

_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def _toml_string(text: str) -> str:
    """A TOML basic string (JSON's escapes leave DEL raw, which TOML forbids)."""
    return '"' + "".join(_ESCAPES.get(ch) or (f"\\u{ord(ch):04x}" if ord(ch) < 0x20 or ord(ch) == 0x7F else ch)
                         for ch in text) + '"'


def toml_literal(value: Any) -> str:
    """``value`` as a TOML literal that :func:`shoal.presets.io.parse_value` reads back."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_literal(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_string(str(k))} = {toml_literal(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"{type(value).__name__} is not a preset value")


def overrides(values: dict[str, Any]) -> list[str]:
    """Field values as ``shoal run --set`` strings."""
    return [f"{key}={toml_literal(value)}" for key, value in values.items()]


def load_scene(preset: str, values: dict[str, Any]) -> Scenario:
    """The validated scenario of ``preset`` with ``values``, or :class:`PresetError`."""
    return presets_io.load_shipped(preset, overrides(values))  # lessons name shipped presets only


def describe(preset: str, values: dict[str, Any]) -> str:
    """``standard-pso with controller.omega = 1.1`` (what a Set up button loads)."""
    if not values:
        return preset
    return f"{preset} with " + ", ".join(f"{k} = {toml_literal(v)}" for k, v in values.items())


def scene_errors(lesson: Lesson) -> list[str]:
    """Every step whose scene the preset model or the app's limits refuse, naming lesson, step and field."""
    out = []
    for i, step in enumerate(lesson.steps):
        scene = lesson.scene(i)
        if scene is None:
            continue
        try:
            check_app_limits(load_scene(*scene))
        except PresetError as err:
            where = f"{lesson.id}.md, step {i + 1} '{step.title}'"
            out += [f"{where}: {describe(*scene)}: {msg}" for msg in err.messages]
    return out
