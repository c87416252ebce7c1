"""The one place the exporter meets the app: sessions and the arena view of a kind of scene.

An exported page is drawn by the view the app shows for that kind of scene (``rebuild``,
``draw(snapshot)``) on a scene that only records, so the page shows the layers the app draws.
The frames come from either

* a seeded run (:func:`run_frames`): a fresh session of the preset steps on and every kept
  step is drawn as the app draws it while playing (bests, rays, sensing sectors, beliefs);
* a recording (:func:`recorded_frames`): a session's ring buffer or a replay file, shown in a
  replay session and drawn as the app's timeline shows it: robots, headings, collisions,
  trails, swarm B, the obstacles and the source as they were at that step, and the static
  scene. What the app draws only live is not recorded.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..kinds.registry import kind_for
from ..replay import Recording
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view.view import View
from .frames import FramePlan


def new_session(scenario: Scenario) -> Session:
    """A fresh session of the kind ``scenario`` needs (refuses, like the app, what it cannot show)."""
    return kind_for(scenario).session(scenario)


def new_view(scenario: Scenario, scene: Any) -> View:
    """The arena view the app shows ``scenario`` in, on ``scene`` (nothing to drag on a page)."""
    view = kind_for(scenario).view(scene, None)
    view.rebuild(0)
    return view


def draw_frame(view: View, frame: Snapshot) -> None:
    """One kept step (swarm B with it), as the app's tab draws it."""
    view.draw(frame)


def _last_step(session: Session) -> int:
    return session.timeline_span()[1]


def run_frames(session: Session, plan: FramePlan, on_steps: Callable[[int], None] | None = None
               ) -> Iterator[Snapshot]:
    """Step a fresh ``session`` (with swarm B if Compare is on) and yield the live snapshot at
    every kept step (past the preset's last step too: the run being shared may have run on)."""
    for k in plan.steps:
        if _last_step(session) < k:
            done = session.advance(k - _last_step(session))
            if on_steps is not None:
                on_steps(done)
        yield session.shown_snapshot()


def replay_session(rec: Recording) -> Session:
    """A session showing ``rec`` (its embedded preset validated, its shape checked)."""
    try:
        scenario = presets_io.validate(rec.meta["preset"])
    except PresetError as err:
        raise PresetError([f"preset: {m}" for m in err.messages]) from None
    session = new_session(scenario)
    session.enter_replay(rec, (None, "exported"))  # refuses positions of another dimension
    return session


def recorded_frames(session: Session, plan: FramePlan) -> Iterator[Snapshot]:
    """The recorded frame of every kept step of a replay ``session``, as its timeline shows it:
    the robots, swarm B where it recorded that step, the obstacles and the source as they were."""
    for k in plan.steps:
        session.scrub(k)
        yield session.shown_snapshot()
