"""The top-down view of an acoustic swarm (Ch. 6–8): robots, the source (drag it to move it),
each robot's pair of bearing rays, their intersections, personal and global bests, the d_c
circle, the escort ring and GT-PSO triplets.

The arena square (``arena.half_size``) spans ``2 · VIEW_HALF`` view units, as in the
Chapter 3 view. Batched nodes only: rays, triangles and rings are segment lists, points are
point clouds; the source is a one-instance batched disc mesh so that it can be dragged.
All nodes hang off one frame, which is shifted when the swarm or the source leaves the
square (a moving source), so that both stay in view.
"""

from __future__ import annotations

import itertools
from typing import Any, Callable

import numpy as np

from shoal.presets.models import Scenario

from . import shapes
from .ghosts import GhostLayer
from .scene import VIEW_HALF
from .session.snapshot import Snapshot
from .twin_view import TwinLayer, trail_segments

GRID_CELL = (228, 228, 224)
GRID_SECTION = (205, 205, 200)
BORDER = (60, 60, 60)
ROBOT = (220, 50, 50)
HEADING = (90, 15, 15)
TRAIL = (110, 150, 255)
RAY_TRUE = (30, 150, 60)  # the ray of the pair nearer the true source direction
RAY_MIRROR = (235, 120, 20)  # its mirror image about the robot's axis
HIT_KEPT = (130, 50, 200)  # intersections ahead of both rays (and passing [7.12] under XB-PSO)
HIT_DROPPED = (170, 170, 170)  # ahead of both rays but removed by [7.12]
PICK = (200, 0, 140)  # the selected intersection p_s of each robot
PARTNER = (200, 0, 140)
PBEST = (110, 110, 110)
GBEST = (240, 170, 0)
SOURCE = (20, 150, 60)
DC_RING = (20, 150, 60)
ESCORT = (240, 170, 0)
TRIANGLE = (40, 90, 200)
SELECTED = (255, 190, 0)

Z = dict(grid=-0.025, rings=-0.015, triangles=-0.012, rays=-0.01, trails=-0.005, hits=0.0, pbests=0.004,
         source=0.006, gbest=0.008, robots=0.01, headings=0.012, selected=0.014)

SourceDrag = Callable[[float, float, str], None]
_SERIAL = itertools.count()


