"""Live uPlot charts as data: a :class:`PlotSpec` names the metric columns it shows (the
session's recorded columns, by name) with their labels, strokes and scales, and turns the
recorded metrics into uPlot's data, series and scales; a :class:`Chart` is any other uPlot
(not against time) whose data a kind computes from the session.

Time plots share their x axis with the timeline: the last ``history`` rows up to the step
shown, over the time span of all of them (so a scrubbed curve ends at the cursor). With
swarm B on, B's value of the ``twin`` column is one more (dashed teal) series.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Union

import numpy as np

from shoal.presets.models import Scenario

from ..session.session import Session

Columns = dict[str, np.ndarray]
TWIN_STROKE = "rgb(20,170,180)"  # swarm B's curve
TWIN_DASH = (5.0, 4.0)


def twin_series(label: str) -> dict[str, Any]:
    """uPlot series options of B's curve."""
    return {"label": f"B: {label}", "stroke": TWIN_STROKE, "width": 2, "dash": TWIN_DASH}


def padded(t: np.ndarray, *ys: np.ndarray) -> tuple[np.ndarray, ...]:
    """uPlot needs two x values to draw an axis: repeat a lone point (zeros when there is none)."""
    t = np.asarray(t, dtype=float)
    ys = tuple(np.asarray(y, dtype=float) for y in ys)
    if len(t) >= 2:
        return (t, *ys)
    t0 = float(t[0]) if len(t) else 0.0
    return (np.array([t0, t0 + 1e-6]), *(np.repeat(y[:1], 2) if len(y) else np.zeros(2) for y in ys))


def x_scale(span: tuple[float, float]) -> dict[str, Any]:
    """A numeric (not calendar) x axis over ``span``."""
    t0, t1 = float(span[0]), float(span[1])
    return {"time": False, "range": (t0, max(t1, t0 + 1e-6))}


@dataclass(frozen=True)
class Series:
    """One curve: a metric ``column`` (or a function of the columns and the scenario)."""

    label: str
    column: str | Callable[[Columns, Scenario], np.ndarray]
    stroke: str
    width: float = 2.0
    dash: tuple[float, float] | None = None
    scale: str | None = None  # another y axis
    fill: str | None = None
    show: Callable[[Scenario], bool] | None = None  # hidden (not dropped) when False

    def values(self, m: Columns, scenario: Scenario) -> np.ndarray:
        return np.asarray(m[self.column] if isinstance(self.column, str) else self.column(m, scenario), float)

    def options(self, scenario: Scenario) -> dict[str, Any]:
        out: dict[str, Any] = {"label": self.label, "stroke": self.stroke, "width": self.width}
        for key, value in (("dash", self.dash), ("scale", self.scale), ("fill", self.fill)):
            if value is not None:
                out[key] = value
        if self.show is not None:
            out["show"] = bool(self.show(scenario))
        return out


@dataclass(frozen=True)
class Line:
    """A constant series: a horizontal line at ``value`` (an obstacle layer, d_c)."""

    label: str
    value: float
    stroke: str = "rgba(120,120,120,0.9)"
    width: float = 1.0
    dash: tuple[float, float] | None = (4.0, 4.0)

    def options(self) -> dict[str, Any]:
        out: dict[str, Any] = {"label": self.label, "stroke": self.stroke, "width": self.width}
        if self.dash is not None:
            out["dash"] = self.dash
        return out


@dataclass(frozen=True)
class PlotSpec:
    """A time plot of recorded metric columns."""

    key: str
    title: str
    series: tuple[Series, ...]
    x_label: str = "t [s]"
    y_range: tuple[float, float | None] | Callable[[Session], tuple[float, float]] | None = (0.0, None)
    more_scales: dict[str, Any] = field(default_factory=dict)  # other y axes
    lines: Callable[[Session], tuple[Line, ...]] | None = None
    twin: str | None = None  # the column swarm B's dashed curve repeats (labelled as its series)
    nan_to: float | None = None  # NaN (no value yet) drawn as this
    history: int = 1500
    aspect: float = 2.0
    axes: tuple[dict[str, Any], ...] = ({}, {"size": 50})
    legend: dict[str, Any] | None = None

    def options(self, session: Session) -> tuple[dict[str, Any], ...]:
        sc = session.scenario
        lines = self.lines(session) if self.lines is not None else ()
        return ({"label": self.x_label},) + tuple(s.options(sc) for s in self.series) + tuple(
            line.options() for line in lines)

    def data(self, m: Columns, session: Session) -> tuple[np.ndarray, ...]:
        sc = session.scenario
        out = padded(m["t"], *(s.values(m, sc) for s in self.series))
        lines = self.lines(session) if self.lines is not None else ()
        out = out + tuple(np.full(len(out[0]), float(line.value)) for line in lines)
        return tuple(np.nan_to_num(a, nan=self.nan_to) for a in out) if self.nan_to is not None else out

    def scales(self, span: tuple[float, float], session: Session) -> dict[str, Any]:
        out: dict[str, Any] = {"x": x_scale(span)}
        if self.y_range is not None:
            out["y"] = {"range": self.y_range(session) if callable(self.y_range) else self.y_range}
        return {**out, **self.more_scales}

    def twin_label(self) -> str:
        return next(s.label for s in self.series if s.column == self.twin)


@dataclass(frozen=True)
class Chart:
    """Any other uPlot: ``data`` from the session, ``scales`` from the session and the data."""

    key: str
    title: str
    series: tuple[dict[str, Any], ...]
    data: Callable[[Session], tuple[np.ndarray, ...]]
    scales: Callable[[Session, tuple[np.ndarray, ...]], dict[str, Any]]
    aspect: float = 2.0
    axes: tuple[dict[str, Any], ...] = ({}, {"size": 50})
    legend: dict[str, Any] | None = None


Plot = Union[PlotSpec, Chart]
