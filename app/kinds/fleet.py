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
import math
from typing import Any, Callable

import numpy as np

from shoal.engine.fleet import Fleet, FleetParams
from shoal.engine.fleet_probe import RobotView, robot_view
from shoal.engine.world import WorldSpec
from shoal.presets.build import build_fleet, fleet_params_for, world_for
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.beliefs import host_ghosts
from ..session.history import Frame
from ..session.positions import slo_retune
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view import shapes
from ..view.camera import VIEW_HALF
from ..view.canvas import Canvas
from ..view.layers import (
    Ghosts,
    GlobalBest,
    Headings,
    Layer,
    LegendEntry,
    PersonalBests,
    Robots,
    Static,
    Trails,
    Twin,
    metres,
)
from ..view.view import Home
from .base import AppKind, BaseDriver

OBSTACLE_RADIUS = 0.7  # m: a new obstacle's default radius
FOLLOW = ("world", "swarm", "robot")  # what the view keeps in the middle


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
        """A new fleet for another size, world or positions, or a robot model the fleet cannot
        change running (a :class:`FleetParams` field outside ``Fleet.LIVE``)."""
        a, b = fleet_params_for(old), fleet_params_for(new)
        fixed = {f.name for f in dataclasses.fields(FleetParams)} - Fleet.LIVE
        return (new.sim.robots != old.sim.robots or _changed(old, new, "world") or slo_retune(old, new) is None
                or any(getattr(a, f) != getattr(b, f) for f in fixed))

    def live(self, old: Scenario, new: Scenario) -> dict[str, Any]:
        params, slo = fleet_params_for(new), slo_retune(old, new)  # slo: the running fleet keeps its beliefs
        return {**{k: getattr(params, k) for k in Fleet.LIVE - {"slo"}}, **({"slo": slo} if slo else {})}

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


# ---------------------------------------------------------------------------- view
GRID_CELL = (228, 228, 224)
GRID_SECTION = (205, 205, 200)
WALL = (60, 60, 60)
OBSTACLE = (25, 30, 40)  # toon-lit meshes render lighter: this shows as slate grey
OBSTACLE_EDGE = (60, 68, 82)
START = (70, 120, 230)
SOURCE = (20, 150, 60)
LAYER = (150, 150, 150)
ROBOT = (220, 50, 50)
COLLIDED = (150, 150, 150)
HEADING = (90, 15, 15)
TRAIL = (110, 150, 255)
PBEST = (120, 120, 120)
GBEST = (240, 170, 0)
SELECTED = (255, 190, 0)
SECTOR_NEAR = np.array([215, 70, 20], float)  # lit meshes render lighter than these
SECTOR_FAR = np.array([70, 175, 70], float)
SECTOR_EDGE = (120, 130, 120)
HIT = (200, 80, 0)
FORCE = (130, 50, 200)
REACH_ATTRACT = (40, 90, 200)
REACH_TOTAL = (240, 140, 20)

# heights: later entries are drawn above earlier ones in the top view
Z = dict(grid=-0.025, start=-0.02, layers=-0.015, sectors=-0.01, trails=-0.005, obstacles=0.0,
         pbests=0.004, source=0.006, gbest=0.008, robots=0.01, headings=0.012, probe=0.014, hits=0.016)

PROBE_NODES = ("selected", "sectors", "sector_edges", "hits", "hit_lines", "force", "reach_attract", "reach_total")

ObstacleDrag = Callable[[int, float, float, str], None]  # (index, x, y, phase) in world metres


def _radius(canvas: Canvas, snap: Snapshot) -> float:
    """A robot's radius in scene units."""
    return snap.extras["params"].robot_radius * canvas.scale


