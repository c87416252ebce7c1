"""The top-down view of an SLO scene: truth against belief.

Drawn with a few batched nodes under one frame ``/slo_<n>``: the true positions (red), the
neighbourhood edges (grey), trails, and for the selected observer robot i (yellow ring) a
ghost at ``x_i + x̂_ij`` for every neighbour j it localised this step, joined to the true
``x_j`` by an error segment coloured from green (small) to red (large) (``ghosts.GhostLayer``,
shared with the fleet and acoustic views). The triangle
inspector adds, for one pair (i, j): the mirror pair x1/x2 (purple), dead reckoning x3
(orange), the previous estimate (grey), the estimate kept (blue ring) and the true B (green).

World units are scaled so the arena square spans ``2 · VIEW_HALF`` view units, as in
``scene.py``; the frame shifts to follow a swarm that leaves the square (a random walk).
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from shoal.presets.models import Scenario

from . import shapes
from .ghosts import GhostLayer
from .scene import ROBOT_SIZE, VIEW_HALF
from .session.snapshot import Snapshot
from .twin_view import TwinLayer, trail_segments

ROBOT = (220, 50, 50)
TRAIL = (150, 175, 255)
EDGE = (175, 175, 175)
ARENA = (40, 40, 40)
SELECTED = (255, 190, 0)
MIRROR = (150, 60, 200)
DEAD_RECKONING = (240, 140, 20)
PREVIOUS = (130, 130, 130)
CHOSEN = (30, 80, 220)
TRUTH = (20, 150, 60)

Z = dict(grid=-0.02, edges=-0.01, trails=-0.005, errors=0.004, inspector=0.006, ghosts=0.008, robots=0.01,
         selected=0.012, points=0.014)

_SERIAL = itertools.count()  # fresh node names for every build (see fleet_scene.py)


def view_centre(scenario: Scenario) -> np.ndarray:
    """World point at the middle of the view: where the swarm starts."""
    slo = scenario.slo
    if slo is not None and slo.swarm == "slo" and slo.motion == "random_walk":
        return np.array([50.0, 50.0])  # the walk starts in [0, 100]² (spec §8)
    return np.zeros(2)


class SLOView(shapes.PointLayer, TwinLayer, GhostLayer):
    """The scene of one tab showing an SLO scene. ``scene`` is a viser ``SceneApi``."""

    def __init__(self, scene: Any) -> None:
        self.scene = scene
        self.nodes: dict[str, Any] = {}
        self.scale = 1.0
        self.half = VIEW_HALF
        self.centre = np.zeros(2)  # world point at the origin of the frame
        self.focus = np.zeros(2)  # world point at the middle of the screen
        self.drawn_revision = -1
        self.built_revision = -1
        self._root = "/slo"

    # ------------------------------------------------------------------ transforms
    def to_view(self, xy: np.ndarray, z: float = 0.0) -> np.ndarray:
        return shapes.lift((np.asarray(xy, dtype=float) - self.centre) * self.scale, z)

    def to_scene(self, xy: np.ndarray) -> np.ndarray:
        return (np.asarray(xy, dtype=float) - self.focus) * self.scale

    def to_world(self, scene_xy: np.ndarray) -> np.ndarray:
        return np.asarray(scene_xy, dtype=float)[..., :2] / self.scale + self.focus

    def ray_to_world(self, origin: Any, direction: Any) -> np.ndarray | None:
        o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
        if abs(d[2]) < 1e-9 or -o[2] / d[2] < 0:
            return None
        return self.to_world((o + (-o[2] / d[2]) * d)[:2])

    def _twin_size(self) -> float:
        return ROBOT_SIZE

    # ------------------------------------------------------------------ lifecycle
    def clear(self) -> None:
        for node in reversed(list(self.nodes.values())):
            node.remove()
        self.nodes.clear()
        self.built_revision = self.drawn_revision = -1

    def _name(self, key: str) -> str:
        return f"{self._root}/{key}"

    def rebuild(self, scenario: Scenario, scene_revision: int) -> None:
        self.clear()
        sc = self.scene
        half = float(scenario.arena.half_size)
        self.scale, self.half = VIEW_HALF / half, half
        self.centre = view_centre(scenario)
        self.focus = self.centre.copy()
        self._root = f"/slo_{next(_SERIAL)}"
        self.nodes["root"] = sc.add_frame(self._root, show_axes=False)
        self.nodes["grid"] = sc.add_grid(
            self._name("grid"), width=2 * VIEW_HALF, height=2 * VIEW_HALF, plane="xy", cell_size=VIEW_HALF / 10,
            section_size=VIEW_HALF / 2, cell_color=(228, 228, 224), section_color=(200, 200, 196),
            position=(0.0, 0.0, Z["grid"]), shadow_opacity=0.0, infinite_grid=False, fade_distance=1e4)
        c = self.centre
        square = np.array([[c[0] - half, c[1] - half], [c[0] + half, c[1] - half], [c[0] + half, c[1] + half],
                           [c[0] - half, c[1] + half]])
        self._lines("arena", shapes.polyline(square, closed=True), ARENA, 2.5, 0.0)
        self.built_revision = scene_revision
        self.drawn_revision = -1

    # ------------------------------------------------------------------ node helpers
    def _lines(self, key: str, segs: np.ndarray, color: Any, px: float, z: float) -> None:
        segs = np.asarray(segs, dtype=float).reshape(-1, 2, 2)
        pts = self.to_view(segs, z) if len(segs) else np.zeros((1, 2, 3), np.float32)
        node = self.nodes.get(key)
        if isinstance(color, np.ndarray) and not len(segs):
            color = np.zeros((1, 2, 3), np.uint8)
        if node is None:
            self.nodes[key] = self.scene.add_line_segments(
                self._name(key), pts, colors=color, thickness=px, thickness_units="screen")
        else:
            node.points = pts
            if isinstance(color, np.ndarray):
                node.colors = color
        self.nodes[key].visible = bool(len(segs))

    def _label(self, key: str, text: str, xy: np.ndarray | None) -> None:
        node = self.nodes.get(key)
        ok = xy is not None and bool(np.all(np.isfinite(xy)))
        pos = tuple(float(v) for v in self.to_view(xy + 0.5 / self.scale, 0.02)) if ok else (0.0, 0.0, 0.0)
        if node is None:
            self.nodes[key] = self.scene.add_label(self._name(key), text, position=pos)
        else:
            node.position = pos
        self.nodes[key].visible = ok

    # ------------------------------------------------------------------ per frame
    def _follow(self, x: np.ndarray) -> None:
        lo, hi = x.min(axis=0), x.max(axis=0)
        half = self.half

        def within(c: np.ndarray) -> bool:
            return bool(np.all(lo >= c - half) and np.all(hi <= c + half))

        if within(self.focus):
            return
        target = self.centre if within(self.centre) or np.any(hi - lo > 2 * half) else 0.5 * (lo + hi)
        if not np.allclose(target, self.focus):
            self.focus = np.asarray(target, dtype=float)
            off = (self.centre - self.focus) * self.scale
            self.nodes["root"].position = (float(off[0]), float(off[1]), 0.0)

    def draw(self, snap: Snapshot) -> None:
        if self.built_revision < 0:
            return
        x = snap.x
        self._follow(x)
        self._lines("edges", snap.extras["edges"], EDGE, 1.0, Z["edges"])
        self._lines("trails", trail_segments(snap.trails), TRAIL, 1.2, Z["trails"])
        self._points("robots", x, ROBOT, ROBOT_SIZE, "circle", Z["robots"])
        xi = x[snap.selected]
        self._lines("selected", shapes.circle_segments(xi, 1.7 * ROBOT_SIZE / self.scale, 32), SELECTED, 3.0,
                    Z["selected"])
        self.draw_ghosts(snap.ghosts)  # the observer's beliefs
        self._draw_pair(snap)
        self.drawn_revision = snap.revision

    def _draw_pair(self, snap: Snapshot) -> None:
        p = snap.extras["pair"]
        if p is None:
            for key in ("tri_truth", "tri_mirror", "tri_dr"):
                self._lines(key, np.zeros((0, 2, 2)), EDGE, 1.0, Z["inspector"])
            for key in ("mirror", "dr", "prev", "chosen", "truth"):
                self._points(key, np.zeros((0, 2)), EDGE, 0.1, "circle", Z["points"])
            for key in ("label_x1", "label_x2", "label_x3"):
                self._label(key, key[-2:], None)
            return
        a, (x1, x2, x3) = p.a, p.candidates
        truth = [[a, p.b]]
        self._lines("tri_truth", np.array(truth), TRUTH, 2.0, Z["inspector"])
        mirror = [[a, c] for c in (x1, x2) if np.all(np.isfinite(c))]
        if np.all(np.isfinite(x1)) and np.all(np.isfinite(x2)):
            mirror += list(shapes.dashed(x1, x2, 0.6 / self.scale, 0.4 / self.scale))
        self._lines("tri_mirror", np.array(mirror).reshape(-1, 2, 2), MIRROR, 1.5, Z["inspector"])
        dr = shapes.dashed(a, x3, 0.5 / self.scale, 0.3 / self.scale) if np.all(np.isfinite(x3)) else np.zeros(
            (0, 2, 2))
        self._lines("tri_dr", dr, DEAD_RECKONING, 1.5, Z["inspector"])
        self._points("mirror", np.array([x1, x2]), MIRROR, 0.6 * ROBOT_SIZE, "square", Z["points"])
        self._points("dr", x3[None], DEAD_RECKONING, 0.6 * ROBOT_SIZE, "square", Z["points"])
        self._points("prev", p.prev[None], PREVIOUS, 0.5 * ROBOT_SIZE, "circle", Z["points"])
        self._points("chosen", p.chosen[None], CHOSEN, 1.1 * ROBOT_SIZE, "circle", Z["ghosts"] - 0.001)
        self._points("truth", p.b[None], TRUTH, 1.3 * ROBOT_SIZE, "circle", Z["robots"] - 0.001)
        self._label("label_x1", "x1", x1)
        self._label("label_x2", "x2", x2)
        self._label("label_x3", "x3", x3)
