"""What a tab asks for, and what a shared server allows.

A request names one or two axes (a field of the scene and its values, given as a list or as a
range and a count), the runs per cell, the steps per run and the outcome to show first. It
comes from the page, so any part of it may be anything a hostile client can send: every value
is checked against the scene's catalogue and the server's :class:`Limits`, and every cell by
the preset model and the app's limits, before anything is queued. A refusal names each
problem (:class:`Refused`). A grid in which the model or the limits refuse only some cells
(two fields whose values do not go together) is refused with the number of cells that could
run; asked again with ``skip_invalid``, it runs those and leaves the others out.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Sequence

from shoal.presets.io import PresetError
from shoal.presets.models import Scenario
from shoal.studies.cost import cost
from shoal.studies.sweep import catalogue
from shoal.studies.sweep.grid import Axis, SweepError, cell_problems, label, parse_values
from shoal.studies.sweep.plan import SweepPlan

from ..limits import check_runs

MAX_TEXT = 1000  # characters of a typed list of values
MAX_AXES = 2


class Refused(ValueError):
    """An experiment that cannot run; ``messages`` say why, one problem each. ``runnable``:
    when only some cells are refused, how many could run (of ``cells``) with ``skip_invalid``."""

    def __init__(self, messages: list[str], runnable: int = 0, cells: int = 0) -> None:
        self.messages, self.runnable, self.cells = messages, runnable, cells
        super().__init__("\n".join(messages))


@dataclass(frozen=True)
class Limits:
    """What one experiment may ask of a shared server, and how much its queue holds."""

    max_values: int = 12  # values per field
    max_cells: int = 64  # cells per experiment
    max_runs: int = 100  # runs per cell
    max_steps: int = 10_000  # steps per run
    max_experiment_runs: int = 1_000  # cells × runs of one experiment
    max_queue_runs: int = 3_000  # cells × runs of every experiment queued or running on the server
    max_seconds: float = 600.0  # estimated CPU seconds of one experiment (shoal.studies.cost)
    max_queue_seconds: float = 1_800.0  # estimated CPU seconds of every experiment queued or running

    def describe(self) -> str:
        return (f"at most {self.max_values} values per field, {self.max_cells} cells, {self.max_runs} runs per "
                f"cell, {self.max_steps} steps per run, {self.max_experiment_runs} cells × runs and about "
                f"{self.max_seconds / 60:.0f} CPU minutes per experiment; {self.max_queue_runs} cells × runs and "
                f"{self.max_queue_seconds / 60:.0f} CPU minutes in the server's queue")


@dataclass(frozen=True)
class AxisRequest:
    """A field and its values: ``values`` (a list, or text of TOML literals as ``--grid``
    takes them: ``2, 4, 8``), or ``start``, ``stop`` and ``count`` evenly spaced values."""

    key: Any
    values: Any = None
    start: Any = None
    stop: Any = None
    count: Any = None


@dataclass(frozen=True)
class ExperimentRequest:
    axes: Sequence[AxisRequest]
    runs: Any
    steps: Any = None  # None: the scene's sim.steps
    outcome: Any = None  # None: the first outcome of the scene
    skip_invalid: Any = False  # True: run the cells the model and the limits accept, leave the others out


def _whole(value: Any, what: str, lo: int, hi: int) -> int:
    """``value`` as a whole number in ``[lo, hi]``, else :class:`Refused` saying so."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value != int(value):
        raise Refused([f"{what}: {label(value)[:40]} is not a whole number"])
    if not lo <= int(value) <= hi:
        raise Refused([f"{what}: {int(value)} is outside {lo}..{hi} (this server's limit)"])
    return int(value)


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise Refused([f"{what}: {label(value)[:40]} is not a finite number"])
    return float(value)


def _range_values(field: catalogue.Field, ax: AxisRequest, limits: Limits) -> list[Any]:
    if not field.numeric:
        raise Refused([f"{field.key}: a range needs a numeric field; list the values ({field.range_text()})"])
    start, stop = _number(ax.start, f"{field.key} from"), _number(ax.stop, f"{field.key} to")
    count = _whole(ax.count, f"{field.key} count", 2, limits.max_values)
    raw = [start + (stop - start) * k / (count - 1) for k in range(count)]
    if field.kind == "integer":
        return list(dict.fromkeys(int(round(v)) for v in raw))
    return list(dict.fromkeys(float(f"{v:.6g}") for v in raw))


def _listed_values(field: catalogue.Field, values: Any) -> list[Any]:
    if isinstance(values, str):
        if len(values) > MAX_TEXT:
            raise Refused([f"{field.key}: the list of values is longer than {MAX_TEXT} characters"])
        try:
            return parse_values(values.strip())
        except ValueError as err:
            raise Refused([f"{field.key}: {err}"]) from None
    if isinstance(values, (list, tuple)):
        return list(values)
    raise Refused([f"{field.key}: give a list of values or a range and a count"])


