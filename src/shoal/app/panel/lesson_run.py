"""The run on screen as a lesson step reads it (:mod:`shoal.app.lessons.readings`): the
session's recorded metric rows, by step, if the session shows the step's scene as *Set up*
loads it (the view's settings aside) and nothing was changed while it ran."""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..lessons.readings import Run
from ..lessons.scenes import load_scene
from ..lessons.verify import outside
from ..session.session import Session

NOT_THIS_SCENE = "the arena shows another scene than this step's: press Set up this step to read its numbers"
CHANGED = "the scene was changed while it ran: press Set up this step to read its numbers"
REPLAY = "a replay is shown: press Set up this step to read its numbers"


def same_scene(a: Scenario, b: Scenario) -> bool:
    """The same scene but for the view's settings (playback speed, trails)."""
    return a.model_dump(exclude={"view"}) == b.model_dump(exclude={"view"})


class LessonRun:
    """``measure`` of the Lessons tab for one session (the step's scenario cached)."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self._scenes: dict[str, Scenario | None] = {}
        self._outside: tuple[int, float, np.ndarray, np.ndarray] | None = None  # (epoch, half size, steps, counts)

    def _outside_by_step(self, half: float) -> tuple[np.ndarray, np.ndarray]:
        """Robots outside the arena at every recorded step (the lock held): worked out once a
        frame, for the frames recorded since the last call."""
        h = self.session.history
        kept = self._outside
        if kept is None or kept[0] != h.epoch or kept[1] != half:
            kept = (h.epoch, half, np.zeros(0, np.int64), np.zeros(0))
        steps, counts = kept[2], kept[3]
        new_steps, x = h.positions_after(int(steps[-1]) if len(steps) else -(2**62))
        if len(new_steps):
            steps = np.concatenate([steps, new_steps])
            counts = np.concatenate([counts, outside(x, half)])
        first = int(np.searchsorted(steps, h.ks[0])) if len(h.ks) else len(steps)
        self._outside = (h.epoch, half, steps[first:], counts[first:])
        return self._outside[2], self._outside[3]

    def _scene(self, preset: str, values: dict[str, Any]) -> Scenario | None:
        key = f"{preset} {sorted(values.items())!r}"
        if key not in self._scenes:
            try:
                self._scenes[key] = load_scene(preset, values)
            except PresetError:
                self._scenes[key] = None
        return self._scenes[key]

    def __call__(self, preset: str, values: dict[str, Any], names: tuple[str, ...]) -> Run | str:
        want = self._scene(preset, values)
        s = self.session
        with s.lock:
            if s.replaying is not None:
                return REPLAY
            if want is None or not same_scene(s.scenario, want):
                return NOT_THIS_SCENE
            if s.live_edits:
                return CHANGED
            columns = s.history.metric_arrays()
            k = s.k
            half = float(s.scenario.arena.half_size)
            by_step = self._outside_by_step(half) if "outside" in names and "outside" not in columns else None
        rows = len(columns.get("t", ()))
        steps = np.arange(k - rows + 1, k + 1)
        metrics = {name: columns[name] for name in names if name in columns}
        if by_step is not None:
            known, counts = by_step
            at = np.clip(np.searchsorted(known, steps), 0, max(len(known) - 1, 0))
            found = (at < len(known)) & (known[at] == steps) if len(known) else np.zeros(len(steps), bool)
            metrics["outside"] = np.where(found, counts[at] if len(known) else np.nan, np.nan)
        return Run(steps, metrics)
