"""An experiment's result as a picture: in the page (plotly, redrawn as cells come in) and
as a PNG to download (matplotlib, the pictures of ``shoal sweep``).

One field: the median of the outcome over each cell's runs against the field's value, with
its 95 % confidence interval as a band. Two fields: a heat map of the medians, first field
across, second up. A first-passage median of +inf (fewer than half the runs got there) is
marked "n.c."; a cell left out as invalid "invalid"; a cell not finished yet is left blank.
Axes are named by the fields' titles with their units (:attr:`Field.title`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import plotly.graph_objects as go

from shoal.studies.experiments.output import png_bytes
from shoal.studies.sweep.catalogue import Outcome
from shoal.studies.sweep.plots import heat_figure, line_figure

from .service import Experiment

BLUE, BAND, GREY = "rgb(31,119,180)", "rgba(31,119,180,0.2)", "rgb(150,150,150)"


def _finite(a: np.ndarray) -> list[float | None]:
    """JSON-safe: NaN and ±inf become gaps."""
    return [float(v) if np.isfinite(v) else None for v in np.asarray(a, dtype=float).ravel()]


def _numeric(values: tuple[Any, ...]) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


def _escape(text: str) -> str:
    """Text for a plotly hover template (``%{...}`` is its markup)."""
    return text.replace("{", "(").replace("}", ")")


def title(exp: Experiment, outcome: Outcome, sep: str = " ") -> str:
    """``median <outcome>``, then (after ``sep``) the runs per cell and, while it runs, the cells done."""
    done, cells = len(exp.table), exp.cells
    part = "" if done == cells else f" · {done} of {cells} cells"
    return f"median {outcome.title}{sep}over {exp.plan.runs} runs per cell{part}"


def page_figure(exp: Experiment, outcome: Outcome) -> go.Figure:
    """The plotly figure of ``outcome`` over the finished cells of ``exp``."""
    med, lo, hi = exp.table.summary(outcome.name)
    axes = exp.plan.axes
    fig = go.Figure()
    if len(axes) == 1:
        ax = axes[0]
        x = list(ax.values) if _numeric(ax.values) else list(ax.labels)
        fig.add_trace(go.Scatter(x=x, y=_finite(lo), mode="lines", line={"width": 0}, hoverinfo="skip",
                                 showlegend=False))
        fig.add_trace(go.Scatter(x=x, y=_finite(hi), mode="lines", line={"width": 0}, fill="tonexty",
                                 fillcolor=BAND, name="95 % interval", hoverinfo="skip"))
        fig.add_trace(go.Scatter(x=x, y=_finite(med), mode="lines+markers", line={"color": BLUE}, name="median"))
        marks = [(xi, "n.c.") for xi, m in zip(x, med) if np.isinf(m)]
        marks += [(x[i], "invalid") for i in exp.plan.skipped]
        for xi, text in marks:
            fig.add_annotation(x=xi, y=1.0, yref="paper", text=text, showarrow=False, font={"color": GREY})
        fig.update_xaxes(title_text=ax.name, type=None if _numeric(ax.values) else "category")
        fig.update_yaxes(title_text=outcome.title)
        fig.update_layout(legend={"orientation": "h", "y": -0.3})
    else:
        ax_x, ax_y = axes[0], axes[1]
        z = med.T  # rows: second field, columns: first field
        invalid = np.zeros(exp.plan.shape, dtype=bool)
        for i in exp.plan.skipped:
            invalid[np.unravel_index(i, exp.plan.shape)] = True
        cells = [["invalid" if bad else ("" if np.isnan(v) else ("n.c." if np.isinf(v) else f"{v:.3g}"))
                  for v, bad in zip(row, bad_row)] for row, bad_row in zip(z, invalid.T)]
        median = f"median [{outcome.unit}]" if outcome.unit else "median"
        fig.add_trace(go.Heatmap(x=list(ax_x.labels), y=list(ax_y.labels),
                                 z=[_finite(row) for row in z], text=cells, texttemplate="%{text}",
                                 colorscale="Viridis", colorbar={"title": {"text": median, "side": "right"}},
                                 hovertemplate=f"{_escape(ax_x.name)} = %{{x}}<br>{_escape(ax_y.name)} = %{{y}}"
                                               "<br>median %{text}<extra></extra>"))
        fig.update_xaxes(title_text=ax_x.name, type="category")
        fig.update_yaxes(title_text=ax_y.name, type="category")
    fig.update_layout(title={"text": title(exp, outcome, "<br>"), "font": {"size": 12}},
                      margin={"l": 50, "r": 10, "t": 50, "b": 50}, uirevision=f"experiment-{exp.number}")
    return fig


def empty_figure(note: str) -> go.Figure:
    fig = go.Figure()
    fig.add_annotation(x=0.5, y=0.5, xref="paper", yref="paper", text=note, showarrow=False)
    fig.update_xaxes(visible=False)
    fig.update_yaxes(visible=False)
    fig.update_layout(margin={"l": 10, "r": 10, "t": 10, "b": 10})
    return fig


def png(exp: Experiment, outcome: Outcome) -> bytes:
    """The downloadable picture: ``shoal sweep``'s line (with the band) or heat map."""
    med, lo, hi = exp.table.summary(outcome.name)
    axes, runs = exp.plan.axes, exp.plan.runs
    if len(axes) == 1:
        fig = line_figure(axes[0], outcome.title, med, runs, band=(lo, hi), title=title(exp, outcome))
    else:
        fig = heat_figure(axes, outcome.title, med, runs, title=title(exp, outcome))
    return png_bytes(fig)
