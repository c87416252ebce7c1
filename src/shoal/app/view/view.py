"""The arena of one tab: a :class:`~.canvas.Canvas`, the layers a scene kind draws on it, and
a :class:`Camera` that says where the world sits on screen.

``rebuild`` (a new static scene) forgets every node; the next ``draw`` builds the layers'
static nodes for the snapshot's scene, fitted to the camera's home and what it names as of
interest (the robots, a source: a rebuild that moved the source 2 km away shows it), and calls
the ``fit`` hook with the scene's extent; then every ``draw`` moves the nodes that follow the
snapshot. A camera whose ``home`` changes (a fleet's zoom) builds the scene again at the new
scale; ``fit_all`` does so at once, ``follow_swarm`` keeps the swarm in the middle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Protocol, Sequence

import numpy as np

from ..session.snapshot import Snapshot
from .camera import VIEW_HALF, Viewport
from .canvas import Canvas
from .layers import Layer, LegendEntry, ScaleBar
from .shapes import plane

Fit = Callable[[float, float], None]  # half width and half height of the scene just built, scene units


@dataclass(frozen=True)
class Home:
    """Where the world sits: ``centre`` (m) at the scene origin, ``scale`` scene units a metre,
    and the half extents (m) of what should be on screen."""

    centre: tuple[float, float]
    scale: float
    half: tuple[float, float]


class Camera(Protocol):
    def home(self, snap: Snapshot) -> Home: ...

    def reset(self) -> None:
        """The scene was built again (forget what was followed)."""
        ...

    def follow(self, canvas: Canvas, snap: Snapshot) -> None:
        """Move ``canvas.focus`` to keep what matters in view."""
        ...

    def interest(self, snap: Snapshot) -> np.ndarray:
        """World points (m, (P, 2)) a fitted view keeps on screen besides its home (robots, a source)."""
        ...


MAX_FIT = 1e3  # a fitted view spans at most this many times the home's extent (a diverged swarm)
FIT_MARGIN = 1.08


def fitted(home: Home, points: np.ndarray) -> tuple[Home, np.ndarray]:
    """``home`` widened (a smaller scale, the same centre, so the static scene stays where it is)
    until the box round it and every finite point of ``points`` fits on screen, and the world
    point to put in the middle of the screen: ``home`` and its centre when they already fit."""
    pts = plane(np.asarray(points, dtype=float)).reshape(-1, 2)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    c, h = np.array(home.centre), np.array(home.half)
    if not len(pts) or (np.all(pts >= c - h) and np.all(pts <= c + h)):
        return home, c
    lo, hi = np.minimum(c - h, pts.min(axis=0)), np.maximum(c + h, pts.max(axis=0))
    grow = float(np.max((hi - lo) / 2 / h)) * FIT_MARGIN
    if grow > MAX_FIT:
        return Home(home.centre, home.scale / MAX_FIT, (float(h[0] * MAX_FIT), float(h[1] * MAX_FIT))), c
    return Home(home.centre, home.scale / grow, (float(h[0] * grow), float(h[1] * grow))), (lo + hi) / 2


def swarm_middle(snap: Snapshot) -> np.ndarray | None:
    """The middle of the robots still running (all of them when none is), None without a finite one."""
    x = plane(snap.x)
    alive = x[snap.status == 0] if snap.status is not None and np.any(snap.status == 0) else x
    alive = alive[np.all(np.isfinite(alive), axis=1)]
    return alive.mean(axis=0) if len(alive) else None


def arena_home(snap: Snapshot, centre: np.ndarray | None = None) -> Home:
    """The arena square (``arena.half_size``) filling ``VIEW_HALF`` scene units around ``centre``."""
    half = float(snap.scenario.arena.half_size)
    c = np.zeros(2) if centre is None else np.asarray(centre, dtype=float)
    return Home((float(c[0]), float(c[1])), VIEW_HALF / half, (half, half))


class KeepSwarmInView:
    """Shift the view when the swarm leaves the arena square but would fit in one (a 1-D
    swarm drifting along x, a random walk); a swarm spread wider than the arena keeps the home
    view. ``home_first``: back to the home view as soon as the swarm fits there again."""

    def __init__(self, centre: Callable[[Snapshot], np.ndarray] | None = None, *, home_first: bool = True) -> None:
        self.centre, self.home_first = centre, home_first

    def home(self, snap: Snapshot) -> Home:
        return arena_home(snap, self.centre(snap) if self.centre is not None else None)

    def reset(self) -> None:
        pass

    def interest(self, snap: Snapshot) -> np.ndarray:
        return plane(snap.x)

    def follow(self, canvas: Canvas, snap: Snapshot) -> None:
        x = plane(snap.x)
        if x.size == 0:
            return
        lo, hi = x.min(axis=0), x.max(axis=0)
        half = float(snap.scenario.arena.half_size)
        (lo0, lo1), (hi0, hi1) = lo.tolist(), hi.tolist()  # (plain floats: this runs every draw of every tab)

        def within(c: np.ndarray) -> bool:
            c0, c1 = float(c[0]), float(c[1])
            return lo0 >= c0 - half and lo1 >= c1 - half and hi0 <= c0 + half and hi1 <= c1 + half

        home, spread = canvas.centre, hi0 - lo0 > 2 * half or hi1 - lo1 > 2 * half
        if self.home_first:
            if within(home) or spread:
                target = home  # in the arena, or too spread to frame (a diverging swarm): home view
            elif within(canvas.focus):
                return  # still in the shifted view
            else:
                target = 0.5 * (lo + hi)
        else:
            if within(canvas.focus):
                return
            target = home if within(home) or spread else 0.5 * (lo + hi)
        canvas.set_focus(target)


class View:
    """The arena of one tab for one kind of scene (``name``). ``scene`` is a viser ``SceneApi``."""

    def __init__(self, scene: Any, name: str, camera: Camera, layers: Sequence[Layer], fit: Fit | None = None,
                 labels: Any = None) -> None:
        self.name, self.camera, self.fit = name, camera, fit
        self.layers: tuple[Layer, ...] = (*layers, ScaleBar())
        self.canvas = Canvas(scene, name, labels)
        self.drawn_revision = -1
        self.built_revision = -1
        self._home: Home | None = None  # the scene's home, fitted to what mattered when it was built
        self._base: Home | None = None  # the camera's home it was fitted from
        self._refit = False
        self._restyle = False  # the drawing style changed: lay the layers again at the same home
        self.following = False  # "follow swarm": the swarm's middle stays in the middle of the screen
        self._legend: tuple[tuple[str, int], list[LegendEntry]] | None = None  # (what it was made for, legend)

    # ------------------------------------------------------------------ geometry (clicks, tests)
    @property
    def nodes(self) -> dict[str, Any]:
        return self.canvas.nodes

    @property
    def scale(self) -> float:
        return self.canvas.scale

    @property
    def centre(self) -> np.ndarray:
        return self.canvas.centre

    @property
    def focus(self) -> np.ndarray:
        return self.canvas.focus

    def to_view(self, xy: np.ndarray, z: float = 0.0) -> np.ndarray:
        return self.canvas.to_view(xy, z)

    def to_scene(self, xy: np.ndarray) -> np.ndarray:
        return self.canvas.to_scene(xy)

    def to_world(self, scene_xy: np.ndarray) -> np.ndarray:
        return self.canvas.to_world(scene_xy)

    def ray_to_world(self, origin: Any, direction: Any) -> np.ndarray | None:
        return self.canvas.ray_to_world(origin, direction)

    def layer(self, name: str) -> Layer:
        return next(layer for layer in self.layers if layer.name == name)

    # ------------------------------------------------------------------ lifecycle
    def clear(self) -> None:
        """Remove every node of this view."""
        self.canvas.clear()
        self._home = self._base = None
        self.built_revision = self.drawn_revision = -1

    def fit_all(self) -> None:
        """Build the scene again at the next draw, fitted to the home and everything that matters
        now (the robots wherever they went, a source), and stop following the swarm."""
        self._refit, self.following = True, False
        self.drawn_revision = -1

    def look(self, viewport: Viewport) -> None:
        """The browser's camera moved (a zoom, a pan): draw again what depends on it."""
        if viewport != self.canvas.viewport:
            self.canvas.viewport = viewport
            self.drawn_revision = -1

    def restyle(self, *, light: bool | None = None, text_scale: float | None = None) -> bool:
        """Draw lightly (``light``: dots, no line per robot) or with labels ``text_scale`` times
        their size: the scene is built again at the next draw when either changes. True if it does."""
        c = self.canvas
        light = c.light if light is None else bool(light)
        text_scale = c.text_scale if text_scale is None else float(text_scale)
        if (light, text_scale) == (c.light, c.text_scale):
            return False
        c.light, c.text_scale = light, text_scale
        self._restyle = True  # the next draw lays every layer again, where the view is now
        self.drawn_revision = -1
        return True

    def follow_swarm(self) -> None:
        self.following = True
        self.drawn_revision = -1

    def rebuild(self, scene_revision: int) -> None:
        """A new static scene: the next ``draw`` builds it."""
        self.clear()
        self.built_revision = scene_revision

    def _build(self, base: Home, snap: Snapshot) -> None:
        home, middle = fitted(base, self.camera.interest(snap))
        self._base, self._refit = base, False
        self._lay(home, middle, snap)

    def _lay(self, home: Home, middle: np.ndarray, snap: Snapshot) -> None:
        """Every layer's static nodes at ``home``, world point ``middle`` in the middle of the screen."""
        self._restyle = False
        self.canvas.reset(np.array(home.centre), home.scale)
        self.camera.reset()
        for layer in self.layers:
            layer.build(self.canvas, snap)
        self.canvas.set_focus(middle)
        self._home = home
        if self.fit is not None:
            self.fit(home.half[0] * home.scale, home.half[1] * home.scale)

    def draw(self, snap: Snapshot) -> None:
        """Push one snapshot into the nodes (nothing before the first ``rebuild``)."""
        if self.built_revision < 0:
            return
        base = self.camera.home(snap)
        if base != self._base or self._refit:
            self._build(base, snap)
        elif self._restyle and self._home is not None:
            self._lay(self._home, self.canvas.focus.copy(), snap)
        if self.following:
            middle = swarm_middle(snap)
            if middle is not None:
                self.canvas.set_focus(middle)
        elif self._home == self._base:  # a view fitted wider than its home keeps what it framed
            self.camera.follow(self.canvas, snap)
        for layer in self.layers:
            layer.draw(self.canvas, snap)
        self.drawn_revision = snap.revision

    def legend(self) -> list[LegendEntry]:
        """What the glyphs on screen stand for: the entries of every layer with a node shown (made
        again only when a node was shown or hidden)."""
        key = (self.canvas.root, self.canvas.shown_revision)
        if self._legend is None or self._legend[0] != key:
            self._legend = (key, [entry for layer in self.layers if any(self.canvas.shown(k) for k in layer.keys)
                                  for entry in layer.legend])
        return self._legend[1]
