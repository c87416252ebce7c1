"""The Chapter 4–5 session: robots with bodies in an obstacle world (a :class:`Fleet`).

Playback, history and export come from :class:`BaseSession`. Here:

* changes: controller and sensing fields are :class:`FleetParams` fields and apply at the
  next step; the world, the robot model, the robot count and the oracle/SLO positions switch
  rebuild the fleet (robots back in the start box, world edits dropped); the SLO error set
  and localisation settings retune the running fleet (:mod:`.positions`);
* world edits: add, remove and move obstacles while the robots run (``Fleet.set_world``);
  they live in the running fleet only, since a preset describes its world by generator
  parameters;
* the selected robot's view: its sectors, hits, force and budget (``robot_view``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from shoal.engine.kinds.fleet import Fleet, FleetParams
from shoal.engine.kinds.fleet_probe import RobotView, robot_view
from shoal.engine.robots.world import WorldSpec
from shoal.presets.build import build_fleet, fleet_params_for, world_for
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .base_session import BaseSession
from .ghosts import Ghosts, host_ghosts
from .positions import slo_retune
from .session import check_supported

OBSTACLE_RADIUS = 0.7  # m: a new obstacle's default radius
FOLLOW = ("world", "swarm", "robot")  # what the view keeps in the middle
REBUILD_SECTIONS = ("world", "robot")  # changes here (and sim.robots, the positions switch) rebuild the fleet


class EditRefused(ValueError):
    """A world edit that would put an obstacle on a robot or outside the world."""


@dataclass(frozen=True)
class FleetSnapshot:
    """A consistent copy of what the fleet view draws, taken under the lock."""

    k: int
    t: float
    x: np.ndarray  # (N, 2)
    heading: np.ndarray  # (N,)
    u: np.ndarray  # (N, 2) realised velocity
    cmd: np.ndarray  # (N, 2) controller state: global u, or body-frame [v, w]
    status: np.ndarray  # (N,) 0 active, 1 collided
    y: np.ndarray  # (N, 2) personal bests
    yg: np.ndarray  # (2,) global best
    trails: np.ndarray  # (M, L, 2)
    revision: int
    world_revision: int
    world: WorldSpec  # obstacles as they are now (edits included)
    params: FleetParams  # a copy: robot radius, sensing range, law, α, β, Δt
    view: RobotView  # the selected robot
    follow: str = "world"  # one of FOLLOW
    zoom: float = 1.0  # 1 = the whole world on screen
    live: bool = True  # False: a recorded frame (timeline, replay): no bests, no sensing view
    ghosts: Ghosts | None = None  # the selected robot's beliefs (SLO positions)


def _changed(old: Scenario, new: Scenario, name: str) -> bool:
    a, b = getattr(old, name), getattr(new, name)
    return (a.model_dump() if a is not None else None) != (b.model_dump() if b is not None else None)


class FleetSession(BaseSession):
    """Fleet, world edits and playback state of one browser tab running a Chapter 4–5 scene."""

    METRICS = ("t", "com", "operational", "collided", "max_speed", "best")
    NOTES = "ch4-5"

    def __init__(self, scenario: Scenario) -> None:
        self.world_revision = 0  # bumps whenever the obstacles change (redraw them)
        self.edits = 0  # world edits since the fleet was built
        self.obstacle_radius = OBSTACLE_RADIUS
        self.follow, self.zoom = "world", 1.0
        super().__init__(scenario)

    sim: Fleet

    @property
    def fleet(self) -> Fleet:
        return self.sim

    @classmethod
    def accepts(cls, scenario: Scenario) -> bool:
        return scenario.world is not None

    @classmethod
    def check(cls, scenario: Scenario) -> Scenario:
        check_supported(scenario)
        if not cls.accepts(scenario):
            raise PresetError([f"world: {scenario.name} has no [world]; it runs as a free-space swarm"])
        return scenario

    def _build(self, scenario: Scenario) -> Fleet:
        return build_fleet(scenario, runs=1)  # (a world the generator cannot lay out: PresetError by field)

    def _load(self, scenario: Scenario) -> None:
        super()._load(scenario)
        self.world_revision += 1
        self.edits = 0

    # ------------------------------------------------------------------ changes
    def rebuilds(self, new: Scenario) -> bool:
        """Does going to ``new`` rebuild the fleet (rather than change it at the next step)?"""
        old = self.scenario
        return (new.sim.robots != old.sim.robots or any(_changed(old, new, s) for s in REBUILD_SECTIONS)
                or slo_retune(old, new) is None)

    def _adopt(self, new: Scenario) -> None:
        if self.rebuilds(new):
            self._load(new)  # builds first: a refused world leaves everything as it was
            self.selected_robot = min(self.selected_robot, new.sim.robots - 1)
            self.revision += 1
            return
        old, fleet = self.scenario, self.sim
        params = fleet_params_for(new)
        if params.dt != fleet.params.dt:
            self._keep_clock()
        retune = slo_retune(old, new)  # errors, selection, neighbourhood…: the running fleet keeps its beliefs
        fleet.retune(**{k: getattr(params, k) for k in fleet.LIVE - {"slo"}}, **({"slo": retune} if retune else {}))
        self.scenario = new  # in force from the next step
        if new.sim.seed != old.sim.seed:
            self._reset_locked(new.sim.seed)
        self.revision += 1

    # ------------------------------------------------------------------ world edits
    def _world_changed(self) -> None:
        self.world_revision += 1
        self.edits += 1
        self.revision += 1
        self._twin_world()

    def _twin_world(self) -> None:
        """Swarm B meets the same obstacles as A (the arena draws A's world)."""
        if self.twin is not None:
            with self.twin.lock:
                self.twin.sim.set_world(self.sim.world)
                self.twin.world_revision += 1

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
        with self.lock:
            r = float(self.obstacle_radius if r is None else r)
            self._check_free(x, y, r, "add obstacle")
            world = self.sim.world.with_circle(float(x), float(y), r)
            self.sim.set_world(world)
            self._world_changed()
            return len(world.circles) - 1

    def remove_obstacle_near(self, x: float, y: float, tol: float = 1.0) -> int | None:
        """Remove the obstacle nearest (x, y) within ``tol`` m of its surface; its index or None."""
        with self.lock:
            i = self.sim.world.nearest_obstacle(x, y, tol)
            if i is not None:
                self.sim.set_world(self.sim.world.without_obstacle(i))
                self._world_changed()
            return i

    def nearest_obstacle(self, x: float, y: float, tol: float = 1.0) -> int | None:
        with self.lock:
            return self.sim.world.nearest_obstacle(x, y, tol)

    def move_obstacle(self, index: int, x: float, y: float) -> None:
        """Move obstacle ``index`` to (x, y). Raises :class:`EditRefused` on a robot or outside."""
        with self.lock:
            world = self.sim.world
            if not 0 <= index < world.n_obstacles:
                raise EditRefused(f"move obstacle: there is no obstacle {index}")
            r = float(world.circles[index, 2]) if index < len(world.circles) else 0.0
            self._check_free(x, y, r, "move obstacle")
            self.sim.set_world(world.moved_obstacle(index, float(x), float(y)))
            self._world_changed()

    def restore_world(self) -> None:
        """Drop the edits: the world the scenario generates, robots kept where they are."""
        with self.lock:
            self.sim.set_world(world_for(self.scenario.world))
            self.world_revision += 1
            self.edits = 0
            self._twin_world()
            self.revision += 1

    def robot_near(self, x: float, y: float, tol: float = 0.3) -> int | None:
        """The robot whose body is within ``tol`` m of (x, y), nearest first."""
        with self.lock:
            d = np.hypot(*(self.sim.state.x[0] - (x, y)).T) - self.sim.params.robot_radius
            return int(np.argmin(d)) if d.size and d.min() <= tol else None

    def set_view(self, follow: str, zoom: float) -> None:
        """What the arena keeps in the middle (``FOLLOW``) and how close (zoom ≥ 1)."""
        if follow not in FOLLOW:
            raise ValueError(f"follow: {follow!r} is not one of {FOLLOW}")
        with self.lock:
            self.follow, self.zoom = follow, float(min(max(zoom, 1.0), 20.0))
            self.revision += 1

    # ------------------------------------------------------------------ history and views
    def _metric_row(self, info: Any) -> tuple[float, ...]:
        info = info if info is not None else self.sim.info()
        return (self.clock(), float(info.com_fitness[0]), float(info.operational[0]), float(info.collided[0]),
                float(info.max_speed[0]), float(info.best_fitness[0]))

    def view(self) -> RobotView:
        """The selected robot as its controller sees it now."""
        with self.lock:
            return robot_view(self.sim, min(self.selected_robot, self.sim.robots - 1))

    def snapshot(self, max_trails: int = 80, max_trail_points: int = 40) -> FleetSnapshot:
        with self.lock:
            s = self.sim.state
            return FleetSnapshot(
                k=s.k, t=self.clock(), x=s.x[0].copy(), heading=s.heading[0].copy(), u=s.u[0].copy(),
                cmd=s.cmd[0].copy(),
                status=s.status[0].copy(), y=s.y[0].copy(), yg=s.yg[0].copy(),
                trails=self.trails(max_trails, max_trail_points), revision=self.revision,
                world_revision=self.world_revision, world=self.sim.world,
                params=dataclasses.replace(self.sim.params), view=self.view(), follow=self.follow,
                zoom=self.zoom if self.follow != "world" else 1.0,
                ghosts=host_ghosts(self.sim, min(self.selected_robot, self.sim.robots - 1), s.yg[0]),
            )

    def _replay_blanks(self, frame: Any) -> dict[str, Any]:
        zeros = np.zeros_like(frame.x)
        return {"status": frame.status.copy(), "u": zeros, "cmd": zeros, "y": frame.x.copy()}

    def readout(self) -> dict[str, float]:
        with self.lock:
            info = self.sim.info()
            return {
                "t": self.clock(), "k": float(self.sim.state.k), "com": float(info.com_fitness[0]),
                "operational": float(info.operational[0]), "collided": float(info.collided[0]),
                "layers_passed": float(info.layers_passed[0]), "layers": float(len(self.sim.world.layer_x)),
                "best": float(info.best_fitness[0]),
            }

    def export_extra(self) -> dict[str, Any]:
        w = self.sim.world
        return {"world": {"name": w.name, "circles": w.circles.tolist(), "edits": self.edits}}
