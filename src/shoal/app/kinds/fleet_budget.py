"""The selected robot's budget as a small markdown table with bars: what DVC (or the constant
coefficients) lets each term of its velocity update contribute at this step.

Omni laws: attraction c1 + c2 and avoidance c3, with the reach U·Δt each allows
(U = c√2/β). Non-omni: the turn budgets c1, c2 (towards the bests), c3 (turn right,
body on the left), c4 (turn left, body on the right) and the forward push c5.
"""

from __future__ import annotations

import math

import numpy as np

from shoal.engine.kinds.fleet import FleetParams
from shoal.engine.kinds.fleet_probe import RobotView
from shoal.engine.robots.dvc import w_max

BAR = 12


def bar(value: float, full: float) -> str:
    """``value`` as a bar of ``BAR`` cells, ``full`` filling it."""
    frac = 0.0 if not (full > 0 and math.isfinite(value)) else min(max(value / full, 0.0), 1.0)
    n = int(round(frac * BAR))
    return "`" + "█" * n + "░" * (BAR - n) + "`"


def _row(name: str, value: float, full: float, note: str = "") -> str:
    return f"| {name} | {value:.3f} | {bar(value, full)} | {note} |"


def budget_markdown(view: RobotView, params: FleetParams, status: int, cmd: np.ndarray) -> str:
    """Markdown for the selected robot: state, ω, the coefficients as bars, gaps and command."""
    p, c = params, np.asarray(view.c, dtype=float)
    state = "operational" if status == 0 else "**collided** (disabled)"
    s = np.sort(view.gap)
    head = [f"**robot {view.robot:d}** · {state} · ω = {view.omega:.3g} · "
            f"s₁ = {s[0]:.2f} m, s₂ = {s[1]:.2f} m", "",
            "| term | c | budget | |", "|---|---|---|---|"]
    if p.law == "nonomni":
        wm = w_max(p.v_max, p.dt, p.rotational_energy, p.robot_radius)
        turn = p.beta * wm
        push = p.beta * min(p.alpha * p.sensing_range / p.dt, p.v_max)
        rows = [
            _row("c1 → own best", c[0], turn),
            _row("c2 → swarm best", c[1], turn),
            _row("c3 turn right", c[2], turn, "body left"),
            _row("c4 turn left", c[3], turn, "body right"),
            _row("c5 forward", c[4], push, f"U = {c[4] / p.beta:.2f} m/s"),
        ]
        tail = [f"v = {cmd[0]:.2f} m/s, w = {cmd[1]:.2f} rad/s (w_max = {wm:.2f} rad/s)"]
    else:
        k = math.sqrt(2) / p.beta if p.beta > 0 else math.nan
        if p.dvc:
            full = p.alpha * p.beta * p.sensing_range / (p.dt * math.sqrt(2))  # open-space c1 + c2
        else:
            full = float(c[:3].sum()) if len(c) >= 3 else float(c.sum())
        c12 = float(c[0] + c[1])
        c3 = float(c[2]) if len(c) >= 3 else 0.0
        bounded = p.law == "adapted-rpso"
        reach = (lambda v: f"reach {v * k * p.dt:.2f} m") if bounded else (lambda v: "")
        rows = [_row("attract c1 + c2", c12, full, reach(c12))]
        if p.law != "robot-centred":
            rows.append(_row("avoid c3", c3, full, reach(c12 + c3) if bounded else ""))
        force = float(np.hypot(*view.force))
        tail = [f"‖F_t‖ = {force:.3g} · ‖u‖ = {float(np.hypot(*cmd)):.2f} m/s"]
        if p.dvc:
            tail.append("c3 = 0 exactly when s₁ = s₂: no push between two equal gaps.")
    return "\n".join(head + rows) + "\n\n" + "\n\n".join(tail)
