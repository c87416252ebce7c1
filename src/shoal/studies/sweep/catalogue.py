"""What a sweep of a scene can vary and what it measures, for the app's Experiment tab.

:func:`fields` lists the preset fields of a scenario that make sense to vary: the ones its
scene kind's build function reads (its registry entry's ``read_fields``, only the controller
fields of its mode),
with their range or choices from the preset model. Names, seeds, ``sim.runs`` (the runs per
cell), the view and the arena are never offered, nor anything that is not a number, a choice
or a flag (vectors, schedules). A choice is offered only with the values the model accepts in
this scene.

:func:`outcomes` lists the per-run outcomes a sweep of the scenario records (the kind's
:meth:`~shoal.engine.core.contract.Info.columns` and the sweep's whole-run summaries, exactly
the columns of :func:`~.outcomes.simulate_cell`), each with a label and a unit; positions,
per-run spreads and pair counts are left out.
"""

from __future__ import annotations

import copy
import functools
import math
import re
import types
import typing
from dataclasses import dataclass
from typing import Any, Literal

import annotated_types as at
from pydantic import BaseModel

from shoal.presets.io import PresetError, set_dotted, validate
from shoal.presets.kinds import KINDS, kind_for, metric_columns, plugin_sections
from shoal.presets.models import Registered, Scenario

from .grid import label
from .outcomes import FIRST_PASSAGE, CellJob, simulate_cell

# A swarm, fleet or acoustic swarm with an [slo] section (slo.swarm = "host") also reads these.
SLO_HOST = ("positions", "selection", "errors", "error_values", "prediction_weight", "delta_cos", "delta_v",
            "literal_eq_3_1", "entry_policy", "neighbourhood", "neighbourhood_param", "unit")
# Controller fields that only some modes read.
MODE_ONLY = {"omega": ("raw",), "c1": ("raw",), "c2": ("raw",), "c3": ("raw",), "U": ("physical",),
             "A_plus": ("physical",), "c1_share": ("physical", "dvc"), "alpha": ("dvc",), "beta": ("dvc",),
             "guard": ("dvc",)}


_BRACKET = re.compile(r"\[([^\[\]]+)\]")
_CITATION = re.compile(r"[\d.,–\- ]+")  # what an equation number holds: [4.14], [3.26, 3.29]
_REMARK = re.compile(r"\s+\([^()]*\)")  # " (physical mode)"; not the bracket of c1/(c1+c2)
TITLE_CHARS = 48