def resolve_axis(field: catalogue.Field, ax: AxisRequest, limits: Limits) -> Axis:
    """The axis of ``ax``: every value checked against the field alone."""
    listed = ax.values is not None and not (isinstance(ax.values, str) and not ax.values.strip())
    if not listed and ax.start is None and ax.stop is None:
        raise Refused([f"{field.key}: no values; give a list of values, or a range and a count"])
    values = _listed_values(field, ax.values) if listed else _range_values(field, ax, limits)
    if not values:
        raise Refused([f"{field.key}: no values"])
    if len(values) > limits.max_values:
        raise Refused([f"{field.key}: {len(values)} values; this server takes at most {limits.max_values} per field"])
    labels = [label(v) for v in values]
    if len(set(labels)) != len(labels):
        raise Refused([f"{field.key}: a value is repeated ({', '.join(labels)[:200]})"])
    problems = [p for p in (field.problem(v) for v in values) if p]
    if problems:
        raise Refused(problems[:6])
    return Axis(field.key, tuple(values), title=field.title)


def _cell_problems(plan: SweepPlan) -> list[str]:
    """Each distinct reason a cell was left out, once, naming the first cell and how many more."""
    checked = [PresetError(list(plan.skipped[i])) if i in plan.skipped else sc for i, sc in enumerate(plan.scenarios)]
    return cell_problems(plan.axes, checked, "cell")


def resolve(scenario: Scenario, request: ExperimentRequest, limits: Limits) -> tuple[SweepPlan, str]:
    """The validated plan of ``request`` on ``scenario`` and the outcome to show; or
    :class:`Refused`. The plan's runs, seed and steps are those ``shoal sweep`` takes for
    this scenario with ``--runs``/``--steps``, so its jobs are the same."""
    axes_in = list(request.axes) if isinstance(request.axes, (list, tuple)) else []
    if not 1 <= len(axes_in) <= MAX_AXES:
        raise Refused([f"choose one or two fields to vary (got {len(axes_in)})"])
    fields = {f.key: f for f in catalogue.fields(scenario)}
    keys = [ax.key for ax in axes_in]
    for key in keys:
        if not isinstance(key, str) or key not in fields:
            raise Refused([f"{label(key)[:60]}: not a field this scene can vary"])
    if len(set(keys)) != len(keys):
        raise Refused([f"{keys[0]}: chosen twice; vary two different fields"])
    runs = _whole(request.runs, "runs per cell", 1, limits.max_runs)
    steps = scenario.sim.steps if request.steps is None else request.steps
    steps = _whole(steps, "steps per run", 1, limits.max_steps)
    offered = catalogue.outcomes(scenario)
    outcomes = [o.name for o in offered]
    outcome = catalogue.first_outcome(offered).name if request.outcome is None else request.outcome
    if outcome not in outcomes:
        raise Refused([f"{label(outcome)[:60]}: not an outcome of this scene ({', '.join(outcomes)})"])
    axes = [resolve_axis(fields[ax.key], ax, limits) for ax in axes_in]
    cells = math.prod(len(a.values) for a in axes)
    if cells > limits.max_cells:
        raise Refused([f"{' × '.join(str(len(a.values)) for a in axes)} = {cells} cells; "
                       f"this server runs at most {limits.max_cells} per experiment"])
    if cells * runs > limits.max_experiment_runs:
        raise Refused([f"{cells} cells × {runs} runs = {cells * runs} runs; this server runs at most "
                       f"{limits.max_experiment_runs} per experiment: fewer values or fewer runs"])
    base = scenario.model_dump(mode="json")
    base["sim"].update(runs=runs, steps=steps)  # as shoal sweep --runs --steps
    try:
        plan = SweepPlan.resolve(base, axes, where="cell", skip_invalid=True)
    except SweepError as err:  # no cell is valid
        raise Refused(err.messages[:8]) from None
    limited: dict[int, tuple[str, ...]] = {}
    for i in plan.runnable:  # whatever the fields: sim.steps and sim.robots may be swept
        sc = plan.scenario(i)
        try:
            check_runs(sc, steps=sc.sim.steps, runs=runs, max_steps=limits.max_steps,
                       max_seconds=limits.max_seconds)
        except PresetError as err:
            limited[i] = tuple(err.messages)
    if limited:
        plan = dataclasses.replace(plan, scenarios=tuple(None if i in limited else sc
                                                         for i, sc in enumerate(plan.scenarios)),
                                   skipped={**plan.skipped, **limited})
    if plan.skipped:
        runnable = len(plan.runnable)
        if not runnable:
            raise Refused(_cell_problems(plan)[:8])
        if request.skip_invalid is not True:
            offer = (f"{len(plan.skipped)} of {cells} cells cannot run; the other {runnable} can: "
                     "run them and leave these out?")
            raise Refused([offer, *_cell_problems(plan)[:7]], runnable=runnable, cells=cells)
    seconds = plan_seconds(plan)
    if seconds > limits.max_seconds:
        raise Refused([f"{len(plan.runnable)} cells × {runs} runs: about {seconds:,.0f} CPU seconds, more than the "
                       f"{limits.max_seconds:,.0f} this server gives one experiment; fewer values, runs, steps "
                       "or robots"])
    return plan, outcome


def plan_seconds(plan: SweepPlan) -> float:
    """Estimated CPU seconds of every run of ``plan`` (:func:`shoal.studies.cost.cost`)."""
    return sum(cost(sc, steps=sc.sim.steps, runs=plan.runs).seconds for sc in plan.scenarios if sc is not None)
