"""The scene kind's side of a session (:class:`Driver`).

The session owns what every kind shares (scenario, engine, lock, playback, history, timeline,
swarm B); a driver, one per session, knows its kind's engine: how to build it, which changes
need a new engine and which keywords of the engine's ``retune`` (its ``LIVE`` set) carry the
others to the running one, and what the app records, shows and exports of it.
"""

from __future__ import annotations

from typing import Any, Protocol

from shoal.presets.models import Scenario

from .history import Frame


class Driver(Protocol):
    @property
    def scene_sections(self) -> tuple[str, ...]:
        """Scenario sections drawn in the static scene (a change redraws it)."""
        ...

    def build(self, scenario: Scenario) -> Any:
        """The engine for ``scenario`` (run 0 only); :class:`PresetError` if it cannot be built."""
        ...

    def loaded(self) -> None:
        """A new engine is running (a load or a rebuild)."""
        ...

    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        """Does going from ``old`` to ``new`` need a new engine?"""
        ...

    def live(self, old: Scenario, new: Scenario) -> dict[str, Any]:
        """The keywords of the engine's ``retune`` that take the running engine from ``old`` to
        ``new`` (every field of its ``LIVE`` set; the engine keeps what did not change);
        :class:`PresetError` if ``new`` cannot be expressed."""
        ...

    def dt(self) -> float:
        """The time one step takes (the session's clock)."""
        ...

    def cleared(self) -> None:
        """The history was cleared (load, reset)."""
        ...

    def before_step(self) -> None: ...

    def frame(self, t: float) -> Frame:
        """Run 0's robots now, and the parts of the scene that may change while it runs
        (``Frame.scene``: a fleet's obstacles, a sonar's source)."""
        ...

    def metrics(self) -> dict[str, float]:
        """Run 0's metrics the app records beyond the engine's columns (none for most kinds)."""
        ...

    def snapshot(self, selected: int) -> dict[str, Any]:
        """The kind's part of a :class:`~.snapshot.Snapshot`: ``y``, ``yg``, ``ghosts``, ``extras``."""
        ...

    def recorded(self, frame: Frame) -> dict[str, Any]:
        """``extras`` to replace for a recorded frame: overlays that are not recorded blanked, the
        parts of the scene as they were then (``frame.scene``)."""
        ...

    def readout(self) -> dict[str, float]:
        """Numbers for the status line and the readouts."""
        ...

    def export_extra(self) -> dict[str, Any]:
        """More top-level entries for the JSON export."""
        ...

    def kept(self, scenario: Scenario) -> Scenario:
        """``scenario`` with what the user built by hand (obstacles, the source) in its fields, so a
        downloaded preset brings it back; :class:`PresetError` naming the field if they do not fit."""
        ...

