"""Live uPlot charts as data: a :class:`PlotSpec` names the metric columns it shows (the
session's recorded columns, by name) with their labels, strokes and scales, and turns the
recorded metrics into uPlot's data, series, scales and axes; a :class:`Chart` is any other
uPlot (not against time) whose data a kind computes from the session.

Time plots share their x axis with the timeline: the last ``history`` rows up to the step
shown, over the time span of all of them (so a scrubbed curve ends at the cursor). With
swarm B on, B's value of the ``twin`` column is one more (dashed blue) series.

Every chart is framed the same way (:func:`frame`): an axis range is never empty (one point,
or all values equal, still spans a width); the y range snaps to 1–2–5 steps, so it changes
(and uPlot rebuilds the chart) only now and then; values beyond 10⁵ or below 10⁻³ are shown
in units of 10³ᵏ with the exponent on the axis (no "0,000,000" cut off); the y axis is as wide
as its widest tick text; the x axis is labelled; and the top tick has room above it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Union

import numpy as np

from shoal.presets.models import Scenario

from ..session.session import Session

Columns = dict[str, np.ndarray]
TWIN_STROKE = "rgb(0,140,210)"  # swarm B's curve (its robots' blue, dashed: view/layers.TWIN)
TWIN_DASH = (5.0, 4.0)
PADDING = (12, 16, 0, 0)  # px above, right, below, left of the plot area: the top tick is not cut
MIN_SPAN = 1.0  # an x range of one point spans this (a second, a generation, a robot)
CHAR_PX = 7.0  # width of a tick digit at uPlot's 12 px axis font
EXPONENT_AT = (1e-3, 1e5)  # magnitudes outside this are shown ×10³ᵏ
LABEL_SIZE = 18  # px of an axis label
Range = tuple[Union[float, None], Union[float, None]]


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


def log10_abs(values: np.ndarray, floor: float = 1e-300) -> np.ndarray:
    """log₁₀ |v| with 0 and NaN at ``floor`` and ±inf at the largest float (uPlot's own log axis
    refuses values ≤ 0, and a converging swarm reaches 1e-140)."""
    v = np.abs(np.asarray(values, dtype=float))
    v = np.where(np.isinf(v), np.finfo(float).max, v)  # a swarm that diverged past floats: the top
    return np.log10(np.where(np.isfinite(v) & (v > floor), v, floor))


def x_scale(span: tuple[float, float]) -> dict[str, Any]:
    """A numeric (not calendar) x axis over ``span``, at least :data:`MIN_SPAN` wide."""
    t0, t1 = float(span[0]), float(span[1])
    if not math.isfinite(t0):
        t0 = 0.0
    if not math.isfinite(t1) or t1 - t0 < 1e-5 * max(1.0, abs(t0)):  # one point (or a placeholder pair)
        t1 = t0 + MIN_SPAN
    return {"time": False, "range": (t0, t1)}


def step_up(v: float) -> float:
    """The smallest of 1, 2, 5 × 10ᵏ at or above ``v`` > 0."""
    mag = 10.0 ** math.floor(math.log10(v))
    return next((m * mag for m in (1.0, 2.0, 5.0) if m * mag >= v * (1 - 1e-12)), 10.0 * mag)


def tick_step(span: float, ticks: int = 4) -> float:
    """uPlot's tick increment for ``span`` over about ``ticks`` ticks (1, 2, 2.5, 5 × 10ᵏ)."""
    raw = span / ticks
    mag = 10.0 ** math.floor(math.log10(raw))
    return next((m * mag for m in (1.0, 2.0, 2.5, 5.0) if m * mag >= raw), 10.0 * mag)


def superscript(k: int) -> str:
    return str(k).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))


