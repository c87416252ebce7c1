"""The Chapter 3 figures as plotly figures: pure functions of numbers, no viser.

* the (ω, ĉ) plane of Fig. 3-1 for the law in use: standard-PSO order-1 and order-2 regions
  [3.7], [3.9], or the Adapted PSO strip [3.13] and its robot subset [3.14]; the live point
  and what being inside means;
* the (u, a) phase plane of Fig. 3-3: lines a1, a2, a3 [3.24]-[3.25], the reachable
  parallelogram and the marked points, plus one particle's recent states;
* the speed bounds U [3.29] and U_j [3.26] of the speed plot.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import plotly.graph_objects as go

from shoal.engine.pso import stability

# Colours shared by the plots (CSS strings).
ORDER1_FILL = "rgba(120, 160, 230, 0.30)"
ORDER2_FILL = "rgba(40, 90, 200, 0.45)"
ADAPTED_FILL = "rgba(250, 200, 90, 0.18)"
ROBOT_FILL = "rgba(60, 170, 90, 0.22)"
POINT_OK = "rgb(20, 130, 60)"
POINT_BAD = "rgb(210, 40, 40)"

FONT_PX, TITLE_PX = 12, 14  # nothing smaller (projector mode: twice these, ``text_scaled``)
_FONT = dict(size=FONT_PX)
_MARGIN = dict(l=48, r=10, t=34, b=40)


def text_scaled(fig: go.Figure, scale: float) -> go.Figure:
    """``fig`` with every text at ``scale`` times its size (the title :data:`TITLE_PX`, the rest
    :data:`FONT_PX`); ``fig`` itself when it is already so, else a copy."""
    want = round(FONT_PX * scale)
    long_title = scale > 1 and " = " in (fig.layout.yaxis.title.text or "")
    if fig.layout.font.size == want and all(note.font.size in (None, want) for note in fig.layout.annotations) \
            and not long_title:
        return fig
    out = go.Figure(fig)
    with out.batch_update():
        out.layout.font.size = want
        out.layout.title.font.size = round(TITLE_PX * scale)
        out.layout.legend.font.size = want
        for note in out.layout.annotations:
            note.font.size = want
        m = _MARGIN
        out.layout.margin.update(l=round(m["l"] * scale), t=round(m["t"] * scale), b=round(m["b"] * scale))
        title = out.layout.yaxis.title.text or ""
        if scale > 1 and " = " in title:  # "ĉ = c1 + c2 [m/s]" → "ĉ [m/s]": a long axis title outgrows the axis
            unit = title[title.index("["):] if "[" in title else ""
            out.layout.yaxis.title.text = f"{title.split(' = ')[0]} {unit}".strip()
    return out


def _layout(fig: go.Figure, *, title: str, x: str, y: str, revision: str, legend: dict | None = None) -> go.Figure:
    fig.update_layout(
        title=dict(text=title, font=dict(size=TITLE_PX), x=0.02, y=0.98),
        xaxis_title=x,
        yaxis_title=y,
        uirevision=revision,  # keep the user's zoom across updates
        margin=_MARGIN,
        font=_FONT,
        template="plotly_white",
        legend=legend or dict(orientation="h", yanchor="top", y=-0.2, x=0.0, font=dict(size=FONT_PX)),
        showlegend=True,
    )
    return fig


# --------------------------------------------------------------------- (ω, ĉ) plane
def stability_curves(n: int = 201) -> dict[str, np.ndarray]:
    """Boundaries of the standard-PSO regions on ω ∈ [−1, 1]: ĉ = 4(ω+1) and 24(1−ω²)/(7−5ω)."""
    omega = np.linspace(-1.0, 1.0, n)
    return {
        "omega": omega,
        "order1": stability.order1_boundary(omega),
        "order2": stability.order2_boundary(omega),
    }


def in_region(omega: float, c_hat: float, adapted: bool) -> bool:
    """Is the live point inside the region that matters for the active law?"""
    if adapted:
        return bool(stability.adapted_stable(omega, c_hat, robot_subset=True))
    return bool(stability.order2_stable(omega, c_hat))


STABLE_MEANS = "inside: the steps stay bounded<br>(not: the swarm finds the optimum)"
OUTSIDE_MEANS = "outside: nothing keeps the steps<br>bounded (see the spread below)"


def stability_figure(omega: float, c_hat: float, *, adapted: bool, n: int = 201) -> go.Figure:
    """Fig. 3-1 for the law in use, with the live (ω, ĉ) and what "stable" means beside it.

    Traces, by name: the Adapted law's ``Adapted (−1 < ω < 1)`` and ``Adapted on robots
    (0 ≤ ω < 1)`` [3.13], [3.14], or the standard law's ``order-1 (standard)`` and ``order-2
    (standard)`` [3.7], [3.9]; then ``current``.
    """
    top = _top(c_hat)
    fig = go.Figure()
    if adapted:
        fig.add_trace(go.Scatter(
            x=[-1, 1, 1, -1, -1], y=[0, 0, top, top, 0], fill="toself", fillcolor=ADAPTED_FILL,
            line=dict(color="rgba(220,150,30,0.9)", dash="dot", width=1), name="Adapted (−1 < ω < 1)",
            mode="lines", hoverinfo="skip",
        ))
        fig.add_trace(go.Scatter(
            x=[0, 1, 1, 0, 0], y=[0, 0, top, top, 0], fill="toself", fillcolor=ROBOT_FILL,
            line=dict(color="rgba(40,140,70,0.9)", width=1), name="Adapted on robots (0 ≤ ω < 1)", mode="lines",
            hoverinfo="skip",
        ))
    else:
        cur = stability_curves(n)
        w = cur["omega"]
        fig.add_trace(go.Scatter(
            x=w, y=cur["order1"], fill="tozeroy", fillcolor=ORDER1_FILL, mode="lines",
            line=dict(color="rgb(90,130,210)", width=1.5), name="order-1 (standard)",
        ))
        fig.add_trace(go.Scatter(
            x=w, y=cur["order2"], fill="tozeroy", fillcolor=ORDER2_FILL, mode="lines",
            line=dict(color="rgb(30,70,170)", width=1.5), name="order-2 (standard)",
        ))
    ok = in_region(omega, c_hat, adapted)
    fig.add_trace(go.Scatter(
        x=[omega], y=[c_hat], mode="markers", name="current",
        marker=dict(size=13, color=POINT_OK if ok else POINT_BAD, symbol="x", line=dict(width=1, color="white")),
    ))
    fig.add_annotation(name="meaning", **_meaning(omega, c_hat, top, ok))
    fig = _layout(
        fig, title=_stability_title(omega, c_hat, adapted, ok),
        x="inertia weight ω", y=_stability_ylabel(adapted), revision="stability",
        legend=dict(orientation="v", yanchor="top", y=0.99, xanchor="left", x=0.01, font=dict(size=FONT_PX),
                    bgcolor="rgba(255,255,255,0.8)"),  # inside the plot: the spread below stays on screen
    )
    fig.update_xaxes(range=[-1.05, 1.25], autorange=False, zeroline=True)
    fig.update_yaxes(range=[0, top], autorange=False)
    # everything sits inside its margins, which never grow: no redraw of plotly's own after its first
    # (one still under way as the figure leaves the page, at a swap of scenes, was an error in the page)
    fig.update_layout(margin=dict(autoexpand=False))
    return fig


def figure_law(fig: go.Figure) -> bool | None:
    """Whether a :func:`stability_figure` shows the Adapted law's regions (None: not one)."""
    names = {t.name for t in fig.data}
    if "current" not in names:
        return None
    return any(name.startswith("Adapted") for name in names)