class WorldLayer(Static):
    """The course: its grid, the start box, the walls, the obstacle layers and the source."""

    name = "world"
    keys = ("grid", "start", "start_edge", "walls", "layers", "source", "source_label")
    legend = (LegendEntry("■", START, "start box"), LegendEntry("—", LAYER, "obstacle layer"),
              LegendEntry("●", SOURCE, "source"))

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        world: WorldSpec = snap.extras["world"]
        sc = canvas.scene
        x0, y0, x1, y1 = world.bounds
        canvas.add("grid", sc.add_grid(
            canvas.name("grid"), width=(x1 - x0) * canvas.scale, height=(y1 - y0) * canvas.scale, plane="xy",
            cell_size=1.0 * canvas.scale, section_size=5.0 * canvas.scale, cell_color=GRID_CELL,
            section_color=GRID_SECTION, position=(0.0, 0.0, Z["grid"]), shadow_opacity=0.0, infinite_grid=False,
            fade_distance=1e4))
        bx0, by0, bx1, by1 = world.start_box
        box = np.array([[bx0, by0], [bx1, by0], [bx1, by1], [bx0, by1]])
        canvas.add("start", sc.add_mesh_simple(
            canvas.name("start"), canvas.to_view(box, Z["start"]), np.array([[0, 1, 2], [0, 2, 3]], np.uint32),
            color=START, opacity=0.18, material="toon3", side="double", cast_shadow=False, receive_shadow=False))
        canvas.lines("start_edge", shapes.polyline(box, closed=True), START, 1.5, Z["start"])
        canvas.lines("walls", np.asarray(world.walls), WALL, 3.0, Z["obstacles"])
        layers = [shapes.dashed((lx, y0), (lx, y1), 0.6, 0.6) for lx in world.layer_x]
        canvas.lines("layers", np.concatenate(layers) if layers else np.zeros((0, 2, 2)), LAYER, 1.2, Z["layers"])
        for i, lx in enumerate(world.layer_x):
            canvas.label(f"layer_label_{i}", f"layer {i + 1}", np.array([lx, y1 + 0.8]))
        src = np.asarray(world.source, dtype=float)
        canvas.points("source", src[None], SOURCE, 1.0 * canvas.scale, "circle", Z["source"])
        canvas.label("source_label", "source", src + (0.8, 0.8))


class Obstacles(Static):
    """Every obstacle as one instance of a disc mesh (a drag on it says which one), redrawn when
    the world changes; drag one to move it."""

    name = "obstacles"
    keys = ("obstacles", "obstacle_edges", "polygons")
    legend = (LegendEntry("●", (70, 78, 95), "obstacle"),)

    def __init__(self, on_drag: ObstacleDrag | None) -> None:
        self.on_drag = on_drag
        self._canvas: Canvas | None = None

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        self._canvas, self._revision, self._count = canvas, -1, -1

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        if snap.extras["world_revision"] == self._revision:
            return
        world: WorldSpec = snap.extras["world"]
        circles = world.circles
        node = canvas.nodes.get("obstacles")
        pos = canvas.to_view(circles[:, :2], Z["obstacles"])
        scales = (circles[:, 2] * canvas.scale).astype(np.float32)
        if len(circles) != self._count or node is None:  # count changed: a new node
            canvas.drop("obstacles")
            if len(circles):
                v, f = shapes.disc_mesh(40)
                node = canvas.add("obstacles", canvas.scene.add_batched_meshes_simple(
                    canvas.name("obstacles", fresh=True), v, f,
                    batched_wxyzs=np.tile([1.0, 0, 0, 0], (len(circles), 1)), batched_positions=pos,
                    batched_scales=scales, batched_colors=OBSTACLE, lod="off", material="toon3", side="double",
                    cast_shadow=False, receive_shadow=False))
                node.on_drag("left")(self.dragged)
            self._count = len(circles)
        else:
            node.batched_positions = pos
            node.batched_scales = scales
        rims = [shapes.circle_segments(c[:2], c[2], 40) for c in circles]
        canvas.lines("obstacle_edges", np.concatenate(rims) if rims else np.zeros((0, 2, 2)), OBSTACLE_EDGE, 1.2,
                     Z["obstacles"] + 0.001)
        canvas.drop("polygons")
        if world.polygons:
            verts, faces, base = [], [], 0
            for p in world.polygons:  # convex: a fan from vertex 0
                verts.append(canvas.to_view(p, Z["obstacles"]))
                faces += [(base, base + j, base + j + 1) for j in range(1, len(p) - 1)]
                base += len(p)
            canvas.add("polygons", canvas.scene.add_mesh_simple(
                canvas.name("polygons", fresh=True), np.vstack(verts), np.array(faces, np.uint32), color=OBSTACLE,
                material="toon3", side="double", cast_shadow=False, receive_shadow=False))
        self._revision = snap.extras["world_revision"]

    def dragged(self, event: Any) -> None:
        """viser's drag event on an obstacle: where the pointer is, in world metres."""
        if self.on_drag is None or event.instance_index is None or self._canvas is None:
            return
        xy = self._canvas.to_world(np.asarray(event.end_position, dtype=float)[:2])
        self.on_drag(int(event.instance_index), float(xy[0]), float(xy[1]), str(event.phase))


