"""A take-over's state: the lecture's run as bytes that a private session starts from.

:func:`capture` takes, under the session's lock, what the next steps depend on and what the
app adds on top of the engine:

- the engine's own snapshot (``sim.snapshot()``: step, positions, velocities, bests, every
  random stream, a fleet's world as edited, a sonar's source; :mod:`shoal.engine.core.snapshot`),
  and swarm B's when Compare is on, with its overrides;
- the scenario as edited (validated again on the way in), the session's clock, what happens at
  the last step, playing or paused, the selected robot, and where the lecture's Lessons tab is.

The recorded history is not carried: the private session's plots and trails start at the step
taken over (a take-over is a fresh run from that state, and its bytes stay small).

The bytes are one ``.npz`` archive with a JSON header (``engine.core.snapshot.to_bytes``): no
pickle, nothing named to import. They travel from the lecture's process to a worker's through
the desk (:mod:`.desk`, :mod:`.channel`), never through a client. :func:`restore` builds the
private session from them; :func:`snapshot_bytes` gives A's part as a snapshot that
``shoal.make(snapshot=...)`` reads, so a headless run can go on from the same state.
"""

from __future__ import annotations

from typing import Any

from shoal import __version__
from shoal.engine.core.snapshot import SnapshotError, from_bytes, to_bytes
from shoal.presets.io import PresetError, validate
from shoal.presets.models import Scenario

from ..kinds.registry import app_kind, session_for
from ..lessons.panel import LessonProgress
from ..session.session import Session

FORMAT = "shoal-takeover"
VERSION = 1


class CannotTakeOver(Exception):
    """The run cannot be handed over now, or the bytes are no take-over; the message says why."""


def _engine(session: Session) -> dict[str, Any]:
    take = getattr(session.sim, "snapshot", None)
    if take is None:
        raise CannotTakeOver(f"the {type(session.sim).__name__} engine of this scene offers no snapshot")
    return dict(take())


def _app_scenario(session: Session) -> Scenario:
    """The scenario of the engine the app runs (run 0 alone)."""
    sc = session.scenario
    return sc if sc.sim.runs == 1 else sc.model_copy(update={"sim": sc.sim.model_copy(update={"runs": 1})})


def capture(session: Session, lessons: LessonProgress | None = None) -> bytes:
    """The state of ``session`` now as a take-over's bytes (:class:`CannotTakeOver` when there is
    none to hand over: a replay on screen, an engine without a snapshot)."""
    with session.lock:
        if session.replaying is not None:
            raise CannotTakeOver("the lecture shows a replay, not a live run: take over once it runs live")
        if session.timeline.cursor is not None:
            raise CannotTakeOver("the lecture shows a recorded step: take over once it is back at the live step")
        twin = session.twin
        header = {
            "takeover": FORMAT, "version": VERSION, "shoal": __version__, "kind": session.kind.name,
            "engine": app_kind(session).engine,
            "k": session.k, "t": session.clock(), "scenario": _app_scenario(session).model_dump(mode="json"),
            "at_end": session.at_end, "playing": session.playing, "selected": session.selected_robot,
            "dim": session.selected_dim, "compare": dict(session.overrides) if twin is not None else None,
            "lesson": (lessons.lesson, lessons.step) if lessons is not None else None,
        }
        data = {"a": _engine(session), "b": _engine(twin) if twin is not None else None}
        try:
            return to_bytes(header, data)
        except TypeError as err:
            raise CannotTakeOver(f"this run's state cannot be written: {err}") from None


def _read(state: bytes) -> tuple[dict[str, Any], dict[str, Any]]:
    try:
        header, data = from_bytes(state)
    except SnapshotError as err:
        raise CannotTakeOver(f"not a take-over: {err}") from None
    if header.get("takeover") != FORMAT or header.get("version") != VERSION:
        raise CannotTakeOver("not a take-over of this Shoal")
    if not isinstance(data, dict) or not isinstance(data.get("a"), dict):
        raise CannotTakeOver("a take-over without its run")
    return header, data


def restore(state: bytes) -> tuple[Session, bool]:
    """The private session a take-over's bytes start, and whether it plays."""
    header, data = _read(state)
    try:
        scenario = validate(header["scenario"])
        session = session_for(scenario)
        at_end = header.get("at_end")
        if isinstance(at_end, str):
            session.choose_at_end(at_end)
        overrides = header.get("compare")
        if isinstance(overrides, dict):
            session.enable_compare(overrides)
        t = float(header.get("t", 0.0))
        with session.lock:
            session.resume(data["a"], t)
            twin = session.twin
            if twin is not None and isinstance(data.get("b"), dict):
                twin.resume(data["b"], t)
            session.select(int(header.get("selected", 0)))
            session.selected_dim = min(max(int(header.get("dim", 0)), 0), scenario.sim.d - 1)
    except (PresetError, SnapshotError, KeyError, TypeError, ValueError) as err:
        raise CannotTakeOver(f"this take-over cannot start here: {err}") from None
    if session.kind.name != header.get("kind") or session.k != int(header.get("k", -1)):
        raise CannotTakeOver(f"the take-over's {session.kind.name} engine is at step {session.k}, its header says a "
                             f"{header.get('kind')} one at {header.get('k')}")
    return session, bool(header.get("playing", False))


def lesson_of(state: bytes) -> LessonProgress | None:
    """Where the lecture's Lessons tab was when this take-over was made (None: not said)."""
    header, _ = _read(state)
    where = header.get("lesson")
    if not isinstance(where, (list, tuple)) or len(where) != 2:
        return None
    lesson, step = where
    return LessonProgress(lesson=lesson if isinstance(lesson, str) else None,
                          step=step if isinstance(step, int) and not isinstance(step, bool) else 0)


def snapshot_bytes(state: bytes) -> bytes:
    """Swarm A of a take-over as the bytes of a ``shoal.make(snapshot=...)`` snapshot (the same
    scenario, kind, step and engine state; no metric rows)."""
    header, data = _read(state)
    return to_bytes({"shoal": header.get("shoal", __version__), "kind": header["engine"], "k": header["k"],
                     "scenario": header["scenario"]}, {"engine": data["a"], "rows": None})