def update_stability_point(fig: go.Figure, omega: float, c_hat: float, *, adapted: bool) -> go.Figure:
    """Move the live point of a :func:`stability_figure` in place (cheap: no new figure); a
    figure of the other law is drawn anew."""
    if figure_law(fig) is not adapted:
        return stability_figure(omega, c_hat, adapted=adapted)
    top = _top(c_hat)
    ok = in_region(omega, c_hat, adapted)
    with fig.batch_update():
        for trace in fig.data:
            if trace.name == "current":
                trace.x, trace.y = [omega], [c_hat]
                trace.marker.color = POINT_OK if ok else POINT_BAD
            elif trace.name.startswith("Adapted"):
                trace.y = [0, 0, top, top, 0]
        fig.layout.title.text = _stability_title(omega, c_hat, adapted, ok)
        fig.layout.yaxis.title.text = _stability_ylabel(adapted)
        fig.layout.yaxis.range = [0, top]
        fig.layout.annotations[0].update(**_meaning(omega, c_hat, top, ok))
    return fig


def _top(c_hat: float) -> float:
    return max(8.5, 1.15 * float(c_hat) if math.isfinite(c_hat) else 8.5)


def _meaning(omega: float, c_hat: float, top: float, ok: bool) -> dict[str, Any]:
    """The note beside the live point: what inside (or outside) the region means. It points at
    the point from the side with more room."""
    x = float(np.clip(omega, -1.05, 1.25)) if math.isfinite(omega) else 0.0
    y = float(np.clip(c_hat, 0.0, top)) if math.isfinite(c_hat) else 0.0
    return dict(x=x, y=y, text=STABLE_MEANS if ok else OUTSIDE_MEANS, showarrow=True, arrowhead=2, arrowwidth=1,
                arrowcolor="rgb(90,90,90)", ax=-70 if x > 0.2 else 70, ay=-45 if y < 0.6 * top else 45,
                font=dict(size=FONT_PX, color=POINT_OK if ok else POINT_BAD), bgcolor="rgba(255,255,255,0.85)",
                align="left")


