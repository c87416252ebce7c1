"""Headless runs that keep a lesson's words true for what the student will see.

A step's ``check`` runs its scene (preset, field values, the preset's seed) in the engine
for ``check.steps`` steps; run 0 is the run the browser app shows after *Set up*. The
metrics are the columns of ``shoal run``'s ``metrics.csv`` for that kind of scene, plus
``outside`` (robots outside the arena square, as the app's status line counts them).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.engine.core.recorder import metric_table
from shoal.presets.build import build

from .model import AGGREGATES, Check, Lesson
from .scenes import describe, load_scene


def outside(x: np.ndarray, half_size: float) -> np.ndarray:
    """Robots outside the arena square in positions ``x`` (..., N, d): the count over N."""
    return np.sum(np.any(np.abs(np.asarray(x)[..., :2]) > half_size, axis=-1), axis=-1).astype(float)


def run_metrics(preset: str, values: dict[str, Any], steps: int, runs: int = 1) -> dict[str, np.ndarray]:
    """Each metric as an array (steps, runs) over steps 1..``steps`` of the scene."""
    scenario = load_scene(preset, values)
    sim = build(scenario, runs=runs)
    half = scenario.arena.half_size
    rows: dict[str, list[np.ndarray]] = {}
    for _ in range(steps):
        info = sim.step()
        table = metric_table(sim.state, info, sim.t)
        table["outside"] = outside(sim.state.x, half)
        for name, value in table.items():
            rows.setdefault(name, []).append(np.asarray(value, dtype=float))
    return {name: np.stack(v) for name, v in rows.items() if name not in ("run", "step")}


def check_failures(preset: str, values: dict[str, Any], check: Check,
                   metrics: dict[str, np.ndarray] | None = None) -> list[str]:
    """What does not hold of ``check`` in the scene (empty: everything holds); ``metrics``:
    the scene's :func:`run_metrics` if already run."""
    m = run_metrics(preset, values, check.steps, check.runs) if metrics is None else metrics
    out = []
    for kind in AGGREGATES:
        for name, (lo, hi) in getattr(check, kind).items():
            if name not in m:
                out.append(f"{kind}.{name}: no such metric (this scene has: {', '.join(sorted(m))})")
                continue
            series = m[name][check.after - 1:]
            got = {"final": series[-1], "max": np.max(series, axis=0), "min": np.min(series, axis=0),
                   "mean": np.mean(series, axis=0)}[kind]
            bad = [f"run {r}: {v:.4g}" for r, v in enumerate(got) if not lo <= v <= hi]
            if bad:
                span = f"at step {check.steps}" if kind == "final" else f"over steps {check.after}-{check.steps}"
                out.append(f"{kind}.{name} should lie in [{lo:g}, {hi:g}] {span}; " + "; ".join(bad))
    return out


def lesson_check_failures(lesson: Lesson) -> list[str]:
    """Every failing check of every step of ``lesson``, naming lesson and step."""
    out = []
    for i, step in enumerate(lesson.steps):
        scene = lesson.scene(i)
        if scene is None or step.setup is None or step.setup.check is None:
            continue
        where = f"{lesson.id}.md, step {i + 1} '{step.title}' ({describe(*scene)})"
        out += [f"{where}: {msg}" for msg in check_failures(*scene, step.setup.check)]
    return out
