"""The top-down 2-D arena: a few batched scene nodes redrawn from a :class:`Snapshot`.

World coordinates (metres) are scaled so that the arena square always spans
``[-VIEW_HALF, VIEW_HALF]`` in view units; the camera therefore never needs to move when a
preset with another arena size is loaded. Everything lives under one frame, ``/world``;
when the swarm leaves the square (1-D runs drifting along x for ever) that frame is shifted
so the view follows the swarm. On SLO-estimated positions the selected robot's ghosts are
drawn too (:class:`~.ghosts.GhostLayer`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shoal.engine.core.objectives import Objective
from shoal.presets.build import objective_for
from shoal.presets.models import Scenario

from .ghosts import GhostLayer
from .session import Snapshot
from .shapes import PointLayer
from .twin_view import TWIN, TWIN_TRAIL, trail_segments

VIEW_HALF = 10.0  # the arena's half size in view units
CAMERA_FOV = math.radians(8.0)  # far and narrow: close to an orthographic top view
CAMERA_HEIGHT = 1.12 * VIEW_HALF / math.tan(CAMERA_FOV / 2)


def camera_height(aspect: float) -> float:
    """Camera height that shows the whole arena (plus a margin) in a canvas of ``aspect`` = width/height."""
    aspect = aspect if math.isfinite(aspect) and aspect > 0 else 1.0
    return CAMERA_HEIGHT * max(1.0, 1.0 / aspect)

ROBOT = (220, 50, 50)
ROBOT_SIZE = 0.24  # viser point_size: the disc drawn has this radius in view units
HEADING = (120, 20, 20)
TRAIL = (80, 120, 255)
PBEST = (110, 110, 110)
GBEST = (240, 170, 0)
SOURCE = (20, 150, 60)
ARENA = (40, 40, 40)

BENCHMARKS = ("sphere", "rastrigin", "ackley", "rosenbrock", "griewank")


def landscape_rgb(objective: Objective, half_size: float, n: int = 160) -> np.ndarray:
    """The objective on an ``n × n`` grid over the arena as an RGB image (row 0 = top, +y).

    Low cost is dark blue, high cost pale; values are log-compressed so that the many local
    minima of Rastrigin or Griewank stay visible next to the steep walls.
    """
    from matplotlib import colormaps

    xs = np.linspace(-half_size, half_size, n)
    gx, gy = np.meshgrid(xs, xs[::-1])  # image rows run from +y (top) to −y
    f = objective(np.stack([gx, gy], axis=-1))
    if objective.maximise:
        f = -f
    f = np.log1p(f - f.min())
    span = f.max() - f.min()
    v = (f - f.min()) / span if span > 0 else np.zeros_like(f)
    rgb = colormaps["YlGnBu_r"](0.15 + 0.85 * v)[..., :3]
    rgb = 0.55 * rgb + 0.45  # paler, so the robots stand out
    return (255 * rgb).astype(np.uint8)


def _z(points: np.ndarray, z: float = 0.0) -> np.ndarray:
    """(…, d) world points → (…, 3) with d = 1 drawn on the x axis (y = 0)."""
    out = np.zeros(points.shape[:-1] + (3,), dtype=np.float32)
    d = min(points.shape[-1], 2)
    out[..., :d] = points[..., :d]
    out[..., 2] = z
    return out


def _square(half: float) -> np.ndarray:
    c = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
    return np.stack([c, np.roll(c, -1, axis=0)], axis=1)


class ArenaView(PointLayer, GhostLayer):
    """The scene of one tab. ``scene`` is a viser ``SceneApi`` (``client.scene`` or ``server.scene``)."""

    def __init__(self, scene: Any) -> None:
        self.scene = scene
        self.nodes: dict[str, Any] = {}
        self.scale = 1.0
        self.half_size = VIEW_HALF
        self.offset = np.zeros(2)  # world point at the view centre
        self.drawn_revision = -1
        self.built_revision = -1

    # ------------------------------------------------------------------ static scene
    def clear(self) -> None:
        """Remove every node of this view."""
        for node in reversed(list(self.nodes.values())):
            node.remove()
        self.nodes.clear()
        self.built_revision = self.drawn_revision = -1

    def rebuild(self, scenario: Scenario, scene_revision: int) -> None:
        """(Re)create every node for ``scenario``: arena square, grid, landscape or source."""
        self.clear()
        sc = self.scene
        half = float(scenario.arena.half_size)
        s = VIEW_HALF / half
        self.scale, self.half_size, self.offset = s, half, np.zeros(2)
        self.nodes["world"] = sc.add_frame("/world", show_axes=False)
        self.nodes["grid"] = sc.add_grid(
            "/world/grid", width=2 * VIEW_HALF, height=2 * VIEW_HALF, plane="xy",
            cell_size=VIEW_HALF / 10, section_size=VIEW_HALF / 2, cell_color=(225, 225, 225),
            section_color=(185, 185, 185), position=(0.0, 0.0, -0.02), shadow_opacity=0.0,
        )
        self.nodes["arena"] = sc.add_line_segments(
            "/world/arena", _z(_square(VIEW_HALF)), colors=ARENA, thickness=2.5, thickness_units="screen",
        )
        kind = scenario.objective.kind
        source = np.asarray(scenario.objective.source, dtype=float) * s
        if kind in BENCHMARKS and scenario.sim.d >= 2:
            img = landscape_rgb(objective_for(scenario.objective), half)
            self.nodes["landscape"] = sc.add_image(
                "/world/landscape", img, render_width=2 * VIEW_HALF, render_height=2 * VIEW_HALF,
                position=(0.0, 0.0, -0.04), cast_shadow=False, receive_shadow=False,
            )
        if kind != "linear":
            where = source if scenario.sim.d >= 2 else np.array([source[0], 0.0])
            self.nodes["source"] = sc.add_point_cloud(
                "/world/source", _z(where[None, :], 0.01), colors=SOURCE, point_size=0.3,
                point_shape="circle", precision="float32", point_shading="flat",
            )
            self.nodes["source_label"] = sc.add_label(
                "/world/source_label", "source" if kind == "source-distance" else "optimum",
                position=tuple(_z(where, 0.0) + np.array([0.5, 0.5, 0.0], np.float32)),
            )
        one = np.zeros((1, 3), np.float32)
        seg = np.zeros((1, 2, 3), np.float32)
        self.nodes["trails"] = sc.add_line_segments(
            "/world/trails", seg, colors=TRAIL, thickness=1.5, thickness_units="screen")
        self.nodes["pbests"] = sc.add_point_cloud(
            "/world/pbests", one, colors=PBEST, point_size=0.1, point_shape="square",
            precision="float32", point_shading="flat")
        self.nodes["headings"] = sc.add_line_segments(
            "/world/headings", seg, colors=HEADING, thickness=2.0, thickness_units="screen")
        self.nodes["robots"] = sc.add_point_cloud(
            "/world/robots", one, colors=ROBOT, point_size=ROBOT_SIZE, point_shape="circle",
            precision="float32", point_shading="flat")
        self.nodes["gbest"] = sc.add_point_cloud(
            "/world/gbest", one, colors=GBEST, point_size=0.4, point_shape="diamond",
            precision="float32", point_shading="flat")
        self.built_revision = scene_revision
        self.drawn_revision = -1

    # ------------------------------------------------------------------ per frame
    def view_points(self, world: np.ndarray, z: float = 0.0) -> np.ndarray:
        """World (…, d) → view (…, 3) float32, before the follow offset (which moves ``/world``)."""
        return _z(np.asarray(world, dtype=float) * self.scale, z)

    to_view = view_points  # the name GhostLayer draws with

    def _name(self, key: str) -> str:
        return f"/world/{key}"

    def _twin_size(self) -> float:
        return ROBOT_SIZE

    def to_scene(self, xy: np.ndarray) -> np.ndarray:
        """World (…, d) → scene (…, 2) coordinates, the follow offset included (as the camera sees them)."""
        return (_z(np.asarray(xy, dtype=float))[..., :2] - self.offset) * self.scale

    def follow(self, x: np.ndarray) -> bool:
        """Shift the view when the swarm leaves the arena square but would fit in one (a 1-D swarm
        drifting along x); a swarm spread wider than the arena keeps the home view. Returns True
        if the view moved."""
        if x.size == 0:
            return False
        xy = _z(x)[:, :2].astype(float)
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        half = self.half_size

        def within(centre: np.ndarray) -> bool:
            return bool(np.all(lo >= centre - half) and np.all(hi <= centre + half))

        if within(np.zeros(2)) or np.any(hi - lo > 2 * half):
            target = np.zeros(2)  # in the arena, or too spread to frame (a diverging swarm): home view
        elif within(self.offset):
            return False  # still in the shifted view
        else:
            target = 0.5 * (lo + hi)
        if np.allclose(target, self.offset):
            return False
        self.offset = target
        self.nodes["world"].position = (float(-target[0] * self.scale), float(-target[1] * self.scale), 0.0)
        return True

    def draw(self, snap: Snapshot) -> None:
        """Push one snapshot into the batched nodes (nothing before the first ``rebuild``)."""
        n = self.nodes
        if "robots" not in n:
            return
        self.follow(snap.x)
        n["robots"].points = self.view_points(snap.x, 0.02)
        n["pbests"].points = self.view_points(snap.y, 0.005)
        n["gbest"].points = self.view_points(snap.yg[None, :], 0.012)
        n["pbests"].visible = n["gbest"].visible = snap.live  # a recorded frame has no bests
        start = self.view_points(snap.x, 0.015)
        tip = start.copy()
        tip[:, 0] += 0.35 * np.cos(snap.heading)
        tip[:, 1] += 0.35 * np.sin(snap.heading)
        n["headings"].points = np.stack([start, tip], axis=1)
        tr = snap.trails
        if tr.ndim == 3 and tr.shape[0] and tr.shape[1] >= 2:
            pts = self.view_points(tr, 0.0)
            segs = np.stack([pts[:, :-1], pts[:, 1:]], axis=2).reshape(-1, 2, 3)
        else:
            segs = np.repeat(start[:1, None, :], 2, axis=1) if len(start) else np.zeros((1, 2, 3), np.float32)
        n["trails"].points = segs
        self.draw_ghosts(snap.ghosts if snap.live else None)  # SLO positions: the selected robot's beliefs
        self.drawn_revision = snap.revision

    def draw_twin(self, view: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Swarm B (compare): teal dots just under A's robots and teal trails; hidden without B."""
        n = self.nodes
        if "robots" not in n:
            return
        if view is None:
            for key in ("twin", "twin_trails"):
                if key in n:
                    n[key].visible = False
            return
        if "twin" not in n:
            one, seg = np.zeros((1, 3), np.float32), np.zeros((1, 2, 3), np.float32)
            n["twin_trails"] = self.scene.add_line_segments(
                "/world/twin_trails", seg, colors=TWIN_TRAIL, thickness=1.5, thickness_units="screen")
            n["twin"] = self.scene.add_point_cloud(
                "/world/twin", one, colors=TWIN, point_size=ROBOT_SIZE, point_shape="circle", precision="float32",
                point_shading="flat")
        x, trails = view
        n["twin"].points = self.view_points(x, 0.018)
        segs = trail_segments(trails)
        n["twin_trails"].points = self.view_points(segs, -0.001) if len(segs) else np.zeros((1, 2, 3), np.float32)
        n["twin"].visible, n["twin_trails"].visible = True, bool(len(segs))