def _stability_title(omega: float, c_hat: float, adapted: bool, ok: bool) -> str:
    verdict = "inside" if ok else "OUTSIDE"
    region = "the Adapted region" if adapted else "the order-2 region"
    unit = " m/s" if adapted else ""  # ĉ has a unit only for the Adapted law
    return f"(ω, ĉ) = ({omega:.3g}, {c_hat:.3g}{unit}): {verdict} {region}"


def _stability_ylabel(adapted: bool) -> str:
    return "ĉ = c1 + c2 [m/s]" if adapted else "ĉ = c1 + c2 (no unit)"  # (the title names the region)


# --------------------------------------------------------------------- (u, a) plane
def phase_geometry(omega: float, c_hat: float, dt: float) -> dict[str, Any]:
    """Everything Fig. 3-3b draws for one dimension, or ``{}`` when no bound exists (ω ∉ [0, 1), ĉ ≤ 0).

    Lines are given by two far end points (the plot's axis range clips them): a2 and a3 are
    a1 moved by ±(ĉ, ĉ/Δt), which is [3.25] and also works for the vertical a1 at ω = 0.
    """
    if not (0.0 <= omega < 1.0) or c_hat <= 0 or dt <= 0:
        return {}
    U_j = c_hat / (1.0 - omega)
    A_minus_j = 2.0 * c_hat / dt
    u_lim, a_lim = 1.3 * U_j, 1.3 * A_minus_j
    line1 = stability.line_a1(omega, dt, 10 * u_lim, 10 * a_lim)
    shift = np.array([c_hat, c_hat / dt])
    poly = stability.reachable_parallelogram(omega, c_hat, dt)
    markers = stability.phase_markers(omega, c_hat, dt)
    return {
        "U_j": U_j, "A_plus_j": c_hat / dt, "A_minus_j": A_minus_j, "u_lim": u_lim, "a_lim": a_lim,
        "a1": line1, "a2": line1 + shift, "a3": line1 - shift,
        "parallelogram": np.vstack([poly, poly[:1]]),
        **markers,
    }


def phase_figure(
    omega: float, c_hat: float, dt: float, u: np.ndarray | None = None, a: np.ndarray | None = None,
    *, adapted: bool = True, label: str = "particle",
) -> go.Figure:
    """Fig. 3-3b plus a particle's recent (u_j, a_j).

    Traces, by name: ``reachable set``, ``a1``, ``a2``, ``a3``, ``★ ±U_j``, ``■ max deceleration``,
    ``◆ max acceleration``, ``recent``, ``now``.
    """
    geo = phase_geometry(omega, c_hat, dt) if adapted else {}
    fig = go.Figure()
    if geo:
        p = geo["parallelogram"]
        fig.add_trace(go.Scatter(
            x=p[:, 0], y=p[:, 1], fill="toself", fillcolor="rgba(120,160,230,0.22)", mode="lines",
            line=dict(color="rgba(90,130,210,0.8)", width=1), name="reachable set", hoverinfo="skip",
        ))
        for name, color, dash in (("a1", "rgb(60,60,60)", "dash"), ("a2", "rgb(200,90,30)", "solid"),
                                  ("a3", "rgb(120,60,170)", "solid")):
            pts = geo[name]
            fig.add_trace(go.Scatter(x=pts[:, 0], y=pts[:, 1], mode="lines", name=name,
                                     line=dict(color=color, dash=dash, width=1.5)))
        for key, name, symbol, color in (
            ("star", "★ ±U_j", "star", "rgb(230,170,0)"),
            ("square", "■ max deceleration", "square", "rgb(200,40,40)"),
            ("diamond", "◆ max acceleration", "diamond", "rgb(40,150,70)"),
        ):
            pts = geo[key]
            fig.add_trace(go.Scatter(x=pts[:, 0], y=pts[:, 1], mode="markers", name=name,
                                     marker=dict(symbol=symbol, size=12, color=color,
                                                 line=dict(width=1, color="black"))))
    if u is not None and a is not None and len(u):
        u, a = np.asarray(u, float), np.asarray(a, float)
        fig.add_trace(go.Scatter(x=u, y=a, mode="markers", name="recent",
                                 marker=dict(size=5, color="rgba(30,30,30,0.45)")))
        fig.add_trace(go.Scatter(x=u[-1:], y=a[-1:], mode="markers", name="now",
                                 marker=dict(size=11, color="rgb(220,50,50)", line=dict(width=1, color="black"))))
    if geo:
        u_lim, a_lim = geo["u_lim"], geo["a_lim"]
        if u is not None and a is not None and len(u):
            u_lim = max(u_lim, 1.1 * float(np.nanmax(np.abs(u))))
            a_lim = max(a_lim, 1.1 * float(np.nanmax(np.abs(a))))
        fig.update_xaxes(range=[-u_lim, u_lim])
        fig.update_yaxes(range=[-a_lim, a_lim])
        title = (f"{label}: U_j = {geo['U_j']:.3g}, A+_j = {geo['A_plus_j']:.3g}, "
                 f"A−_j = {geo['A_minus_j']:.3g}")
    elif not adapted:
        title = f"{label} (standard PSO: no bound)"
    else:
        title = f"{label} (no bound for ω = {omega:.3g})"
    return _layout(fig, title=title, x="velocity u_j [m/s]", y="acceleration a_j [m/s²]",
                   revision="phase")