class Probe(Static):
    """The selected robot as its controller sees it: the six sectors filled out to each closest
    body, the range circle, the hits, F_t and the reach its budget allows in one step. Not on
    recorded frames (what a robot sensed is not recorded)."""

    name = "probe"
    keys = PROBE_NODES
    legend = (LegendEntry("○", SELECTED, "selected robot"), LegendEntry("■", (215, 70, 20), "sector (near: red)"),
              LegendEntry("◆", HIT, "closest hit"), LegendEntry("—", FORCE, "virtual force F_t"),
              LegendEntry("○", REACH_ATTRACT, "reach of c1 + c2"), LegendEntry("○", REACH_TOTAL, "reach of ĉ"))

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        if not snap.live:
            canvas.hide(*PROBE_NODES)
            return
        v, p = snap.extras["view"], snap.extras["params"]
        centre, radius, rng = v.x, p.robot_radius, p.sensing_range
        canvas.lines("selected", shapes.circle_segments(centre, 1.35 * radius, 40), SELECTED, 3.0, Z["probe"])
        start = v.frame_angle - math.pi + np.arange(6) * math.pi / 3  # sector k starts here
        node = canvas.nodes.get("sectors")
        frac = np.clip(v.gap / rng, 0.0, 1.0)
        colors = (SECTOR_NEAR + (SECTOR_FAR - SECTOR_NEAR) * frac[:, None]).astype(np.uint8)
        pos = np.repeat(canvas.to_view(centre[None], Z["sectors"]), 6, axis=0)
        scales = ((radius + v.gap) * canvas.scale).astype(np.float32)
        wxyz = shapes.yaw_wxyz(start)
        if node is None:
            vert, face = shapes.wedge_mesh(math.pi / 3, 12)
            canvas.add("sectors", canvas.scene.add_batched_meshes_simple(
                canvas.name("sectors"), vert, face, batched_wxyzs=wxyz, batched_positions=pos, batched_scales=scales,
                batched_colors=colors, opacity=0.45, lod="off", material="toon3",
                side="double", cast_shadow=False, receive_shadow=False))
        else:
            node.batched_positions, node.batched_wxyzs, node.batched_scales = pos, wxyz, scales
            if not np.array_equal(node.batched_colors, colors):
                node.batched_colors = colors
            node.visible = True
        edges = np.concatenate([shapes.circle_segments(centre, radius + rng, 72),
                                shapes.rays(centre, start, radius, radius + rng)])
        canvas.lines("sector_edges", edges, SECTOR_EDGE, 1.0, Z["probe"])
        hits = v.point[v.hit]
        canvas.points("hits", hits, HIT, 0.28 * canvas.scale, "diamond", Z["hits"])
        canvas.lines("hit_lines", np.stack([np.repeat(centre[None], len(hits), 0), hits], axis=1)
                     if len(hits) else np.zeros((0, 2, 2)), HIT, 1.0, Z["probe"])
        f = np.asarray(v.force, dtype=float)
        mag = float(np.hypot(*f))
        if mag > 1e-9 and not p.body_frame:
            length = (radius + rng) * mag / (mag + 1.0)  # saturating: γ/s = 1 reaches half the range
            canvas.lines("force", shapes.arrow(centre, f / mag * length), FORCE, 3.0, Z["probe"])
        else:
            canvas.lines("force", np.zeros((0, 2, 2)), FORCE, 3.0, Z["probe"])
        self._reach(canvas, snap)

    @staticmethod
    def _reach(canvas: Canvas, snap: Snapshot) -> None:
        """How far the budget can carry the selected robot in one step: omni, the attraction reach
        (c1+c2)√2/β·Δt (blue) and the total ĉ√2/β·Δt (orange); non-omni, the forward reach
        c5/β·Δt along the heading (blue). Not drawn for original RPSO, whose terms are unbounded."""
        v, p = snap.extras["view"], snap.extras["params"]
        c, centre, r = np.asarray(v.c, dtype=float), v.x, p.robot_radius
        attract, total = np.zeros((0, 2, 2)), np.zeros((0, 2, 2))
        if p.law == "adapted-rpso" and p.beta > 0:
            k = math.sqrt(2) / p.beta * p.dt
            attract = shapes.circle_segments(centre, r + k * (c[0] + c[1]), 56)
            total = shapes.circle_segments(centre, r + k * c[:3].sum(), 56)
        elif p.law == "nonomni" and p.beta > 0 and len(c) >= 5:
            reach = r + c[4] / p.beta * p.dt
            attract = shapes.rays(centre, np.array([v.heading]), r, reach)
        canvas.lines("reach_attract", attract, REACH_ATTRACT, 2.0, Z["probe"])
        canvas.lines("reach_total", total, REACH_TOTAL, 2.0, Z["probe"])