@dataclass(frozen=True)
class YView:
    """What the y axis shows: [lo, hi] in data units, drawn in units of 10^``exponent``."""

    lo: float
    hi: float
    exponent: int = 0

    @property
    def factor(self) -> float:
        return 10.0 ** -self.exponent

    def range(self) -> tuple[float, float]:
        return self.lo * self.factor, self.hi * self.factor

    def tick_chars(self) -> int:
        """Characters of the widest tick label uPlot writes ("-1,500", "0.025")."""
        lo, hi = self.range()
        decimals = len(f"{tick_step(hi - lo):.12f}".rstrip("0").split(".")[1])
        widest = max(abs(lo), abs(hi))
        return len(f"{widest:,.{decimals}f}") + (1 if lo < 0 else 0)

    def axis(self, label: str = "") -> dict[str, Any]:
        """uPlot options of the y axis: wide enough for its ticks, the exponent (and ``label``) beside it."""
        text = " ".join(t for t in (label, f"×10{superscript(self.exponent)}" if self.exponent else "") if t)
        out: dict[str, Any] = {"size": max(32, int(math.ceil(CHAR_PX * self.tick_chars())) + 18)}
        if text:
            out.update(label=text, labelSize=LABEL_SIZE, labelGap=0)
        return out


def y_view(values: list[np.ndarray], fixed: Range = (None, None)) -> YView:
    """The y range over the finite ``values`` (a side given in ``fixed`` stays), snapped outwards to
    1–2–5 steps, never empty, and its exponent."""
    finite = [v[np.isfinite(v)] for v in (np.asarray(a, dtype=float).ravel() for a in values)]
    data = np.concatenate(finite) if finite else np.zeros(0)
    dlo = float(data.min()) if data.size else 0.0
    dhi = float(data.max()) if data.size else 0.0
    lo = fixed[0] if fixed[0] is not None else (0.0 if dlo >= 0 else -step_up(-dlo))
    hi = fixed[1] if fixed[1] is not None else (0.0 if dhi <= 0 else step_up(dhi))
    lo, hi = float(lo), float(hi)
    if hi - lo <= 1e-12 * max(1.0, abs(lo), abs(hi)):
        hi = lo + (step_up(abs(lo)) if lo else 1.0)
    big = max(abs(lo), abs(hi))
    exponent = 0
    if big >= EXPONENT_AT[1] or big < EXPONENT_AT[0]:
        exponent = 3 * math.floor(math.log10(big) / 3)
        if big < EXPONENT_AT[0] and exponent == 0:
            exponent = -3
    return YView(lo, hi, exponent)


def x_padding(x_range: tuple[float, float]) -> tuple[int, int, int, int]:
    """:data:`PADDING` with the right side wide enough for half the last x tick's text ("1,000"
    centred on the right edge of the plot would be cut)."""
    lo, hi = (float(v) for v in x_range)
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return PADDING
    step = tick_step(hi - lo, 5)
    decimals = len(f"{step:.12f}".rstrip("0").split(".")[1])
    last = math.floor(hi / step + 1e-9) * step
    chars = len(f"{last:,.{decimals}f}")
    return (PADDING[0], max(PADDING[1], int(math.ceil(CHAR_PX * chars / 2)) + 4), PADDING[2], PADDING[3])


@dataclass(frozen=True)
class Frame:
    """What one chart refresh sends: data, series options, scales, axes and the padding round the plot."""

    data: tuple[np.ndarray, ...]
    series: tuple[dict[str, Any], ...]
    scales: dict[str, Any]
    axes: tuple[dict[str, Any], ...]
    padding: tuple[int, int, int, int] = PADDING


def frame(data: tuple[np.ndarray, ...], series: tuple[dict[str, Any], ...], *, x_range: tuple[float, float],
          on_y: tuple[bool, ...], y_range: Range = (None, None), x_label: str = "", y_label: str = "",
          more_scales: dict[str, Any] | None = None, more_axes: tuple[dict[str, Any], ...] = ()) -> Frame:
    """Frame a chart: ``data[0]`` is x, ``on_y[i]`` says whether ``data[i + 1]`` is drawn on the y
    scale (scaled by its exponent; other series keep their own scale in ``more_scales``)."""
    view = y_view([y for y, y_scale in zip(data[1:], on_y) if y_scale], y_range)
    scaled = (np.asarray(data[0], dtype=float),) + tuple(
        np.asarray(y, dtype=float) * view.factor if y_scale else np.asarray(y, dtype=float)
        for y, y_scale in zip(data[1:], on_y))
    x_axis: dict[str, Any] = {"size": 30, "label": x_label, "labelSize": LABEL_SIZE, "labelGap": 0} if x_label else {}
    x = x_scale(x_range)
    return Frame(data=scaled, series=series,
                 scales={"x": x, "y": {"range": view.range()}, **(more_scales or {})},
                 axes=(x_axis, view.axis(y_label)) + tuple(more_axes), padding=x_padding(x["range"]))


