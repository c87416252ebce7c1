"""What a click or a drag in the arena does to a fleet: select a robot, add, remove or move an
obstacle. The robots react at the next step (``Fleet.set_world`` under the session lock).

Clicks: near a robot → select it; shift- or ctrl-click → remove the nearest obstacle;
otherwise the mode decides (add an obstacle, remove one, pick one and then click where it
goes, or only select robots). Dragging an obstacle moves it while the robots run.
"""

from __future__ import annotations

from typing import Callable, Protocol

MODES = ("add obstacle", "remove obstacle", "move obstacle", "select robot")
REMOVE_MODIFIERS = ("shift", "cmd/ctrl")
PICK_TOL = 1.0  # m from an obstacle's surface
ROBOT_TOL = 0.3  # m from a robot's body

Notify = Callable[[str, str, str], None]


class EditRefused(ValueError):
    """A world edit that would put an obstacle on a robot or outside the world."""


class World(Protocol):
    """The edits a fleet's session offers (:class:`~.fleet.FleetDriver`)."""

    def add_obstacle(self, x: float, y: float, r: float | None = None) -> int: ...

    def remove_obstacle_near(self, x: float, y: float, tol: float = 1.0) -> int | None: ...

    def nearest_obstacle(self, x: float, y: float, tol: float = 1.0) -> int | None: ...

    def move_obstacle(self, index: int, x: float, y: float) -> None: ...

    def robot_near(self, x: float, y: float, tol: float = 0.3) -> int | None: ...


class WorldEditor:
    """Clicks and drags in a fleet's arena, for one panel (``world``: the fleet's edits)."""

    def __init__(self, world: World, notify: Notify, select: Callable[[int], None]) -> None:
        self.world, self.notify, self.select = world, notify, select
        self.picked: int | None = None  # "move" mode: the obstacle waiting for its new place
        self._drag_refused: str | None = None

    def click(self, x: float, y: float, modifier: str | None, mode: str) -> str:
        """Handle a click at world (x, y); returns what it did (for tests and the status line)."""
        s = self.world
        if modifier in REMOVE_MODIFIERS or mode == "remove obstacle":
            i = s.remove_obstacle_near(x, y, PICK_TOL)
            if i is None:
                self.notify("Nothing to remove", f"no obstacle within {PICK_TOL:g} m of ({x:.1f}, {y:.1f})", "yellow")
                return "none"
            self.picked = None
            return "removed"
        if mode == "move obstacle":
            return self._move_click(x, y)
        robot = s.robot_near(x, y, ROBOT_TOL)
        if robot is not None:
            self.select(robot)
            return "selected"
        if mode != "add obstacle":
            return "none"
        if s.nearest_obstacle(x, y, 0.0) is not None:
            self.notify("That is an obstacle", "drag it to move it; shift- or ctrl-click removes it", "blue")
            return "none"
        try:
            s.add_obstacle(x, y)
        except EditRefused as err:
            self.notify("Refused", str(err), "red")
            return "refused"
        return "added"

    def _move_click(self, x: float, y: float) -> str:
        s = self.world
        if self.picked is None:
            self.picked = s.nearest_obstacle(x, y, PICK_TOL)
            if self.picked is None:
                robot = s.robot_near(x, y, ROBOT_TOL)
                if robot is not None:
                    self.select(robot)
                    return "selected"
                return "none"
            self.notify("Obstacle picked", "now click where it should go", "blue")
            return "picked"
        try:
            s.move_obstacle(self.picked, x, y)
        except EditRefused as err:
            self.notify("Refused", str(err), "red")
            return "refused"
        self.picked = None
        return "moved"

    def drag(self, index: int, x: float, y: float, phase: str) -> None:
        """An obstacle dragged to (x, y): it follows the pointer wherever it does not touch a robot."""
        if phase == "start":
            self._drag_refused = None
            return
        try:
            self.world.move_obstacle(index, x, y)
            self._drag_refused = None
        except EditRefused as err:
            self._drag_refused = str(err)
        if phase == "end" and self._drag_refused:
            self.notify("Stopped short", self._drag_refused, "yellow")
