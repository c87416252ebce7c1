"""Chapter 4–5 robots with bodies in an obstacle world (a :class:`Fleet`).

* changes (the kind's live rule, presets/kinds.py): controller and sensing fields apply at the
  next step; the world, the robot model, the robot count and the oracle/SLO positions switch
  rebuild the fleet (robots back in the start box, world edits dropped); the SLO error set
  and localisation settings retune the running fleet;
* world edits: add, remove and move obstacles while the robots run (``Fleet.set_world``);
  a downloaded preset keeps them in ``world.obstacles`` (``kept``);
* the selected robot's view: its sectors, hits, force and budget (``robot_view``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable

import numpy as np

from shoal.engine.kinds.fleet import STALL_STEPS, Fleet
from shoal.engine.kinds.fleet_probe import RobotView, robot_view
from shoal.engine.robots.dvc import TABLE_4_1
from shoal.engine.robots.laws import ROBOT_LAWS
from shoal.engine.robots.world import WorldSpec
from shoal.presets.builders.fleet import build_fleet
from shoal.presets.builders.world import check_world, world_for
from shoal.presets.io import PresetError, kept_fields
from shoal.presets.kinds import kind_of
from shoal.presets.models import Scenario, required

from ..markdown import escape
from ..panel.panel import TRAIL_SLIDER
from ..panel.plots import Line, PlotSpec, Series
from ..panel.positions import positions_choices, positions_folder
from ..panel.selection import robot_number
from ..panel.spec import (
    Button,
    Checkbox,
    Dropdown,
    Folder,
    KindPanel,
    Number,
    PanelAPI,
    Slider,
    Tab,
    Text,
    fmt,
    round_sig,
)
from ..session.history import Frame
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view import shapes
from ..view.camera import VIEW_HALF
from ..view.canvas import Canvas
from ..view.layers import (
    GRID_KEYS,
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
    draw_grid,
    metres,
)
from ..view.view import Home
from .base import AppKind, BaseDriver
from .fleet_budget import budget_markdown
from .fleet_world import MODES as CLICK_MODES
from .fleet_world import EditRefused, WorldEditor

OBSTACLE_RADIUS = 0.7  # m: a new obstacle's default radius
FOLLOW = ("world", "swarm", "robot")  # what the view keeps in the middle


class FleetDriver(BaseDriver):
    """A fleet's side of a session, and the world edits made by hand."""

    sim: Fleet

    def __init__(self, session: Session) -> None:
        super().__init__(session)
        self.world_revision = 0  # bumps whenever the obstacles change (redraw them)
        self.edits = 0  # world edits since the fleet was built
        self.dropped = 0  # the edits the last rebuild dropped
        self.obstacle_radius = OBSTACLE_RADIUS
        self.follow, self.zoom = "world", 1.0
        self._recorded: tuple[np.ndarray, WorldSpec] | None = None  # recorded circles → their world

    def build(self, scenario: Scenario) -> Fleet:
        return build_fleet(scenario, runs=1)  # (a world the generator cannot lay out: PresetError by field)

    def loaded(self) -> None:
        self.world_revision += 1
        self.dropped, self.edits = self.edits, 0

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
        """Drop the edits: the world the scenario describes, robots kept where they are."""
        with self.session.lock:
            self.sim.set_world(world_for(required(self.session.scenario.world, "world")))
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

    # ------------------------------------------------------------------ views
    def view(self) -> RobotView:
        """The selected robot as its controller sees it now."""
        with self.session.lock:
            return robot_view(self.sim, min(self.session.selected_robot, self.sim.robots - 1))

    def snapshot(self, selected: int) -> dict[str, Any]:
        s = self.sim.state
        extras = dict(u=s.u[0].copy(), cmd=s.cmd[0].copy(), stalled=s.slow[0] >= STALL_STEPS,
                      world_revision=self.world_revision, world=self.sim.world,
                      params=dataclasses.replace(self.sim.params), view=self.view(), follow=self.follow,
                      zoom=self.zoom if self.follow != "world" else 1.0)
        return {"y": s.y[0].copy(), "yg": s.yg[0].copy(), "ghosts": self.ghosts(selected, s.yg[0]),
                "extras": extras}

    def scene(self) -> dict[str, Any]:
        return {"obstacles": self.sim.world.circles}  # read-only, and the same array until the world changes

    def recorded(self, frame: Frame) -> dict[str, Any]:
        """No velocities or commands; the obstacles as they were (a world of the recorded circles,
        redrawn when they differ from what was drawn)."""
        zeros = np.zeros_like(frame.x)
        out: dict[str, Any] = {"u": zeros, "cmd": zeros}
        circles = frame.scene.get("obstacles")
        if circles is not None:
            if self._recorded is None or self._recorded[0] is not circles:
                self._recorded = (circles, dataclasses.replace(self.sim.world, circles=circles))
            out.update(world=self._recorded[1], world_revision=("recorded", circles.tobytes()))
        return out

    def readout(self) -> dict[str, float]:
        info = self.sim.info()
        return {
            "t": self.session.clock(), "k": float(self.sim.state.k), "com": float(info.com_fitness[0]),
            "operational": float(info.operational[0]), "collided": float(info.collided[0]),
            "stalled": float(info.stalled[0]), "layers_passed": float(info.layers_passed[0]),
            "layers": float(len(self.sim.world.layer_x)), "best": float(info.best_fitness[0]),
        }

    def export_extra(self) -> dict[str, Any]:
        w = self.sim.world
        return {"world": {"name": w.name, "circles": w.circles.tolist(), "edits": self.edits}}

    def kept(self, scenario: Scenario) -> Scenario:
        """The obstacles as edited by hand in ``world.obstacles`` (unchanged without edits)."""
        if not self.edits or scenario.world is None:
            return scenario
        return check_world(kept_fields(scenario, "world", obstacles=self.sim.world.circles.tolist()))


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
STALLED = (255, 120, 0)
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

