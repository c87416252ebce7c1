"""The parameter grid of a sweep: ``--grid dotted.key=v1,v2,...`` axes and their cells.

Values are TOML literals (``1.5``, ``true``, ``"b-pso"``; a bare word is a string), as for
``--set``. Every cell (one value per axis, the cartesian product of the axes) is validated
by the preset model before anything runs, so a bad key or value is named up front.
"""

from __future__ import annotations

import copy
import itertools
import json
import tomllib
from dataclasses import dataclass, field
from typing import Any, Sequence

from shoal.presets.builders.world import check_world
from shoal.presets.io import PresetError, parse_value, set_dotted, validate
from shoal.presets.models import Scenario
from shoal.presets.toml_bounds import check_toml


class SweepError(ValueError):
    """A sweep cannot start; ``messages`` name each bad argument or field."""

    def __init__(self, messages: list[str]) -> None:
        self.messages = messages
        super().__init__("\n".join(messages))


@dataclass(frozen=True)
class Axis:
    """One ``--grid`` argument: a dotted preset field and the values it takes; ``title`` names
    it on a plot (a label with its unit; the key when empty)."""

    key: str
    values: tuple[Any, ...]
    title: str = field(default="", compare=False)

    @property
    def name(self) -> str:
        """What a plot's axis says: the title, or the dotted key."""
        return self.title or self.key

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(label(v) for v in self.values)


def label(value: Any) -> str:
    """A grid value as a CSV cell and plot tick: ``1.5``, ``true``, ``b-pso``, ``[1.0, 2.0]``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float, str)):
        return str(value)
    return json.dumps(value)


def _split_top_level(text: str) -> list[str]:
    """Split at commas outside brackets and quotes."""
    items, depth, quote, start = [], 0, "", 0
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append(text[start:i])
            start = i + 1
    return items + [text[start:]]


def parse_values(text: str) -> list[Any]:
    """``1,1.5,3`` → ``[1, 1.5, 3]``; ``b-pso,xb-pso`` → two strings; arrays stay whole."""
    try:
        literal = f"v = [{text}]"
        check_toml(literal)  # (keys, dotted parts and nesting bounded before tomllib)
        values = tomllib.loads(literal)["v"]
    except (ValueError, RecursionError):  # not TOML, or beyond the bounds: value by value
        values = None
    if values is None or len(values) != len(_split_top_level(text)):
        parts = [p.strip() for p in _split_top_level(text)]
        if any(not p for p in parts):
            raise ValueError("empty value (two commas in a row, or a comma at an end)")
        values = [parse_value(p) for p in parts]
    return values


def parse_axis(text: str) -> Axis:
    """One ``--grid`` argument ``dotted.key=v1,v2,...``."""
    key, sep, rest = text.partition("=")
    key = key.strip()
    if not sep or not key or not rest.strip():
        raise SweepError([f"--grid {text!r}: expected dotted.key=v1,v2,..."])
    try:
        values = parse_values(rest.strip())
    except ValueError as err:
        raise SweepError([f"--grid {key}: {err}"]) from None
    labels = [label(v) for v in values]
    if len(set(labels)) != len(labels):
        raise SweepError([f"--grid {key}: a value is repeated ({', '.join(labels)})"])
    return Axis(key, tuple(values))


def parse_axes(texts: Sequence[str], fixed: Sequence[str] = ()) -> list[Axis]:
    """Every ``--grid`` argument; a key may appear once and not also among ``fixed`` keys
    (``--set``, ``--steps``, ...); ``sim.runs`` is ``--runs``, not a grid axis."""
    if not texts:
        raise SweepError(["give at least one --grid dotted.key=v1,v2,..."])
    return check_axes([parse_axis(t) for t in texts], fixed)


def check_axes(axes: Sequence[Axis], fixed: Sequence[str] = ()) -> list[Axis]:
    """``axes`` if each key appears once, not among ``fixed`` and not ``sim.runs``, each with
    distinct values (:class:`SweepError` naming the axis otherwise)."""
    if not axes:
        raise SweepError(["give at least one --grid dotted.key=v1,v2,..."])
    for a in axes:
        labels = a.labels
        if not labels:
            raise SweepError([f"--grid {a.key}: no values"])
        if len(set(labels)) != len(labels):
            raise SweepError([f"--grid {a.key}: a value is repeated ({', '.join(labels)})"])
    seen: set[str] = set()
    for a in axes:
        if a.key in seen:
            raise SweepError([f"--grid {a.key}: given twice"])
        if a.key == "sim.runs":
            raise SweepError(["--grid sim.runs: the runs per cell are --runs, not a grid axis"])
        if a.key in fixed:
            raise SweepError([f"--grid {a.key}: also fixed by --set/--steps/--seed; give it once"])
        seen.add(a.key)
    return list(axes)


def cells(axes: Sequence[Axis]) -> list[tuple[Any, ...]]:
    """The cartesian product of the axes' values, first axis slowest."""
    return list(itertools.product(*(a.values for a in axes)))


def cell_scenario(base: dict[str, Any], axes: Sequence[Axis], values: Sequence[Any]) -> Scenario:
    """``base`` (a raw preset dict) with one cell's values, validated by the preset model (and
    its world laid out, if it has one)."""
    data = copy.deepcopy(base)
    for a, v in zip(axes, values):
        set_dotted(data, a.key, copy.deepcopy(v))
    return check_world(validate(data))


def check_cells(base: dict[str, Any], axes: Sequence[Axis]) -> list[Scenario | PresetError]:
    """Every cell's scenario, or the model's refusal of it, in :func:`cells` order."""
    out: list[Scenario | PresetError] = []
    for values in cells(axes):
        try:
            out.append(cell_scenario(base, axes, values))
        except PresetError as err:
            out.append(err)
    return out


def cell_problems(axes: Sequence[Axis], checked: Sequence[Any], where: str = "--grid cell") -> list[str]:
    """The refusals among ``checked`` (one per cell, a :class:`PresetError` where refused), each
    distinct message once, naming the first cell it occurs in (after ``where``) and the field,
    e.g. ``--grid cell acoustics.Q=-1, acoustics.U=2: acoustics.Q: Input should be greater than
    0 (got -1)``."""
    first: dict[str, str] = {}
    count: dict[str, int] = {}
    for values, result in zip(cells(axes), checked):
        if isinstance(result, PresetError):
            cell = ", ".join(f"{a.key}={label(v)}" for a, v in zip(axes, values))
            for m in result.messages:
                first.setdefault(m, cell)
                count[m] = count.get(m, 0) + 1
    return [f"{where} {cell}: {m}" + (f" (and {count[m] - 1} more cells)" if count[m] > 1 else "")
            for m, cell in first.items()]


def resolve_cells(base: dict[str, Any], axes: Sequence[Axis], where: str = "--grid cell") -> list[Scenario]:
    """Validate every cell; all problems in one :class:`SweepError` (see :func:`cell_problems`)."""
    checked = check_cells(base, axes)
    problems = cell_problems(axes, checked, where)
    if problems:
        raise SweepError(problems)
    return [sc for sc in checked if isinstance(sc, Scenario)]
