"""Chapter 4–5 robots with bodies in an obstacle world (a :class:`Fleet`).

* changes: controller and sensing fields are :class:`FleetParams` fields and apply at the
  next step; the world, the robot model, the robot count and the oracle/SLO positions switch
  rebuild the fleet (robots back in the start box, world edits dropped); the SLO error set
  and localisation settings retune the running fleet;
* world edits: add, remove and move obstacles while the robots run (``Fleet.set_world``);
  they live in the running fleet only, since a preset describes its world by generator
  parameters;
* the selected robot's view: its sectors, hits, force and budget (``robot_view``).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from shoal.engine.fleet import Fleet, FleetParams
from shoal.engine.fleet_probe import RobotView, robot_view
from shoal.presets.build import build_fleet, fleet_params_for, world_for
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.beliefs import host_ghosts
from ..session.history import Frame
from ..session.positions import slo_retune
from ..session.session import Session
from .base import AppKind, BaseDriver

OBSTACLE_RADIUS = 0.7  # m: a new obstacle's default radius
FOLLOW = ("world", "swarm", "robot")  # what the view keeps in the middle
REBUILD_SECTIONS = ("world", "robot")  # changes here (and sim.robots, the positions switch) rebuild the fleet


class EditRefused(ValueError):
    """A world edit that would put an obstacle on a robot or outside the world."""


def _world_error(msg: str) -> str:
    """A world generator's message ("length: ...") named by its preset field ("world.length: ...")."""
    field, sep, rest = msg.partition(":")
    if not sep or " " in field:
        return f"world: {msg}"
    return f"world.{ {'size': 'width'}.get(field, field)}:{rest}"


def _changed(old: Scenario, new: Scenario, name: str) -> bool:
    a, b = getattr(old, name), getattr(new, name)
    return (a.model_dump() if a is not None else None) != (b.model_dump() if b is not None else None)