def update_phase_points(fig: go.Figure, u: np.ndarray, a: np.ndarray) -> bool:
    """Replace the ``recent``/``now`` points of a :func:`phase_figure` in place, widening the axes
    if the points leave them. Returns False when the figure has no such traces (rebuild it)."""
    names = {t.name: t for t in fig.data}
    if "recent" not in names or "now" not in names or not len(u):
        return False
    u, a = np.asarray(u, float), np.asarray(a, float)
    with fig.batch_update():
        names["recent"].x, names["recent"].y = u, a
        names["now"].x, names["now"].y = u[-1:], a[-1:]
        for axis, values in ((fig.layout.xaxis, u), (fig.layout.yaxis, a)):
            if axis.range is not None:
                lim = max(abs(axis.range[1]), 1.1 * float(np.nanmax(np.abs(values))))
                if lim > axis.range[1]:
                    axis.range = [-lim, lim]
    return True


class PhaseText:
    """A :func:`phase_figure` as the JSON text plotly.js reads, its particle's points swapped in
    without plotly's validation: ``figure.to_json()`` costs about 10 ms for this figure, once a
    second in every tab playing a Chapter 3 swarm; the figure's other traces and its layout are
    written once into a template (rewritten when :func:`update_phase_points` would widen the
    axes), and only the ``recent`` and ``now`` points are written anew."""

    _SLOTS = ("recent.x", "recent.y", "now.x", "now.y")

    def __init__(self, fig: go.Figure) -> None:
        self._doc = json.loads(fig.to_json())
        names = [t.get("name") for t in self._doc.get("data", ())]
        self._at = (names.index("recent"), names.index("now")) if {"recent", "now"} <= set(names) else None
        self._template: str | None = None  # the document's JSON, each slot a quoted placeholder

    def _slot(self, name: str) -> str:
        return f"\x00phase:{name}\x00"

    def text(self, u: np.ndarray, a: np.ndarray) -> str | None:
        """The figure with these points (None when it has no such traces or there are none: rebuild it)."""
        if self._at is None or not len(u):
            return None
        u, a = np.asarray(u, float), np.asarray(a, float)
        layout = self._doc.get("layout", {})
        for axis, values in ((layout.get("xaxis"), u), (layout.get("yaxis"), a)):
            if axis is not None and axis.get("range") is not None:
                lim = max(abs(axis["range"][1]), 1.1 * float(np.nanmax(np.abs(values))))
                if lim > axis["range"][1]:
                    axis["range"] = [-lim, lim]
                    self._template = None
        if self._template is None:
            recent, now = (self._doc["data"][i] for i in self._at)
            recent["x"], recent["y"] = self._slot("recent.x"), self._slot("recent.y")
            now["x"], now["y"] = self._slot("now.x"), self._slot("now.y")
            self._template = json.dumps(self._doc)
        text = self._template
        for name, values in zip(self._SLOTS, (u, a, u[-1:], a[-1:])):
            text = text.replace(json.dumps(self._slot(name)), json.dumps(_plain(values)), 1)
        return text


def _plain(v: np.ndarray) -> list[float | None]:
    """Numbers as JSON reads them (NaN as null, as plotly writes it)."""
    return [x if math.isfinite(x) else None for x in v.tolist()]


# --------------------------------------------------------------------- speed vs time
def speed_bounds(omega: np.ndarray, c_hat: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-step U_j = ĉ/(1 − ω) [3.26] and U = U_j √d [3.29]; NaN where ω ∉ [0, 1)."""
    omega, c_hat = np.asarray(omega, float), np.asarray(c_hat, float)
    ok = (omega >= 0) & (omega < 1)
    U_j = np.where(ok, c_hat / np.where(ok, 1.0 - omega, 1.0), np.nan)
    return U_j * math.sqrt(d), U_j