def _heading_angle(snap: Snapshot) -> np.ndarray:
    """Along the velocity, or the body's heading (body-frame laws, robots at rest)."""
    u = snap.extras["u"]
    speed = np.hypot(u[:, 0], u[:, 1])
    return np.where(snap.extras["params"].body_frame | (speed < 1e-9), snap.heading, np.arctan2(u[:, 1], u[:, 0]))


class FollowCamera:
    """The whole world (zoom 1), or a closer view (``follow``/``zoom`` of the snapshot) that
    follows the swarm's centre or the selected robot."""

    def __init__(self) -> None:
        self.zoom = 1.0
        self._followed: str | None = None  # follow mode of the last draw (a new one re-centres at once)

    def home(self, snap: Snapshot) -> Home:
        x0, y0, x1, y1 = snap.extras["world"].bounds
        zoom = float(snap.extras["zoom"])
        return Home(((x0 + x1) / 2, (y0 + y1) / 2), zoom * 2 * VIEW_HALF / max(x1 - x0, y1 - y0),
                    ((x1 - x0) / 2, (y1 - y0) / 2))

    def reset(self) -> None:
        self._followed = None

    def follow(self, canvas: Canvas, snap: Snapshot) -> None:
        follow, self.zoom = snap.extras["follow"], float(snap.extras["zoom"])
        if follow == "world" or self.zoom <= 1.0:
            target = canvas.centre
        elif follow == "robot":
            target = snap.extras["view"].x
        else:
            alive = snap.status == 0
            target = snap.x[alive].mean(axis=0) if alive.any() else snap.x.mean(axis=0)
            if self._followed == "swarm":  # a dead zone round the middle: no jitter step by step
                off = target - canvas.focus
                dead = 0.15 * VIEW_HALF / canvas.scale  # metres; VIEW_HALF/scale reaches the nearer edge
                target = canvas.focus + np.sign(off) * np.maximum(np.abs(off) - dead, 0.0)
        self._followed = follow
        x0, y0, x1, y1 = snap.extras["world"].bounds
        canvas.set_focus(np.clip(target, (x0, y0), (x1, y1)))


def layers(panels: Any) -> tuple[Layer, ...]:
    """The fleet's arena: the course and its obstacles (drag one to move it), the robots with
    their headings, trails and bests, the selected robot's sensing; swarm B, the beliefs."""
    return (
        WorldLayer(),
        Obstacles(panels.drag_obstacle if panels is not None else None),
        Robots(ROBOT, _radius, Z["robots"], collided=COLLIDED),
        Headings(HEADING, lambda canvas, snap: 1.3 * snap.extras["params"].robot_radius, Z["headings"],
                 angle=_heading_angle),
        Trails(TRAIL, 1.5, Z["trails"]),
        PersonalBests(PBEST, metres(0.25), Z["pbests"]),
        GlobalBest(GBEST, metres(0.75), Z["gbest"]),
        Probe(),
        Ghosts(_radius),
        Twin(_radius, (0.009, -0.006)),
    )


def accepts(scenario: Scenario) -> bool:
    return scenario.world is not None


def refuse(scenario: Scenario) -> None:
    if not accepts(scenario):
        raise PresetError([f"world: {scenario.name} has no [world]; it runs as a free-space swarm"])


KIND = AppKind(name="fleet", title="Chapter 4–5 fleet", priority=20, accepts=accepts, refuse=refuse,
               make_driver=FleetDriver, notes="ch4-5", layers=layers, camera=FollowCamera)


def driver(session: Session) -> FleetDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, FleetDriver), session.kind.name
    return session.driver
