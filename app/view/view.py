"""The arena of one tab: a :class:`~.canvas.Canvas`, the layers a scene kind draws on it, and
a :class:`Camera` that says where the world sits on screen.

``rebuild`` (a new static scene) forgets every node; the next ``draw`` builds the layers'
static nodes for the snapshot's scene and calls the ``fit`` hook with the scene's extent, then
every ``draw`` moves the nodes that follow the snapshot. A camera whose ``home`` changes (a
fleet's zoom) builds the scene again at the new scale.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Protocol, Sequence

import numpy as np

from ..session.snapshot import Snapshot
from .camera import VIEW_HALF
from .canvas import Canvas
from .layers import Layer, LegendEntry
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

    def follow(self, canvas: Canvas, snap: Snapshot) -> None:
        x = plane(snap.x)
        if x.size == 0:
            return
        lo, hi = x.min(axis=0), x.max(axis=0)
        half = float(snap.scenario.arena.half_size)

        def within(c: np.ndarray) -> bool:
            return bool(np.all(lo >= c - half) and np.all(hi <= c + half))

        home, spread = canvas.centre, bool(np.any(hi - lo > 2 * half))
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

    def __init__(self, scene: Any, name: str, camera: Camera, layers: Sequence[Layer], fit: Fit | None = None) -> None:
        self.name, self.camera, self.layers, self.fit = name, camera, tuple(layers), fit
        self.canvas = Canvas(scene, name)
        self.drawn_revision = -1
        self.built_revision = -1
        self._home: Home | None = None

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
        self._home = None
        self.built_revision = self.drawn_revision = -1

    def rebuild(self, scene_revision: int) -> None:
        """A new static scene: the next ``draw`` builds it."""
        self.clear()
        self.built_revision = scene_revision

    def _build(self, home: Home, snap: Snapshot) -> None:
        self.canvas.reset(np.array(home.centre), home.scale)
        self.camera.reset()
        for layer in self.layers:
            layer.build(self.canvas, snap)
        self._home = home
        if self.fit is not None:
            self.fit(home.half[0] * home.scale, home.half[1] * home.scale)

    def draw(self, snap: Snapshot) -> None:
        """Push one snapshot into the nodes (nothing before the first ``rebuild``)."""
        if self.built_revision < 0:
            return
        home = self.camera.home(snap)
        if home != self._home:
            self._build(home, snap)
        self.camera.follow(self.canvas, snap)
        for layer in self.layers:
            layer.draw(self.canvas, snap)
        self.drawn_revision = snap.revision

    def legend(self) -> list[LegendEntry]:
        """What the glyphs on screen stand for: the entries of every layer with a node shown."""
        return [entry for layer in self.layers if any(self.canvas.shown(k) for k in layer.keys)
                for entry in layer.legend]