# A stalled robot's ring is a few pixels across, redrawn with every update for hundreds of robots
# in a packed fleet: an octagon (each segment is a few triangles a frame for a software renderer).
STALLED_RING_SEGMENTS = 8


class Stalled(Static):
    """A ring round each running robot that has barely moved for a while (squeezed between bodies
    it may not approach: the engine's ``stalled``); not on recorded frames."""

    name = "stalled"
    keys = ("stalled", "stalled_dots")
    legend = (LegendEntry("○", STALLED, "stalled robot (barely moving)"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        stalled = snap.extras.get("stalled")
        x = snap.x[stalled] if stalled is not None else np.zeros((0, 2))
        r = 1.6 * snap.extras["params"].robot_radius
        if canvas.light:  # a disc under the robot, showing round it as a ring
            canvas.hide("stalled")
            canvas.points("stalled_dots", x, STALLED, 2 * r * canvas.scale, "circle", Z["robots"] - 0.001)
            return
        canvas.hide("stalled_dots")
        ring = shapes.circle_segments(np.zeros(2), r, STALLED_RING_SEGMENTS)
        segs = (ring[None] + shapes.plane(x)[:, None, None, :]).reshape(-1, 2, 2)
        canvas.lines("stalled", segs, STALLED, 2.5, Z["robots"] + 0.001)


PROBE_NODES = ("selected", "sectors", "sector_edges", "hits", "hit_lines", "force", "reach_attract", "reach_total")

ObstacleDrag = Callable[[int, float, float, str], None]  # (index, x, y, phase) in world metres
# Segments of an obstacle's outline: within 2 % of its radius (a pixel at 50 px). Every line segment
# is a few triangles a frame for a software-rendered page; a course has a hundred obstacles or more.
RIM_SEGMENTS = 16


def _radius(canvas: Canvas, snap: Snapshot) -> float:
    """A robot's radius in scene units."""
    return snap.extras["params"].robot_radius * canvas.scale


class WorldLayer(Static):
    """The course: its grid, the start box, the walls, the obstacle layers and the source."""

    name = "world"
    keys = (*GRID_KEYS, "start", "start_edge", "walls", "layers", "source", "source_label")
    legend = (LegendEntry("■", START, "start box"), LegendEntry("—", LAYER, "layer"),
              LegendEntry("●", SOURCE, "source"))

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        world: WorldSpec = snap.extras["world"]
        sc = canvas.scene
        x0, y0, x1, y1 = world.bounds
        draw_grid(canvas, np.array([x0, y0]), np.array([x1, y1]), 1.0, (GRID_CELL, GRID_SECTION), Z["grid"])
        bx0, by0, bx1, by1 = world.start_box
        box = np.array([[bx0, by0], [bx1, by0], [bx1, by1], [bx0, by1]])
        canvas.add("start", sc.add_mesh_simple(
            canvas.name("start"), canvas.to_view(box, Z["start"]), np.array([[0, 1, 2], [0, 2, 3]], np.uint32),
            color=START, opacity=0.18, material="toon3", side="double", cast_shadow=False, receive_shadow=False))
        canvas.lines("start_edge", shapes.polyline(box, closed=True), START, 1.5, Z["start"])
        canvas.lines("walls", np.asarray(world.walls), WALL, 3.0, Z["obstacles"])
        layers = [np.array([[(lx, y0), (lx, y1)]]) if canvas.light else shapes.dashed((lx, y0), (lx, y1), 0.6, 0.6)
                  for lx in world.layer_x]  # the light drawing: one line a layer, not a hundred dashes
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
        rims = [] if canvas.light else [shapes.circle_segments(c[:2], c[2], RIM_SEGMENTS) for c in circles]
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
    legend = (LegendEntry("○", SELECTED, "selected"), LegendEntry("■", (215, 70, 20), "sector (near: red)"),
              LegendEntry("◆", HIT, "closest hit"), LegendEntry("—", FORCE, "force F_t"),
              LegendEntry("○", REACH_ATTRACT, "reach c1+c2"), LegendEntry("○", REACH_TOTAL, "reach ĉ"))

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

    def interest(self, snap: Snapshot) -> np.ndarray:
        return np.zeros((0, 2))  # its home is the whole world already

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


def layers(part: KindPanel | None) -> tuple[Layer, ...]:
    """The fleet's arena: the course and its obstacles (drag one to move it), the robots with
    their headings, trails and bests, the selected robot's sensing; swarm B, the beliefs."""
    return (
        WorldLayer(),
        Obstacles(part.drag if part is not None else None),
        Robots(ROBOT, _radius, Z["robots"], collided=COLLIDED),
        Stalled(),
        Headings(HEADING, lambda canvas, snap: 1.3 * snap.extras["params"].robot_radius, Z["headings"],
                 angle=_heading_angle),
        Trails(TRAIL, 1.5, Z["trails"]),
        PersonalBests(PBEST, metres(0.25), Z["pbests"]),
        GlobalBest(GBEST, metres(0.75), Z["gbest"]),
        Probe(),
        Ghosts(_radius),
        Twin(_radius, (0.009, -0.006)),
    )


# ---------------------------------------------------------------------------- panel
# label → (controller.law, controller.mode)
CONTROLLERS: dict[str, tuple[str, str]] = {
    "Original RPSO": ("rpso", "raw"),
    "Adapted RPSO (constant)": ("adapted-rpso", "raw"),
    "Adapted RPSO + DVC": ("adapted-rpso", "dvc"),
    "Robot-centred (constant)": ("robot-centred", "raw"),
    "Non-omni + DVC": ("nonomni", "dvc"),
}
BODY_FRAME_LAWS = tuple(name for name, law in ROBOT_LAWS.items() if law.body_frame)
OMNI_DRIVES = ("holonomic", "mecanum")
WORLDS = ("obstacle-course", "forest", "empty")
RATIO_MARKS = ((0.5, "½"), (1.0, "1"), (2.0, "2"))  # the Table 4.1 cases
VIEWS = {"whole world": "world", "follow the swarm": "swarm", "follow the robot": "robot"}
FOLLOW_ZOOM = 2.5  # zoom a follow view starts with
REBUILD_NOTE = ("*Changes on this tab rebuild the fleet: the robots start again from the start box and obstacle "
                "edits are dropped.*")
EDIT_HELP = ("Click the arena: **add** an obstacle · **shift-** or **ctrl-click** removes the nearest · **drag** an "
             "obstacle to move it · click a robot to select it.")
EXPORT_NOTE = (" Obstacles added, removed or moved by hand go into the downloaded preset and the JSON export "
               "(world.obstacles, as they are now); a replay keeps them as they were at each step.")


def controller_changes(label: str, sc: Scenario) -> dict[str, Any]:
    """The preset fields that switch ``sc`` to the controller ``label`` (one of ``CONTROLLERS``)."""
    law, mode = CONTROLLERS[label]
    c = sc.controller
    changes: dict[str, Any] = {"controller.law": law, "controller.mode": mode}
    drive = sc.robot.drive
    if law in BODY_FRAME_LAWS and drive != "differential":
        changes["robot.drive"] = "differential"
    elif law not in BODY_FRAME_LAWS and drive == "differential":
        changes["robot.drive"] = "holonomic"
    if mode == "raw" and (c.c3 == 0.0 or c.mode == "dvc"):
        case = TABLE_4_1["c3-equal"]  # a sensible constant case to start from
        changes.update({f"controller.{k}": v for k, v in case.items()})
    return changes


def controller_label(law: str, mode: str) -> str:
    for label, key in CONTROLLERS.items():
        if key == (law, mode):
            return label
    return f"{law} ({mode})"


def _controller(s: Session) -> str:
    return controller_label(s.scenario.controller.law, s.scenario.controller.mode)


def _controllers(s: Session) -> tuple[str, ...]:
    label = _controller(s)
    return tuple(CONTROLLERS) + (() if label in CONTROLLERS else (label,))


def _set_controller(s: Session, label: str) -> dict[str, Any] | None:
    c = s.scenario.controller
    if label not in CONTROLLERS or CONTROLLERS[label] == (c.law, c.mode):
        return None
    return controller_changes(label, s.scenario)


def _dvc(s: Session) -> bool:
    return s.scenario.controller.mode == "dvc"


def _omni(sc: Scenario) -> bool:
    """An omnidirectional RPSO law (original or Adapted): attraction and avoidance c1, c2, c3."""
    return not ROBOT_LAWS[sc.controller.law].body_frame


def _avoidance(sc: Scenario) -> float:
    """c3, when the law has an avoidance term."""
    c = sc.controller
    return c.c3 if ROBOT_LAWS[c.law].terms > 2 else 0.0


def _c_hat(s: Session) -> float:
    c = s.scenario.controller
    return round_sig(min(max(c.c1 + c.c2 + _avoidance(s.scenario), 0.05), 5.0), 4)


def _ratio(s: Session) -> float:
    c = s.scenario.controller
    c12 = c.c1 + c.c2
    return round_sig(min(_avoidance(s.scenario) / c12 if c12 > 0 else 4.0, 4.0), 4)


def _budget(panel: PanelAPI, total: float | None = None, ratio: float | None = None) -> None:
    """ĉ and c3/(c1+c2) → c1, c2, c3 (split by c1 : c2)."""
    total = float(panel.handles["c_hat"].value if total is None else total)
    ratio = float(panel.handles["ratio"].value if ratio is None else ratio)
    c = panel.session.scenario.controller
    if ROBOT_LAWS[c.law].terms <= 2:
        c12, c3 = total, c.c3
    else:
        c12, c3 = total / (1.0 + ratio), total * ratio / (1.0 + ratio)
    changes = {"controller.c1": round_sig(c.c1_share * c12), "controller.c2": round_sig((1 - c.c1_share) * c12),
               "controller.c3": round_sig(c3)}
    panel.apply(changes, f"ĉ = {total:g}, c3/(c1+c2) = {ratio:g}")


def _drives(s: Session) -> tuple[str, ...]:
    sc = s.scenario
    drives = ("differential",) if sc.controller.law in BODY_FRAME_LAWS else OMNI_DRIVES
    return drives if sc.robot.drive in drives else drives + (sc.robot.drive,)


def _view(panel: PanelAPI, value: Any) -> None:
    """The arena's view: the whole world, or a closer one that follows the swarm or the robot."""
    follow = VIEWS.get(panel.handles["view"].value, "world")
    panel.handles["zoom"].visible = follow != "world"
    driver(panel.session).set_view(follow, float(panel.handles["zoom"].value))


def _restore(panel: PanelAPI) -> None:
    driver(panel.session).restore_world()
    panel.notify("World restored", "the preset's obstacles are back; the robots carry on", "blue")


def _obstacle_radius(panel: PanelAPI, value: Any) -> None:
    driver(panel.session).obstacle_radius = float(min(max(value, 0.05), 10.0))


def _keep(panel: PanelAPI, value: Any) -> None:
    """A choice kept in its handle (read when the arena is clicked)."""


def _budget_table(s: Session, snap: Snapshot) -> str:
    e = snap.extras
    i = e["view"].robot
    return budget_markdown(e["view"], e["params"], int(snap.status[i]), e["cmd"][i])


def _readout(s: Session) -> str:
    c = s.scenario.controller
    if c.mode == "dvc":
        n = ROBOT_LAWS[c.law].terms
        text = (f"ω = 1 − β = {1 - c.beta:.3g}; every robot gets its own c1..c{n:d} each step from its "
                "sector gaps (see the selected robot above).")
    else:
        c_hat = c.c1 + c.c2 + _avoidance(s.scenario)
        U = c_hat * 2 ** 0.5 / (1 - c.omega)
        bound = "" if c.law == "rpso" else f"; U = ĉ√2/(1 − ω) = {fmt(U, 'm/s')}"
        text = f"c1 = {c.c1:.4g}, c2 = {c.c2:.4g}, c3 = {c.c3:.4g}, ω = {c.omega:.3g}{bound}"
        if c.law == "rpso":
            text += "; original RPSO: unbounded terms, clipped at the top speed"
    with s.lock:
        sensing = s.sim.params.sensing_range
    return text + f" · sensing range {sensing:g} m"


def _status(s: Session, r: dict[str, float], state: str) -> str:
    sc, edits = s.scenario, driver(s).edits
    return (f"**{escape(sc.name)}** · {state} · t = {r['t']:.0f} s · {s.progress()} · "
            f"CoM x = {r['com']:.1f} m"
            + (f" · layers passed {int(r['layers_passed'])}/{int(r['layers'])}" if r["layers"] else "")
            + f" · {int(r['operational'])}/{int(r['operational'] + r['collided'])} operational"
            + (f" · {int(r['stalled'])} stalled" if r.get("stalled") else "")
            + (f" · {edits:d} obstacle edit{'s' * (edits != 1)}" if edits else ""))


def _compare(s: Session) -> dict[str, dict[str, Any]]:
    """B with another controller (law, coefficient policy and the drive it needs), or on the
    other positions (oracle vs SLO)."""
    sc = s.scenario
    here = (sc.controller.law, sc.controller.mode)
    return {**{f"controller: {label}": controller_changes(label, sc) for label, key in CONTROLLERS.items()
               if key != here}, **positions_choices(sc)}


def _rebuilt(s: Session, what: str, changes: dict[str, Any]) -> tuple[str, str]:
    n = driver(s).dropped
    dropped = f"; {n} obstacle edit{'s' * (n != 1)} dropped" if n else ""
    return "Fleet rebuilt", f"{what}: the robots start again from the start box{dropped}"


def _world_layers(s: Session) -> tuple[Line, ...]:
    return tuple(Line(f"layer {i + 1}", float(x), stroke="rgba(120, 120, 120, 0.9)", dash=(3.0, 4.0))
                 for i, x in enumerate(s.sim.world.layer_x))


COM = PlotSpec("com", "swarm fitness: CoM x [m] · dotted: layers",
               (Series("CoM x [m]", "com_fitness", "rgb(220,50,50)", 2),), lines=_world_layers, twin="com_fitness",
               y_range=lambda s: (float(s.sim.world.bounds[0]), float(s.sim.world.bounds[2])), aspect=1.6,
               legend={"show": False})
ROBOTS = PlotSpec("robots", "robots", (
    Series("operational", "operational", "rgb(30,140,70)", 2),
    Series("collided", "collided", "rgb(150,150,150)", 2, dash=(6.0, 4.0)),
    Series("stalled", "stalled", "rgb(255,120,0)", 2, dash=(2.0, 3.0)),
), y_range=lambda s: (0.0, float(max(s.robots, 1)) + 0.5))


def panel(api: PanelAPI) -> KindPanel:
    """The selected robot's budget, the controller, the world and its obstacles, the robots,
    live plots. Controller and sensing fields change the running fleet at its next step; the
    world, the robot model and the robot count rebuild it (the panel says so)."""
    editor = WorldEditor(driver(api.session), api.notify, api.select_robot)
    world = lambda kind: (lambda s: s.scenario.world.kind == kind)  # noqa: E731
    omni = lambda s: _omni(s.scenario)  # noqa: E731
    return KindPanel(
        folders=(
            Folder("Arena view and selected robot", expand=False, items=(
                Dropdown("view", "view", tuple(VIEWS), act=_view,
                         hint="the whole world, or a closer view that follows"),
                Slider("zoom", "zoom", 1.0, 6.0, 0.5, "how close the following view is", act=_view,
                       initial=FOLLOW_ZOOM, visible=lambda s: driver(s).follow != "world"),
                robot_number(hint="whose sectors, force and budget are drawn; or click a robot"),
                Text("budget", on_snapshot=_budget_table),
            )),
            positions_folder(),
        ),
        tabs=(
            Tab("Controller", (
                Dropdown("controller", "controller", _controllers, read=_controller, write=_set_controller,
                         hint="velocity law and coefficient policy (Chapters 4 and 5)"),
                Slider("controller.dt", "Δt [s]", 0.1, 2.0, 0.05, "controller period"),
                Slider("controller.alpha", "α safety", 0.05, 0.99, 0.01,
                       "DVC: a step may cover at most α of a gap [4.14]", visible=_dvc),
                Slider("controller.beta", "β", 0.05, 1.0, 0.01, "ĉ = βU/√d [4.15]; ω = 1 − β under DVC", visible=_dvc),
                Slider("controller.omega", "ω", 0.0, 0.99, 0.01, "inertia weight (constant coefficients)",
                       visible=lambda s: not _dvc(s)),
                Slider("c_hat", "ĉ = c1 + c2 + c3", 0.05, 5.0, 0.01, "total budget of the constant coefficients [m/s]",
                       read=_c_hat, act=lambda p, v: _budget(p, total=v), visible=lambda s: not _dvc(s),
                       label_of=lambda sc: "ĉ = c1 + c2 + c3" if _omni(sc) else "ĉ = c1 + c2"),
                Slider("ratio", "c3 / (c1 + c2)", 0.0, 4.0, 0.05, "avoidance against attraction; Table 4.1: ½, 1, 2",
                       marks=RATIO_MARKS, read=_ratio, act=lambda p, v: _budget(p, ratio=v),
                       visible=lambda s: not _dvc(s) and omni(s)),
                Slider("controller.gamma", "γ", 0.1, 10.0, 0.1,
                       "avoidance sensitivity [4.4]: F = γ/s; only the sign of F_t counts in Adapted RPSO",
                       visible=omni),
                Slider("controller.c1_share", "c1 : c2 split", 0.0, 1.0, 0.05, "c1/(c1+c2); the thesis uses 0.5"),
                Slider("sensing.range", "sensing range R [m]", 0.5, 10.0, 0.1, "LiDAR range of the six sectors"),
                Checkbox("controller.guard", "DVC inertia guard", visible=_dvc,
                         hint="ours: cap each step at α of every sensed gap, inertia included"),
                Dropdown("controller.update", "update order", ("sequential", "simultaneous"),
                         hint="robots sense and move one after another (Algorithms 1–2) or all at once"),
                Text("readout", compute=_readout),
                Text(text="*Controller changes take effect at the next step, without a restart.*"),
            )),
            Tab("World", (
                Text(text=REBUILD_NOTE),
                Dropdown("world.kind", "world", WORLDS),
                Slider("world.layers", "layers", 1, 15, 1, "obstacle layers, denser towards the source", integer=True,
                       visible=world("obstacle-course")),
                Slider("world.length", "length [m]", 20.0, 150.0, 1.0, "course length along x",
                       visible=world("obstacle-course")),
                Slider("world.width", "width [m]", 13.0, 80.0, 1.0, "course width, or the side of a square arena"),
                Slider("world.density", "tree density", 0.01, 0.2, 0.01, "share of the forest floor covered by trees",
                       visible=world("forest")),
                Slider("sim.robots", "robots", 1, 40, 1, "number of robots (rebuilds the fleet)", integer=True),
                Number("world.seed", "world seed", read=lambda s: int(required(s.scenario.world, "world").seed),
                       hint="which random course or forest"),
                Dropdown("robot.motion", "motion", ("kinematic", "physics"),
                         hint="ideal particles (MATLAB) or pymunk bodies with inertia (Gazebo)"),
                Dropdown("robot.drive", "drive", _drives,
                         hint="holonomic, mecanum (direction-dependent top speed) or differential"),
                Folder("Edit obstacles", items=(
                    Text(text=EDIT_HELP),
                    Dropdown("click", "click does", CLICK_MODES, act=_keep),
                    Slider("obstacle_radius", "new obstacle radius [m]", 0.2, 3.0, 0.1,
                           read=lambda s: driver(s).obstacle_radius, act=_obstacle_radius),
                    Button("restore", "Restore world", _restore, hint="drop the edits: the preset's world again"),
                )),
                TRAIL_SLIDER,
            )),
            Tab("Plots", (COM, ROBOTS)),
        ),
        status=_status, compare=_compare, rebuilt=_rebuilt, export_note=EXPORT_NOTE, state=editor,
        click=lambda p, x, y, modifier: editor.click(x, y, modifier, p.handles["click"].value),
        drag=editor.drag)


def accepts(scenario: Scenario) -> bool:
    return kind_of(scenario) == "fleet"


def refuse(scenario: Scenario) -> None:
    if not accepts(scenario):
        raise PresetError([f"world: {scenario.name} has no [world]; it runs as a free-space swarm"])


KIND = AppKind(name="fleet", title="Chapter 4–5 fleet", engine="fleet", refuse=refuse,
               make_driver=FleetDriver, notes="ch4-5", layers=layers, camera=FollowCamera, make_panel=panel)


def driver(session: Session) -> FleetDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, FleetDriver), session.kind.name
    return session.driver
