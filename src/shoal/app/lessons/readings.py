"""A lesson step's numbers as the screen shows them: the metrics its ``check`` names, read off
the run the app shows (run 0) the way :mod:`.verify` computes them headless.

The Lessons tab lists them under the question (:func:`text`), so that every number a step
asks about can be read on the screen the step sets up: ``final`` at the check's last step
(now, until the run gets there), ``max``, ``min`` and ``mean`` over steps ``after``… of
the check, the window so far until the run gets to its end. The host gives the run as a
:class:`Run` (the metric rows it recorded, by step); the values are those of the headless
check for the same scene, digit for digit (``tests/test_lessons.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from shoal.studies.sweep.catalogue import labels

from .model import AGGREGATES, Check, Lesson

# verify.py's own metric, the SLO swarm's best so far (the sweep catalogue labels neither) and
# the sweep's "final best f" (a reading is at a step of its own)
OWN_LABELS = {"outside": ("robots outside the arena", "robots"), "best_so_far": ("best f so far", ""),
              "best_fitness": ("best f", "")}
SHARES = ("frac_inside_ring", "dead_reckoning")  # read as a percentage
COUNTS = ("collided", "stalled", "operational", "layers_passed", "outside", "contacts", "steps_to_converge",
          "quality_met_at")
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
FIRST_PASSAGE = {"steps_to_converge": "not yet", "quality_met_at": "not yet"}  # -1: not reached (yet)


@dataclass(frozen=True)
class Run:
    """What the host recorded of the run on screen: the step numbers of its metric rows
    (increasing, consecutive) and each metric's values at those steps."""

    steps: np.ndarray
    metrics: dict[str, np.ndarray]

    @property
    def k(self) -> int:
        """The step the run is at."""
        return int(self.steps[-1]) if len(self.steps) else 0


@dataclass(frozen=True)
class Reading:
    """One number of a step: ``kind`` of ``metric`` over steps ``first``..``upto`` of the
    check's ``first``..``last`` (``final``: ``first`` = ``upto``), or ``value`` None when the
    window is not reached yet or no longer recorded."""

    metric: str
    kind: str
    first: int
    upto: int
    last: int
    value: float | None

    @property
    def complete(self) -> bool:
        """The run got to the check's last step: the number the lesson quotes."""
        return self.upto >= self.last

    @property
    def label(self) -> str:
        """What the metric is, with its unit (the sweep's outcome labels, without their "at the end")."""
        name, unit = OWN_LABELS.get(self.metric) or labels().get(self.metric) or (self.metric.replace("_", " "), "")
        name = name.replace(" at the end", "")
        counted = unit in name.split()  # "collided robots", not "collided robots [robots]"
        return f"{name} [{unit}]" if unit and self.metric not in SHARES and not counted else name

    @property
    def span(self) -> str:
        if self.kind == "final":
            return f"at step {self.last}" if self.complete else f"at step {self.upto} (of {self.last})"
        word = {"max": "highest", "min": "lowest", "mean": "mean"}[self.kind]
        if self.complete:
            return f"{word} over steps {self.first}–{self.last}"
        if self.upto < self.first:
            return f"{word} over steps {self.first}–{self.last} (from step {self.first})"
        return f"{word} over steps {self.first}–{self.upto} so far (of {self.first}–{self.last})"

    @property
    def shown(self) -> str:
        return format_value(self.metric, self.value)


def format_value(metric: str, value: float | None) -> str:
    """A metric's value as the Lessons tab prints it (and the browser test reads it)."""
    if value is None:
        return "—"
    if not math.isfinite(value):
        return "∞" if value > 0 else ("−∞" if value < 0 else "—")
    if metric in FIRST_PASSAGE and value < 0:
        return FIRST_PASSAGE[metric]
    if metric in SHARES:
        return f"{100 * value:.1f} %"
    if metric in COUNTS and value == int(value):
        return str(int(value))
    if value != 0 and not 1e-3 <= abs(value) < 1e6:
        mantissa, exponent = f"{value:.3e}".split("e")
        return f"{float(mantissa):.3g}×10{str(int(exponent)).translate(SUPERSCRIPT)}"
    return f"{value:.4g}"


def aggregate(kind: str, series: np.ndarray) -> float:
    """``final``, ``max``, ``min`` or ``mean`` of one run's ``series`` (as :mod:`.verify` takes them)."""
    return float({"final": series[-1], "max": np.max(series), "min": np.min(series),
                  "mean": np.mean(series)}[kind])


def read(check: Check, run: Run) -> list[Reading]:
    """The readings of ``check`` on ``run``, at step ``min(k, check.steps)``."""
    upto = min(run.k, check.steps)
    out = []
    for kind in AGGREGATES:
        for metric in getattr(check, kind):
            first = upto if kind == "final" else check.after
            values, value = run.metrics.get(metric), None
            if values is not None and upto >= first:
                keep = (run.steps >= first) & (run.steps <= upto)
                if np.count_nonzero(keep) == upto - first + 1:  # the whole window is still recorded
                    value = aggregate(kind, values[keep])
            out.append(Reading(metric, kind, first, upto, check.steps, value))
    return out


def headless(check: Check, metrics: dict[str, np.ndarray]) -> list[Reading]:
    """The same readings of :func:`.verify.run_metrics`' run 0 (steps 1..``check.steps``)."""
    steps = np.arange(1, check.steps + 1)
    return read(check, Run(steps, {name: np.asarray(v)[:, 0] for name, v in metrics.items()}))


def text(readings: list[Reading], k: int) -> str:
    """The readings as the Lessons tab's markdown."""
    if not readings:
        return ""
    lines = "\n".join(f"- {r.label}, {r.span}: **{r.shown}**" for r in readings)
    return f"**Read on screen** <small>(the run shown, at step {k})</small>\n\n{lines}"


Scene = tuple[str, dict[str, Any]]
# the host's run on screen if it shows the scene (preset, values), recorded with the metrics
# named; else why not, in words
Measure = Callable[[str, dict[str, Any], tuple[str, ...]], "Run | str"]


def names(check: Check) -> tuple[str, ...]:
    """The metrics ``check`` names, in order."""
    return tuple(dict.fromkeys(m for kind in AGGREGATES for m in getattr(check, kind)))


def step_check(lesson: Lesson, index: int) -> tuple[Scene, Check] | None:
    """The scene and check of step ``index`` of ``lesson`` (None: it checks nothing)."""
    if not 0 <= index < len(lesson.steps):
        return None
    step, scene = lesson.steps[index], lesson.scene(index)
    if scene is None or step.setup is None or step.setup.check is None:
        return None
    return scene, step.setup.check
