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
            frames = list(s.history.frames) if "outside" in names and "outside" not in columns else []
            half = float(s.scenario.arena.half_size)
        rows = len(columns.get("t", ()))
        steps = np.arange(k - rows + 1, k + 1)
        metrics = {name: columns[name] for name in names if name in columns}
        if frames:
            by_step = {f.k: f.x for f in frames}
            metrics["outside"] = np.array([outside(by_step[j], half) if j in by_step else np.nan
                                           for j in steps.tolist()])
        return Run(steps, metrics)