@dataclass(frozen=True)
class Field:
    """A preset field that can be an axis: a number in ``[lo, hi]`` (``lo_open``/``hi_open``:
    the end itself excluded), a whole number, or one of ``choices``."""

    key: str  # dotted path, as for --set and --grid
    description: str
    kind: Literal["number", "integer", "choice"]
    value: Any  # in the scenario now (None: unset)
    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple[Any, ...] = ()

    @property
    def numeric(self) -> bool:
        return self.kind != "choice"

    @property
    def unit(self) -> str:
        """The unit its description gives in brackets (``[m/s]``; an equation number is no unit), or ''."""
        found = [u for u in _BRACKET.findall(self.description) if not _CITATION.fullmatch(u)]
        return found[0] if found else ""

    @property
    def title(self) -> str:
        """The field in words with its unit, for a plot's axis: ``top speed U [m/s]``, ``inertia
        weight ω``, ``DVC safety factor α [4.14]`` (remarks in parentheses and after a ';' left
        out, and after a ':' that ends three words or more); its name when nothing is left."""
        text = self.description
        while (shorter := _REMARK.sub("", text)) != text:
            text = shorter
        text = text.split(";", 1)[0]
        head, colon, _ = text.partition(": ")
        if colon and len(head.split()) >= 3:
            text = head
        text = " ".join(text.split()).strip(" ,")
        if not text:
            text = self.key.rsplit(".", 1)[-1]
        if len(text) > TITLE_CHARS:
            text = text[: TITLE_CHARS - 1].rstrip() + "…"
        unit = self.unit
        return f"{text} [{unit}]" if unit and f"[{unit}]" not in text else text

    def range_text(self) -> str:
        """``0 < U ≤ 1000``, or the choices."""
        if not self.numeric:
            return " | ".join(label(c) for c in self.choices)
        name = self.key.rsplit(".", 1)[-1]
        left = f"{self.lo:g} {'<' if self.lo_open else '≤'} " if math.isfinite(self.lo) else ""
        right = f" {'<' if self.hi_open else '≤'} {self.hi:g}" if math.isfinite(self.hi) else ""
        return f"{left}{name}{right}"

    def problem(self, value: Any) -> str | None:
        """Why ``value`` cannot be on this axis (None: it can, as far as this field alone goes)."""
        if not self.numeric:
            return None if any(value == c and type(value) is type(c) for c in self.choices) else (
                f"{self.key}: {label(value)} is not one of {self.range_text()}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return f"{self.key}: {label(value)} is not a number"
        if self.kind == "integer" and value != int(value):
            return f"{self.key}: {value:g} is not a whole number"
        if not math.isfinite(value):
            return f"{self.key}: {value} is not a finite number"
        below = value < self.lo or (self.lo_open and value == self.lo)
        above = value > self.hi or (self.hi_open and value == self.hi)
        return f"{self.key}: {value:g} is outside {self.range_text()}" if below or above else None

    def suggest(self, count: int = 5) -> tuple[Any, ...]:
        """A first guess at the values: every choice, or ``count`` values from half to twice
        the current one (within the range)."""
        if not self.numeric:
            return self.choices
        lo, hi = span(self)
        values = [lo + (hi - lo) * k / (count - 1) for k in range(count)]
        if self.kind == "integer":
            return tuple(dict.fromkeys(int(round(v)) for v in values))
        return tuple(dict.fromkeys(float(f"{v:.3g}") for v in values))


def span(f: Field) -> tuple[float, float]:
    """A useful default range of a numeric field: half to twice its value, inside the model's
    range (an open end is kept a little way off)."""
    v = f.value if isinstance(f.value, (int, float)) and not isinstance(f.value, bool) else None
    lo = max(f.lo, v / 2 if v and v > 0 else (2 * v if v else 0.0))
    hi = min(f.hi, 2 * v if v and v > 0 else (v / 2 if v else 1.0))
    if not hi > lo:
        lo, hi = (f.lo, min(f.hi, f.lo + 1.0)) if math.isfinite(f.lo) else (max(f.lo, f.hi - 1.0), f.hi)
    inset = 1e-3 * (hi - lo)
    if f.lo_open and lo <= f.lo:
        lo = f.lo + inset
    if f.hi_open and hi >= f.hi:
        hi = f.hi - inset
    if f.kind == "integer":
        lo, hi = math.ceil(lo), math.floor(hi)
    return lo, hi


def _model_of(annotation: Any) -> type[BaseModel] | None:
    for a in typing.get_args(annotation) or (annotation,):
        if isinstance(a, type) and issubclass(a, BaseModel):
            return a
    return None


def _scalar(annotation: Any) -> Any:
    """``float | None`` → float; anything else as it is."""
    if isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is typing.Union:
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        return args[0] if len(args) == 1 else annotation
    return annotation


def _bounds(metadata: list[Any]) -> dict[str, Any]:
    out: dict[str, Any] = {"lo": -math.inf, "hi": math.inf, "lo_open": False, "hi_open": False}
    for m in metadata:
        if isinstance(m, at.Ge):
            out.update(lo=float(m.ge), lo_open=False)  # type: ignore[arg-type]  # (the model's bounds are numbers)
        elif isinstance(m, at.Gt):
            out.update(lo=float(m.gt), lo_open=True)  # type: ignore[arg-type]
        elif isinstance(m, at.Le):
            out.update(hi=float(m.le), hi_open=False)  # type: ignore[arg-type]
        elif isinstance(m, at.Lt):
            out.update(hi=float(m.lt), hi_open=True)  # type: ignore[arg-type]
    return out


def _valid_choices(raw: dict[str, Any], key: str, options: tuple[Any, ...]) -> tuple[Any, ...]:
    """The options the model accepts for ``key`` with everything else as in ``raw``."""
    ok = []
    for option in options:
        data = copy.deepcopy(raw)
        try:
            set_dotted(data, key, option)
            validate(data)
        except PresetError:
            continue
        ok.append(option)
    return tuple(ok)


def _leaves(model: type[BaseModel], obj: Any, prefix: str, names: tuple[str, ...] | None,
            raw: dict[str, Any]) -> list[Field]:
    out: list[Field] = []
    for name in names if names is not None else tuple(model.model_fields):
        info = model.model_fields[name]
        key, value = f"{prefix}.{name}", getattr(obj, name)
        nested = _model_of(info.annotation)
        if nested is not None:
            out += _leaves(nested, value, key, None, raw)
            continue
        kind = _scalar(info.annotation)
        text = info.description or name
        named = next((m for m in info.metadata if isinstance(m, Registered)), None)  # a registry's names
        if kind is bool or typing.get_origin(kind) is Literal or named is not None:
            options = named.names() if named is not None else (False, True) if kind is bool else typing.get_args(kind)
            choices = _valid_choices(raw, key, options)
            if len(choices) > 1:
                out.append(Field(key, text, "choice", value, choices=choices))
        elif kind in (int, float):
            out.append(Field(key, text, "integer" if kind is int else "number", value, **_bounds(info.metadata)))
    return out


def reads(scenario: Scenario) -> dict[str, tuple[str, ...] | None]:
    """The section → field names that the scenario's kind reads (its mode's controller fields)."""
    sections = dict(kind_for(scenario).read_fields())
    if scenario.slo is not None and "slo" not in sections:
        sections = {"slo": SLO_HOST, **sections}
    names = sections.get("controller")
    if names is not None:
        mode = scenario.controller.mode
        sections["controller"] = tuple(n for n in names if mode in MODE_ONLY.get(n, (mode,)))
    return sections


def fields(scenario: Scenario) -> list[Field]:
    """The fields of ``scenario`` worth an axis, the kind's own controls first."""
    return list(_fields(scenario.model_dump_json()))


@functools.lru_cache(maxsize=16)
def _fields(scenario_json: str) -> tuple[Field, ...]:
    scenario = Scenario.model_validate_json(scenario_json)
    raw = scenario.model_dump(mode="json")
    out: list[Field] = []
    for section, names in reads(scenario).items():
        field = Scenario.model_fields.get(section)
        model = _model_of(field.annotation) if field is not None else plugin_sections()[section]
        assert model is not None, section  # (every section a kind reads is a model)
        out += _leaves(model, scenario.section(section), section, names, raw)
    return tuple(out)


@dataclass(frozen=True)
class Outcome:
    """A per-run outcome: its column name, what it is, its unit."""

    name: str
    label: str
    unit: str = ""

    @property
    def first_passage(self) -> bool:
        """A time to reach something; a run that never got there counts as +inf in medians."""
        return self.name in FIRST_PASSAGE

    @property
    def title(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label


COMMON_LABELS: dict[str, tuple[str, str]] = {  # the columns of every kind; each kind labels its own (its entry)
    "t": ("time the run ended", "s"),
    "peak_speed": ("highest robot speed over the run", "m/s"),
    "best_fitness": ("final best f", ""),
    "max_speed": ("highest robot speed at the end", "m/s"),
    "mean_speed": ("mean robot speed at the end", "m/s"),
    "time_to_converge_s": ("time to converge", "s"),
}
HIDDEN_SUFFIXES = ("_std", "_sem", "_count")  # the per-run spread and pair counts behind the SLO error statistics


def labels() -> dict[str, tuple[str, str]]:
    """Column → (label, unit) of every outcome a sweep may offer: the common ones and each
    registered kind's (``SceneKind.labels``)."""
    out = dict(COMMON_LABELS)
    for kind in KINDS.values():
        out.update(kind.labels)
    return out


def hidden() -> frozenset[str]:
    """Columns never offered as outcomes: where the run ended (step) and each kind's own
    (``SceneKind.hidden``: positions, the SLO swarm's copy of best_fitness)."""
    return frozenset({"step", *(c for kind in KINDS.values() for c in kind.hidden)})


def first_columns() -> tuple[str, ...]:
    """The outcomes shown first, in this order of preference: each kind's first headline column
    (``SceneKind.headline``), the columns every kind has (best_fitness) last."""
    firsts = [kind.headlines[0] for kind in KINDS.values() if kind.headlines]
    common = set(COMMON_LABELS)
    return tuple(dict.fromkeys([c for c in firsts if c not in common] + [c for c in firsts if c in common]))


def first_outcome(outcomes: list[Outcome]) -> Outcome:
    """The outcome shown first: its kind's headline measure (:func:`first_columns`)."""
    names = [o.name for o in outcomes]
    return outcomes[next((names.index(n) for n in first_columns() if n in names), 0)]


def outcomes(scenario: Scenario) -> list[Outcome]:
    """The outcomes a sweep of ``scenario`` records, labelled, in the order of its columns."""
    return list(_outcomes(scenario.model_dump_json()))


@functools.lru_cache(maxsize=16)
def _outcomes(scenario_json: str) -> tuple[Outcome, ...]:
    columns = simulate_cell(CellJob(0, scenario_json, 0, 1, 0), 0, 1).columns  # built, not stepped
    names = [n for n in columns if n not in hidden() and not n.endswith(HIDDEN_SUFFIXES)]
    schema = {c.name: (c.description, "" if c.unit in ("", "objective") else c.unit) for c in metric_columns()}
    named = labels()
    return tuple(Outcome(n, *named.get(n) or schema.get(n) or (n.replace("_", " "), "")) for n in names)