FONT = 'system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", sans-serif'  # uPlot's own


def scale_text(f: Frame, scale: float) -> Frame:
    """``f`` with its axes' text ``scale`` times uPlot's 12 px (a projector), the axes as much wider."""
    if scale == 1.0:
        return f
    px = round(12 * scale)

    def axis(a: dict[str, Any]) -> dict[str, Any]:
        out = {**a, "font": f"{px}px {FONT}", "labelFont": f"bold {px}px {FONT}"}
        for key in ("size", "labelSize"):
            if key in out:
                out[key] = int(math.ceil(out[key] * scale))
        return out

    axes = tuple(axis(a) for a in f.axes)
    if axes and "size" not in axes[0]:  # the x axis: uPlot's 50 px hold 12 px digits
        axes = ({**axes[0], "size": int(math.ceil(50 * scale))},) + axes[1:]
    top, right, bottom, left = f.padding
    return Frame(f.data, f.series, f.scales, axes, (top, int(math.ceil(right * scale)), bottom, left))


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
    """A time plot of recorded metric columns. ``y_range``: a side given stays, None follows the
    data; ``more_axes``: the axes of ``more_scales`` (drawn as given)."""

    key: str
    title: str
    series: tuple[Series, ...]
    x_label: str = "t [s]"
    y_range: Range | Callable[[Session], Range] = (0.0, None)
    y_label: str = ""
    more_scales: dict[str, Any] = field(default_factory=dict)  # other y axes
    more_axes: tuple[dict[str, Any], ...] = ()
    lines: Callable[[Session], tuple[Line, ...]] | None = None
    twin: str | None = None  # the column swarm B's dashed curve repeats (labelled as its series)
    nan_to: float | None = None  # NaN (no value yet) drawn as this
    history: int = 1500
    aspect: float = 2.0
    legend: dict[str, Any] | None = None
    visible: Callable[[Session], bool] | None = None

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

    def render(self, m: Columns, span: tuple[float, float], session: Session,
               twin: np.ndarray | None = None) -> Frame:
        """The frame to send for metrics ``m`` over ``span`` (with B's ``twin`` column at the same times)."""
        data, series = self.data(m, session), self.options(session)
        on_y = tuple(s.scale in (None, "y") for s in self.series) + (True,) * (len(data) - 1 - len(self.series))
        if twin is not None:
            data = data + (np.nan_to_num(np.asarray(twin, dtype=float), nan=0.0),)
            series = series + (twin_series(self.twin_label()),)
            on_y = on_y + (True,)
        y_range = self.y_range(session) if callable(self.y_range) else self.y_range
        return frame(data, series, x_range=span, on_y=on_y, y_range=y_range, x_label=self.x_label,
                     y_label=self.y_label, more_scales=self.more_scales, more_axes=self.more_axes)

    def twin_label(self) -> str:
        return next(s.label for s in self.series if s.column == self.twin)


@dataclass(frozen=True)
class Chart:
    """Any other uPlot: ``data`` from the session, ``scales`` from the session and the data (its
    y range is kept; the frame widens an empty one and labels the axes)."""

    key: str
    title: str
    series: tuple[dict[str, Any], ...]
    data: Callable[[Session], tuple[np.ndarray, ...]]
    scales: Callable[[Session, tuple[np.ndarray, ...]], dict[str, Any]]
    x_label: str = ""
    y_label: str = ""
    aspect: float = 2.0
    legend: dict[str, Any] | None = None
    visible: Callable[[Session], bool] | None = None

    def render(self, session: Session) -> Frame:
        data = self.data(session)
        scales = self.scales(session, data)
        x = scales.get("x", {}).get("range") or (float(np.min(data[0])), float(np.max(data[0])))
        y = tuple(scales.get("y", {}).get("range") or (None, None))
        return frame(data, self.series, x_range=(float(x[0]), float(x[1])), on_y=(True,) * (len(data) - 1),
                     y_range=(y[0], y[1]), x_label=self.x_label, y_label=self.y_label)


Plot = Union[PlotSpec, Chart]