class SonarView(shapes.GroundFrame, shapes.PointLayer, TwinLayer, GhostLayer):
    """The scene of one tab showing an acoustic swarm. ``scene`` is a viser ``SceneApi``."""

    RAY_SHARE = 0.3  # ray length as a share of the arena side

    def __init__(self, scene: Any) -> None:
        self.scene = scene
        self.nodes: dict[str, Any] = {}
        self.scale = 1.0
        self.focus = np.zeros(2)  # world point at the middle of the screen
        self.half = 1.0
        self.drawn_revision = -1
        self.built_revision = -1
        self.on_source_drag: SourceDrag | None = None  # (x, y, phase) in world metres
        self._root = "/sonar"
        self._static = False

    # ------------------------------------------------------------------ transforms
    def to_view(self, xy: np.ndarray, z: float = 0.0) -> np.ndarray:
        """World metres (…, 2) → coordinates under the root frame (…, 3) float32."""
        return shapes.lift(np.asarray(xy, dtype=float) * self.scale, z)

    # ------------------------------------------------------------------ lifecycle
    def _name(self, key: str) -> str:
        return f"{self._root}/{key}"

    def clear(self) -> None:
        for node in reversed(list(self.nodes.values())):
            node.remove()
        self.nodes.clear()
        self.drawn_revision = -1
        self.built_revision = -1
        self._static = False

    def rebuild(self, scenario: Scenario, scene_revision: int) -> None:
        self.clear()
        self.half = float(scenario.arena.half_size)
        self.scale = VIEW_HALF / self.half
        self.focus = np.zeros(2)
        self.built_revision = scene_revision

    def _lines(self, key: str, segs: np.ndarray, color: Any, px: float, z: float) -> None:
        segs = np.asarray(segs, dtype=float).reshape(-1, 2, 2)
        pts = self.to_view(segs, z) if len(segs) else np.zeros((1, 2, 3), np.float32)
        colors = np.asarray(color, np.uint8)
        node = self.nodes.get(key)
        if node is None:
            self.nodes[key] = self.scene.add_line_segments(
                self._name(key), pts, colors=colors if colors.ndim == 1 else colors, thickness=px,
                thickness_units="screen")
        else:
            node.points = pts
        self.nodes[key].visible = bool(len(segs))

    def _build_static(self) -> None:
        sc = self.scene
        self._root = f"/sonar_{next(_SERIAL)}"
        self.nodes["root"] = sc.add_frame(self._root, show_axes=False)
        side = 2 * VIEW_HALF
        cell = 10 ** np.floor(np.log10(self.half / 4)) * self.scale  # about 10 cells a half side
        self.nodes["grid"] = sc.add_grid(
            self._name("grid"), width=side, height=side, plane="xy", cell_size=float(cell),
            section_size=float(5 * cell), cell_color=GRID_CELL, section_color=GRID_SECTION,
            position=(0.0, 0.0, Z["grid"]), shadow_opacity=0.0, infinite_grid=False, fade_distance=1e4)
        h = self.half
        box = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
        self._lines("border", shapes.polyline(box, closed=True), BORDER, 1.5, Z["grid"])
        v, f = shapes.disc_mesh(32)
        node = sc.add_batched_meshes_simple(
            self._name("source"), v, f, batched_wxyzs=np.array([[1.0, 0, 0, 0]]),
            batched_positions=np.zeros((1, 3), np.float32), batched_scales=np.array([0.022 * side], np.float32),
            batched_colors=SOURCE, lod="off", material="toon3", side="double", cast_shadow=False,
            receive_shadow=False)
        node.on_drag("left")(self._dragged)
        self.nodes["source"] = node
        self.nodes["source_label"] = sc.add_label(self._name("source_label"), "source (drag me)",
                                                  position=(0.0, 0.0, 0.0))
        self._static = True

    def _dragged(self, event: Any) -> None:
        if self.on_source_drag is None:
            return
        xy = self.to_world(np.asarray(event.end_position, dtype=float)[:2])
        self.on_source_drag(float(xy[0]), float(xy[1]), str(event.phase))

    # ------------------------------------------------------------------ per frame
    def draw(self, snap: Snapshot) -> None:
        if self.built_revision < 0:
            return
        if not self._static:
            self._build_static()
        self._follow(snap)
        self._draw_source(snap)
        self._draw_robots(snap)
        self._draw_rays(snap)
        self._draw_hits(snap)
        self._draw_triangles(snap)
        self.draw_ghosts(snap.ghosts if snap.live else None)  # SLO positions: the selected robot's beliefs
        self.drawn_revision = snap.revision

    def _follow(self, snap: Snapshot) -> None:
        """Keep the swarm's centre and the source on screen (a source may run away)."""
        com = snap.x.mean(axis=0)
        lim = 0.92 * self.half
        if np.all(np.abs(com - self.focus) < lim) and np.all(np.abs(snap.extras["source"] - self.focus) < lim):
            return
        self.focus = (com + snap.extras["source"]) / 2
        off = -self.focus * self.scale
        self.nodes["root"].position = (float(off[0]), float(off[1]), 0.0)

    def _draw_source(self, snap: Snapshot) -> None:
        src = snap.extras["source"]
        self.nodes["source"].batched_positions = self.to_view(src[None], Z["source"])
        self.nodes["source_label"].position = tuple(float(v) for v in self.to_view(src + 0.04 * self.half, 0.0))
        self._lines("dc_ring", shapes.circle_segments(src, snap.extras["d_c"], 72), DC_RING, 1.0, Z["rings"])
        if snap.extras["r_trap"] > 0 and snap.live:
            rings = np.concatenate([shapes.circle_segments(snap.yg, snap.extras["r_trap"], 72),
                                    shapes.circle_segments(src, snap.extras["r_trap"], 72)])
        else:
            rings = np.zeros((0, 2, 2))
        self._lines("escort", rings, ESCORT, 2.0, Z["rings"])

    def _draw_robots(self, snap: Snapshot) -> None:
        self._points("robots", snap.x, ROBOT, 0.009 * VIEW_HALF * 2, "circle", Z["robots"])
        tip = snap.x + 0.025 * self.half * np.column_stack([np.cos(snap.heading), np.sin(snap.heading)])
        self._lines("headings", np.stack([snap.x, tip], axis=1), HEADING, 2.0, Z["headings"])
        self._lines("trails", trail_segments(snap.trails), TRAIL, 1.2, Z["trails"])
        self._points("pbests", snap.y if snap.y is not None else np.zeros((0, 2)), PBEST, 0.006 * VIEW_HALF * 2, "square", Z["pbests"])
        self._points("gbest", snap.yg[None] if snap.live else np.zeros((0, 2)), GBEST, 0.016 * VIEW_HALF * 2,
                     "diamond", Z["gbest"])
        i = snap.selected
        self._lines("selected", shapes.circle_segments(snap.x[i], 0.02 * self.half, 32), SELECTED, 3.0,
                    Z["selected"])

    def _twin_size(self) -> float:
        return 0.009 * VIEW_HALF * 2

    def ray_segments(self, snap: Snapshot) -> tuple[np.ndarray, np.ndarray]:
        """(true, mirror) segment lists (N, 2, 2), each starting at a robot."""
        if snap.extras["rays"] is None or snap.extras["true_ray"] is None:
            return np.zeros((0, 2, 2)), np.zeros((0, 2, 2))
        n = len(snap.x)
        length = self.RAY_SHARE * 2 * self.half
        idx = np.arange(n)
        true_dir = snap.extras["rays"][idx, snap.extras["true_ray"]]
        mirror_dir = snap.extras["rays"][idx, 1 - snap.extras["true_ray"]]
        true = np.stack([snap.x, snap.x + length * true_dir], axis=1)
        mirror = np.stack([snap.x, snap.x + length * mirror_dir], axis=1)
        return true, mirror

    def _draw_rays(self, snap: Snapshot) -> None:
        true, mirror = self.ray_segments(snap)
        self._lines("rays_true", true, RAY_TRUE, 1.2, Z["rays"])
        self._lines("rays_mirror", mirror, RAY_MIRROR, 1.2, Z["rays"])
        i = snap.selected
        sel = np.concatenate([true[i:i + 1], mirror[i:i + 1]]) if len(true) else np.zeros((0, 2, 2))
        if len(sel):  # the selected robot's pair, thicker
            self._lines("rays_sel_true", sel[:1], RAY_TRUE, 3.0, Z["rays"] + 0.001)
            self._lines("rays_sel_mirror", sel[1:], RAY_MIRROR, 3.0, Z["rays"] + 0.001)
        else:
            self._lines("rays_sel_true", sel, RAY_TRUE, 3.0, Z["rays"] + 0.001)
            self._lines("rays_sel_mirror", sel, RAY_MIRROR, 3.0, Z["rays"] + 0.001)

    def _draw_hits(self, snap: Snapshot) -> None:
        empty = np.zeros((0, 2))
        kept = dropped = picks = empty
        partner = np.zeros((0, 2, 2))
        if snap.extras["points"] is not None and snap.extras["tri_members"] is None:  # B/XB-PSO: up to four per robot
            fwd = snap.extras["forward"].astype(bool)
            keep = snap.extras["kept"].astype(bool)
            kept = snap.extras["points"][keep]
            dropped = snap.extras["points"][fwd & ~keep]
        if snap.extras["points"] is not None and snap.extras["pick"] is not None:
            ok = snap.extras["pick"] >= 0
            idx = np.flatnonzero(ok)
            picks = snap.extras["points"][idx, snap.extras["pick"][idx]]
        if snap.extras["partner"] is not None:
            i = snap.selected
            j = int(snap.extras["partner"][i])
            if 0 <= j < len(snap.x) and j != i:
                partner = np.stack([snap.x[i], snap.x[j]])[None]
        size = 0.006 * VIEW_HALF * 2
        self._points("hits_kept", kept, HIT_KEPT, size, "circle", Z["hits"])
        self._points("hits_dropped", dropped, HIT_DROPPED, size, "circle", Z["hits"])
        self._points("picks", picks, PICK, 1.8 * size, "diamond", Z["hits"] + 0.001)
        self._lines("partner", partner, PARTNER, 1.5, Z["rays"] + 0.002)

    def _draw_triangles(self, snap: Snapshot) -> None:
        segs = rays = np.zeros((0, 2, 2))
        cents = np.zeros((0, 2))
        if snap.extras["tri_members"] is not None and snap.extras["tri_valid"] is not None:
            ok = snap.extras["tri_valid"].astype(bool) & np.all(snap.extras["tri_members"] >= 0, axis=1)
            m = snap.extras["tri_members"][ok]
            if len(m):
                p = snap.x[m]  # (T, 3, 2)
                segs = np.concatenate([np.stack([p[:, a], p[:, b]], axis=1) for a, b in ((0, 1), (1, 2), (2, 0))])
                cents = snap.extras["tri_centroid"][ok]
                rays = np.stack([cents, cents + 0.08 * self.half * snap.extras["tri_direction"][ok]], axis=1)
        self._lines("triangles", segs, TRIANGLE, 1.0, Z["triangles"])
        self._lines("tri_rays", rays, TRIANGLE, 2.0, Z["triangles"])
        self._points("tri_centroids", cents, TRIANGLE, 0.008 * VIEW_HALF * 2, "circle", Z["triangles"])
