"""The one place the exporter meets the app: sessions and the arena view of a kind of scene.

An exported page is drawn by the view the app shows for that kind of scene (an object with
``rebuild(scenario, revision)``, ``draw(snapshot)`` and ``draw_twin(view)``) on a scene that
only records, so the page shows the layers the app draws. The frames come from either

* a seeded run (:func:`run_frames`): a fresh session of the preset steps on and every kept
  step is drawn as the app draws it while playing (bests, rays, sensing sectors, beliefs);
* a recorded history (:func:`recorded_frames`): the frames of a session's ring buffer (and
  of swarm B), drawn as the app's timeline shows them when scrubbing: robots, headings,
  collisions, trails and the static scene. What the app draws only live is not recorded.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator

import numpy as np

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..replay import Recording
from .frames import FramePlan

Twin = tuple[np.ndarray, np.ndarray] | None  # swarm B's robots and trails, as ``BaseSession.twin_view``
Drawn = tuple[Any, Twin]  # (snapshot, twin) of one kept step


def _kind(scenario: Scenario) -> Any:
    from ..tab import kind_for  # the tab module imports every panel: load it only when exporting

    return kind_for(scenario)


def new_session(scenario: Scenario) -> Any:
    """A fresh session of the kind ``scenario`` needs (refuses, like the app, what it cannot show)."""
    return _kind(scenario).session(scenario)


def new_view(scenario: Scenario, scene: Any) -> Any:
    """The arena view the app shows ``scenario`` in, on ``scene``, with its static scene built."""
    view = _kind(scenario).view(scene)
    view.rebuild(scenario, 0)
    return view


def draw_frame(view: Any, frame: Drawn) -> None:
    """One kept step, as the app's tab draws it."""
    snap, twin = frame
    view.draw(snap)
    view.draw_twin(twin)


def _last_step(session: Any) -> int:
    return session.timeline()[1]


def run_frames(session: Any, plan: FramePlan, on_steps: Callable[[int], None] | None = None) -> Iterator[Drawn]:
    """Step a fresh ``session`` (with swarm B if Compare is on) and yield the live snapshot at
    every kept step."""
    for k in plan.steps:
        while _last_step(session) < k:
            done = session.step(k - _last_step(session))
            if on_steps is not None:
                on_steps(done)
            if not done:
                raise PresetError([f"sim.steps: the run ends at step {_last_step(session)}, before step {k}"])
        yield session.shown_snapshot(), session.twin_view()


def replay_session(rec: Recording) -> Any:
    """A session showing ``rec`` (its embedded preset validated, its shape checked)."""
    try:
        scenario = presets_io.validate(rec.meta["preset"])
    except PresetError as err:
        raise PresetError([f"preset: {m}" for m in err.messages]) from None
    session = new_session(scenario)
    session.enter_replay(rec, (None, "exported"))  # refuses positions of another dimension
    return session


def recorded_frames(a: Any, b: Any | None, plan: FramePlan) -> Iterator[Drawn]:
    """The recorded frame of every kept step from replay sessions ``a`` and ``b`` (swarm B,
    drawn where it recorded that step)."""
    b_steps = {f.k for f in b.frames} if b is not None else set()
    for k in plan.steps:
        a.scrub(k)
        view_b: Twin = None
        if b is not None and k in b_steps:
            b.scrub(k)
            snap_b = b.shown_snapshot()
            view_b = (snap_b.x, snap_b.trails)
        yield a.shown_snapshot(), view_b


def session_recordings(session: Any) -> tuple[Recording, Recording | None, dict[str, Any]]:
    """A session's recorded history, swarm B's (None without B) and B's overrides."""
    with session.lock:
        twin = session.twin
        return session.recording(), (twin.recording() if twin is not None else None), dict(session.overrides)