class FleetDriver(BaseDriver):
    """A fleet's side of a session, and the world edits made by hand."""

    metrics = ("com", "operational", "collided", "max_speed", "best")
    sim: Fleet

    def __init__(self, session: Session) -> None:
        super().__init__(session)
        self.world_revision = 0  # bumps whenever the obstacles change (redraw them)
        self.edits = 0  # world edits since the fleet was built
        self.obstacle_radius = OBSTACLE_RADIUS
        self.follow, self.zoom = "world", 1.0

    def build(self, scenario: Scenario) -> Fleet:
        try:
            return build_fleet(scenario, runs=1)
        except ValueError as err:  # the world generator refuses a combination the model allows
            raise PresetError([_world_error(str(err))]) from None

    def loaded(self) -> None:
        self.world_revision += 1
        self.edits = 0

    # ------------------------------------------------------------------ changes
    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        return (new.sim.robots != old.sim.robots or any(_changed(old, new, s) for s in REBUILD_SECTIONS)
                or slo_retune(old, new) is None)

    def retune(self, old: Scenario, new: Scenario) -> None:
        fleet = self.sim
        params = fleet_params_for(new)
        for f in dataclasses.fields(FleetParams):
            value = getattr(params, f.name)
            if getattr(fleet.params, f.name) != value:
                setattr(fleet.params, f.name, value)  # in force from the next step
        retune = slo_retune(old, new)
        if retune:  # errors, selection, neighbourhood…: the running fleet keeps its beliefs
            fleet.retune_slo(**retune)  # type: ignore[attr-defined]

    # ------------------------------------------------------------------ world edits
    def _world_changed(self) -> None:
        self.world_revision += 1
        self.edits += 1
        self.session.live_edits += 1
        self.session.revision += 1
        self._twin_world()

    def _twin_world(self) -> None:
        """Swarm B meets the same obstacles as A (the arena draws A's world)."""
        twin = self.session.twin
        if twin is not None:
            with twin.lock:
                twin.sim.set_world(self.sim.world)
                driver(twin).world_revision += 1

    def _check_free(self, x: float, y: float, r: float, what: str) -> None:
        fleet = self.sim
        x0, y0, x1, y1 = fleet.world.bounds
        if not (x0 < x < x1 and y0 < y < y1):
            raise EditRefused(f"{what}: ({x:.1f}, {y:.1f}) m is outside the world")
        gap = np.hypot(*(fleet.state.x[0] - (x, y)).T) - r - fleet.params.robot_radius
        if gap.size and gap.min() < 0.05:
            raise EditRefused(f"{what}: it would touch robot {int(np.argmin(gap))}")

    def add_obstacle(self, x: float, y: float, r: float | None = None) -> int:
        """Add a circle at (x, y) (default radius ``obstacle_radius``); returns its index.
        Raises :class:`EditRefused` on a robot or outside the world."""
        with self.session.lock:
            r = float(self.obstacle_radius if r is None else r)
            self._check_free(x, y, r, "add obstacle")
            world = self.sim.world.with_circle(float(x), float(y), r)
            self.sim.set_world(world)
            self._world_changed()
            return len(world.circles) - 1

    def remove_obstacle_near(self, x: float, y: float, tol: float = 1.0) -> int | None:
        """Remove the obstacle nearest (x, y) within ``tol`` m of its surface; its index or None."""
        with self.session.lock:
            i = self.sim.world.nearest_obstacle(x, y, tol)
            if i is not None:
                self.sim.set_world(self.sim.world.without_obstacle(i))
                self._world_changed()
            return i

    def nearest_obstacle(self, x: float, y: float, tol: float = 1.0) -> int | None:
        with self.session.lock:
            return self.sim.world.nearest_obstacle(x, y, tol)

    def move_obstacle(self, index: int, x: float, y: float) -> None:
        """Move obstacle ``index`` to (x, y). Raises :class:`EditRefused` on a robot or outside."""
        with self.session.lock:
            world = self.sim.world
            if not 0 <= index < world.n_obstacles:
                raise EditRefused(f"move obstacle: there is no obstacle {index}")
            r = float(world.circles[index, 2]) if index < len(world.circles) else 0.0
            self._check_free(x, y, r, "move obstacle")
            self.sim.set_world(world.moved_obstacle(index, float(x), float(y)))
            self._world_changed()

    def restore_world(self) -> None:
        """Drop the edits: the world the scenario generates, robots kept where they are."""
        with self.session.lock:
            self.sim.set_world(world_for(self.session.scenario.world))
            self.world_revision += 1
            self.edits = 0
            self._twin_world()
            self.session.revision += 1

    def robot_near(self, x: float, y: float, tol: float = 0.3) -> int | None:
        """The robot whose body is within ``tol`` m of (x, y), nearest first."""
        return self.session.robot_near(x, y, tol, body=self.sim.params.robot_radius)

    def set_view(self, follow: str, zoom: float) -> None:
        """What the arena keeps in the middle (``FOLLOW``) and how close (zoom ≥ 1)."""
        if follow not in FOLLOW:
            raise ValueError(f"follow: {follow!r} is not one of {FOLLOW}")
        with self.session.lock:
            self.follow, self.zoom = follow, float(min(max(zoom, 1.0), 20.0))
            self.session.revision += 1

    # ------------------------------------------------------------------ history and views
    def metric_row(self, info: Any) -> tuple[float, ...]:
        info = info if info is not None else self.sim.info()
        return (float(info.com_fitness[0]), float(info.operational[0]), float(info.collided[0]),
                float(info.max_speed[0]), float(info.best_fitness[0]))

    def view(self) -> RobotView:
        """The selected robot as its controller sees it now."""
        with self.session.lock:
            return robot_view(self.sim, min(self.session.selected_robot, self.sim.robots - 1))

    def snapshot(self, selected: int) -> dict[str, Any]:
        s = self.sim.state
        extras = dict(u=s.u[0].copy(), cmd=s.cmd[0].copy(), world_revision=self.world_revision, world=self.sim.world,
                      params=dataclasses.replace(self.sim.params), view=self.view(), follow=self.follow,
                      zoom=self.zoom if self.follow != "world" else 1.0)
        return {"y": s.y[0].copy(), "yg": s.yg[0].copy(), "ghosts": host_ghosts(self.sim, selected, s.yg[0]),
                "extras": extras}

    def recorded(self, frame: Frame) -> dict[str, Any]:
        zeros = np.zeros_like(frame.x)
        return {"u": zeros, "cmd": zeros}

    def readout(self) -> dict[str, float]:
        info = self.sim.info()
        return {
            "t": self.session.clock(), "k": float(self.sim.state.k), "com": float(info.com_fitness[0]),
            "operational": float(info.operational[0]), "collided": float(info.collided[0]),
            "layers_passed": float(info.layers_passed[0]), "layers": float(len(self.sim.world.layer_x)),
            "best": float(info.best_fitness[0]),
        }

    def export_extra(self) -> dict[str, Any]:
        w = self.sim.world
        return {"world": {"name": w.name, "circles": w.circles.tolist(), "edits": self.edits}}


def accepts(scenario: Scenario) -> bool:
    return scenario.world is not None


def refuse(scenario: Scenario) -> None:
    if not accepts(scenario):
        raise PresetError([f"world: {scenario.name} has no [world]; it runs as a free-space swarm"])


KIND = AppKind(name="fleet", title="Chapter 4–5 fleet", priority=20, accepts=accepts, refuse=refuse,
               make_driver=FleetDriver, notes="ch4-5")


def driver(session: Session) -> FleetDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, FleetDriver), session.kind.name
    return session.driver
