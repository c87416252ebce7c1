"""The top-down view of a Chapter 4–5 fleet: a world with obstacles, robots with bodies and,
for the selected robot, its six sensing sectors, closest hits, virtual force and budget.

The world is scaled so that its longer side spans ``2 · VIEW_HALF`` view units around the
origin (the camera of ``scene.py`` shows that square). Batched nodes only: every obstacle is
one instance of a single disc mesh (so a drag on it reports which one), the robots are one
flat-shaded point cloud, lines are segment lists. All nodes hang off one frame ``/fleet_<n>``.
"""

from __future__ import annotations

import itertools
import math
from typing import Any, Callable

import numpy as np

from shoal.engine.robots.world import WorldSpec
from shoal.presets.models import Scenario

from . import shapes
from .fleet_session import FleetSnapshot
from .ghosts import GhostLayer
from .scene import VIEW_HALF
from .twin_view import TwinLayer, trail_segments

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

ObstacleDrag = Callable[[int, float, float, str], None]

# Every build of the scene, and every re-created obstacle node, gets names never used before:
# viser lets a create supersede a pending remove of the same name in its send queue, which
# can reorder a subtree's removal and re-creation (and leave the scene empty).
_SERIAL = itertools.count()


class FleetView(shapes.GroundFrame, shapes.PointLayer, TwinLayer, GhostLayer):
    """The scene of one tab showing a fleet. ``scene`` is a viser ``SceneApi``.

    ``follow`` and ``zoom`` (from the snapshot) pick the view: the whole world (zoom 1), or a
    closer view that follows the swarm's centre or the selected robot. Everything hangs off
    the frame ``/fleet``, which moves to keep the followed point in the middle.
    """

    def __init__(self, scene: Any) -> None:
        self.scene = scene
        self.nodes: dict[str, Any] = {}
        self.scale = 1.0
        self.centre = np.zeros(2)  # world point at the origin of /fleet
        self.focus = np.zeros(2)  # world point at the middle of the screen
        self.zoom = 1.0
        self.drawn_revision = -1
        self.built_revision = -1
        self.world_revision = -1
        self.on_obstacle_drag: ObstacleDrag | None = None  # (index, x, y, phase) in world metres
        self._static = False
        self._n_obstacles = -1
        self._followed: str | None = None  # follow mode of the last draw (a new one re-centres at once)
        self._root = "/fleet"

    # ------------------------------------------------------------------ transforms
    def to_view(self, xy: np.ndarray, z: float = 0.0) -> np.ndarray:
        """World metres (…, 2) → view units (…, 3) float32."""
        return shapes.lift((np.asarray(xy, dtype=float) - self.centre) * self.scale, z)

    # ------------------------------------------------------------------ lifecycle
    def _drop_nodes(self) -> None:
        for node in reversed(list(self.nodes.values())):
            node.remove()
        self.nodes.clear()
        self.drawn_revision = self.world_revision = -1
        self._static = False
        self._n_obstacles = -1
        self._followed = None

    def _name(self, key: str, fresh: bool = False) -> str:
        """The scene path of node ``key`` (``fresh``: a name not used before, for a re-created node)."""
        return f"{self._root}/{key}" + (f"_{next(_SERIAL)}" if fresh else "")

    def clear(self) -> None:
        self._drop_nodes()
        self.built_revision = -1

    def rebuild(self, scenario: Scenario, scene_revision: int) -> None:
        """Forget every node; the next ``draw`` builds the scene of the new fleet."""
        self.clear()
        self.built_revision = scene_revision

    def _lines(self, key: str, segs: np.ndarray, color: tuple[int, int, int], px: float, z: float) -> None:
        """Create or update a segment node (an empty list draws one invisible point-segment)."""
        pts = self.to_view(segs, z) if len(segs) else np.zeros((1, 2, 3), np.float32)
        node = self.nodes.get(key)
        if node is None:
            self.nodes[key] = self.scene.add_line_segments(
                self._name(key), pts, colors=color, thickness=px, thickness_units="screen")
        else:
            node.points = pts
        self.nodes[key].visible = bool(len(segs))

    def _point_size(self, size_m: float) -> float:
        return size_m * self.scale  # markers sized in metres

    # ------------------------------------------------------------------ static scene
    def _build_static(self, world: WorldSpec) -> None:
        sc = self.scene
        x0, y0, x1, y1 = world.bounds
        self.centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
        self.focus = self.centre.copy()
        self.scale = self.zoom * 2 * VIEW_HALF / max(x1 - x0, y1 - y0)
        w, h = (x1 - x0) * self.scale, (y1 - y0) * self.scale
        self._root = f"/fleet_{next(_SERIAL)}"
        self.nodes["root"] = sc.add_frame(self._root, show_axes=False)
        self.nodes["grid"] = sc.add_grid(
            self._name("grid"), width=w, height=h, plane="xy", cell_size=1.0 * self.scale,
            section_size=5.0 * self.scale, cell_color=GRID_CELL, section_color=GRID_SECTION,
            position=(0.0, 0.0, Z["grid"]), shadow_opacity=0.0, infinite_grid=False, fade_distance=1e4)
        bx0, by0, bx1, by1 = world.start_box
        box = np.array([[bx0, by0], [bx1, by0], [bx1, by1], [bx0, by1]])
        self.nodes["start"] = sc.add_mesh_simple(
            self._name("start"), self.to_view(box, Z["start"]), np.array([[0, 1, 2], [0, 2, 3]], np.uint32),
            color=START, opacity=0.18, material="toon3", side="double", cast_shadow=False,
            receive_shadow=False)
        self._lines("start_edge", shapes.polyline(box, closed=True), START, 1.5, Z["start"])
        self._lines("walls", np.asarray(world.walls), WALL, 3.0, Z["obstacles"])
        layers = [shapes.dashed((lx, y0), (lx, y1), 0.6, 0.6) for lx in world.layer_x]
        self._lines("layers", np.concatenate(layers) if layers else np.zeros((0, 2, 2)), LAYER, 1.2, Z["layers"])
        for i, lx in enumerate(world.layer_x):
            self.nodes[f"layer_label_{i}"] = sc.add_label(
                self._name(f"layer_label_{i}"), f"layer {i + 1}", position=tuple(self.to_view((lx, y1 + 0.8), 0.0)))
        src = np.asarray(world.source, dtype=float)
        self._points("source", src[None], SOURCE, 1.0, "circle", Z["source"])
        self.nodes["source_label"] = sc.add_label(
            self._name("source_label"), "source", position=tuple(self.to_view(src + (0.8, 0.8), 0.0)))
        self._static = True

    def _draw_obstacles(self, world: WorldSpec) -> None:
        circles = world.circles
        node = self.nodes.get("obstacles")
        pos = self.to_view(circles[:, :2], Z["obstacles"])
        scales = (circles[:, 2] * self.scale).astype(np.float32)
        if len(circles) != self._n_obstacles or node is None:  # count changed: a new node
            if node is not None:
                node.remove()
                self.nodes.pop("obstacles")
            if len(circles):
                v, f = shapes.disc_mesh(40)
                node = self.scene.add_batched_meshes_simple(
                    self._name("obstacles", fresh=True), v, f,
                    batched_wxyzs=np.tile([1.0, 0, 0, 0], (len(circles), 1)), batched_positions=pos,
                    batched_scales=scales, batched_colors=OBSTACLE, lod="off", material="toon3", side="double",
                    cast_shadow=False, receive_shadow=False)
                self.nodes["obstacles"] = node
                node.on_drag("left")(self._dragged)
            self._n_obstacles = len(circles)
        else:
            node.batched_positions = pos
            node.batched_scales = scales
        rims = [shapes.circle_segments(c[:2], c[2], 40) for c in circles]
        self._lines("obstacle_edges", np.concatenate(rims) if rims else np.zeros((0, 2, 2)), OBSTACLE_EDGE, 1.2,
                    Z["obstacles"] + 0.001)
        self._draw_polygons(world)

    def _draw_polygons(self, world: WorldSpec) -> None:
        if "polygons" in self.nodes:
            self.nodes.pop("polygons").remove()
        if not world.polygons:
            return
        verts, faces, base = [], [], 0
        for p in world.polygons:  # convex: a fan from vertex 0
            verts.append(self.to_view(p, Z["obstacles"]))
            faces += [(base, base + j, base + j + 1) for j in range(1, len(p) - 1)]
            base += len(p)
        self.nodes["polygons"] = self.scene.add_mesh_simple(
            self._name("polygons", fresh=True), np.vstack(verts), np.array(faces, np.uint32), color=OBSTACLE,
            material="toon3", side="double", cast_shadow=False, receive_shadow=False)

    def _dragged(self, event: Any) -> None:
        if self.on_obstacle_drag is None or event.instance_index is None:
            return
        xy = self.to_world(np.asarray(event.end_position, dtype=float)[:2])
        self.on_obstacle_drag(int(event.instance_index), float(xy[0]), float(xy[1]), str(event.phase))

    # ------------------------------------------------------------------ per frame
    def draw(self, snap: FleetSnapshot) -> None:
        """Push one snapshot into the nodes (building the static scene first if needed)."""
        if self.built_revision < 0:
            return
        if snap.zoom != self.zoom:  # another scale: every node again
            self._drop_nodes()
            self.zoom = snap.zoom
        if not self._static:
            self._build_static(snap.world)
        self._follow(snap)
        if snap.world_revision != self.world_revision:
            self._draw_obstacles(snap.world)
            self.world_revision = snap.world_revision
        self._draw_robots(snap)
        if snap.live:
            self._draw_probe(snap)
        else:  # a recorded frame: what the robot sensed is not recorded
            for key in PROBE_NODES:
                if key in self.nodes:
                    self.nodes[key].visible = False
        self.draw_ghosts(snap.ghosts if snap.live else None)  # SLO positions: the selected robot's beliefs
        self.drawn_revision = snap.revision

    def _follow(self, snap: FleetSnapshot) -> None:
        """Move /fleet so the followed point (swarm centre or selected robot) stays in view."""
        if snap.follow == "world" or self.zoom <= 1.0:
            target = self.centre
        elif snap.follow == "robot":
            target = snap.view.x
        else:
            alive = snap.status == 0
            target = snap.x[alive].mean(axis=0) if alive.any() else snap.x.mean(axis=0)
            if self._followed == "swarm":  # a dead zone round the middle: no jitter step by step
                off = target - self.focus
                dead = 0.15 * VIEW_HALF / self.scale  # metres; VIEW_HALF/scale reaches the nearer edge
                target = self.focus + np.sign(off) * np.maximum(np.abs(off) - dead, 0.0)
        self._followed = snap.follow
        x0, y0, x1, y1 = snap.world.bounds
        target = np.clip(target, (x0, y0), (x1, y1))
        if not np.allclose(target, self.focus):
            self.focus = np.asarray(target, dtype=float)
            off = (self.centre - self.focus) * self.scale
            self.nodes["root"].position = (float(off[0]), float(off[1]), 0.0)

    def _draw_robots(self, snap: FleetSnapshot) -> None:
        r = snap.params.robot_radius
        colors = np.where((snap.status != 0)[:, None], COLLIDED, ROBOT).astype(np.uint8)
        pos = self.to_view(snap.x, Z["robots"])
        node = self.nodes.get("robots")
        if node is None:  # flat-shaded points: exact colours; a point's size is its radius
            self.nodes["robots"] = self.scene.add_point_cloud(
                self._name("robots"), pos, colors=colors, point_size=r * self.scale, point_shape="circle",
                precision="float32", point_shading="flat")
        else:
            node.points, node.colors = pos, colors
        speed = np.hypot(snap.u[:, 0], snap.u[:, 1])
        along = np.where(snap.params.body_frame | (speed < 1e-9), snap.heading, np.arctan2(snap.u[:, 1], snap.u[:, 0]))
        tip = snap.x + 1.3 * r * np.column_stack([np.cos(along), np.sin(along)])
        self._lines("headings", np.stack([snap.x, tip], axis=1), HEADING, 2.0, Z["headings"])
        self._lines("trails", trail_segments(snap.trails), TRAIL, 1.5, Z["trails"])
        none = np.zeros((0, 2))
        self._points("pbests", snap.y if snap.live else none, PBEST, 0.25, "square", Z["pbests"])
        self._points("gbest", snap.yg[None] if snap.live else none, GBEST, 0.75, "diamond", Z["gbest"])
        self._robot_radius = r

    def _twin_size(self) -> float:
        return getattr(self, "_robot_radius", 0.2)

    def _draw_probe(self, snap: FleetSnapshot) -> None:
        """The selected robot: sectors filled out to each closest body, the range circle, the
        hits, F_t and the reach its budget allows in one step."""
        v, p = snap.view, snap.params
        centre, radius, rng = v.x, p.robot_radius, p.sensing_range
        self._lines("selected", shapes.circle_segments(centre, 1.35 * radius, 40), SELECTED, 3.0, Z["probe"])
        start = v.frame_angle - math.pi + np.arange(6) * math.pi / 3  # sector k starts here
        node = self.nodes.get("sectors")
        frac = np.clip(v.gap / rng, 0.0, 1.0)
        colors = (SECTOR_NEAR + (SECTOR_FAR - SECTOR_NEAR) * frac[:, None]).astype(np.uint8)
        pos = np.repeat(self.to_view(centre[None], Z["sectors"]), 6, axis=0)
        scales = ((radius + v.gap) * self.scale).astype(np.float32)
        wxyz = shapes.yaw_wxyz(start)
        if node is None:
            vert, face = shapes.wedge_mesh(math.pi / 3, 12)
            self.nodes["sectors"] = self.scene.add_batched_meshes_simple(
                self._name("sectors"), vert, face, batched_wxyzs=wxyz, batched_positions=pos, batched_scales=scales,
                batched_colors=colors, opacity=0.45, lod="off", material="toon3",
                side="double", cast_shadow=False, receive_shadow=False)
        else:
            node.batched_positions, node.batched_wxyzs, node.batched_scales = pos, wxyz, scales
            if not np.array_equal(node.batched_colors, colors):
                node.batched_colors = colors
            node.visible = True
        edges = np.concatenate([shapes.circle_segments(centre, radius + rng, 72),
                                shapes.rays(centre, start, radius, radius + rng)])
        self._lines("sector_edges", edges, SECTOR_EDGE, 1.0, Z["probe"])
        hits = v.point[v.hit]
        self._points("hits", hits, HIT, 0.28, "diamond", Z["hits"])
        self._lines("hit_lines", np.stack([np.repeat(centre[None], len(hits), 0), hits], axis=1)
                    if len(hits) else np.zeros((0, 2, 2)), HIT, 1.0, Z["probe"])
        f = np.asarray(v.force, dtype=float)
        mag = float(np.hypot(*f))
        if mag > 1e-9 and not p.body_frame:
            length = (radius + rng) * mag / (mag + 1.0)  # saturating: γ/s = 1 reaches half the range
            self._lines("force", shapes.arrow(centre, f / mag * length), FORCE, 3.0, Z["probe"])
        else:
            self._lines("force", np.zeros((0, 2, 2)), FORCE, 3.0, Z["probe"])
        self._draw_reach(snap)

    def _draw_reach(self, snap: FleetSnapshot) -> None:
        """How far the budget can carry the selected robot in one step: omni, the attraction reach
        (c1+c2)√2/β·Δt (blue) and the total ĉ√2/β·Δt (orange); non-omni, the forward reach
        c5/β·Δt along the heading (blue). Not drawn for original RPSO, whose terms are unbounded."""
        v, p = snap.view, snap.params
        c, centre, r = np.asarray(v.c, dtype=float), v.x, p.robot_radius
        attract, total = np.zeros((0, 2, 2)), np.zeros((0, 2, 2))
        if p.law == "adapted-rpso" and p.beta > 0:
            k = math.sqrt(2) / p.beta * p.dt
            attract = shapes.circle_segments(centre, r + k * (c[0] + c[1]), 56)
            total = shapes.circle_segments(centre, r + k * c[:3].sum(), 56)
        elif p.law == "nonomni" and p.beta > 0 and len(c) >= 5:
            reach = r + c[4] / p.beta * p.dt
            attract = shapes.rays(centre, np.array([v.heading]), r, reach)
        self._lines("reach_attract", attract, REACH_ATTRACT, 2.0, Z["probe"])
        self._lines("reach_total", total, REACH_TOTAL, 2.0, Z["probe"])
