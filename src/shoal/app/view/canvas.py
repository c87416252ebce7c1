"""The scene nodes of one view, under one root frame, and the map between world metres and
scene coordinates.

The world is drawn scaled by ``scale`` (scene units per metre) around ``centre``, the world
point at the root frame's origin; ``focus`` is the world point in the middle of the screen
(the camera looks straight down at the scene origin), and moving it moves the root frame.
Nodes are batched: one point cloud or one segment list per key, created on first use and
hidden when they have nothing to show.

Two styles of drawing, both read by the layers: ``light`` (a page drawn without a GPU: dots for
what would be a line per robot, no heading strokes) and ``text_scale`` (the labels' size, a
projector); a change of either builds the scene again (:meth:`~.view.View.restyle`).

A label is text at a world point. On a browser's page it is HTML over the canvas (``labels``,
:mod:`.overlay`: sharp at the light drawing's half resolution, sized by the page's projector
mode), placed by an invisible node of the scene; elsewhere (a Share page) a viser label.
"""

from __future__ import annotations

import itertools
from typing import Any, Callable

import numpy as np

from .camera import Viewport
from .node_update import set_array
from .shapes import lift, plane, ray_ground

# Every build of a scene gets a root name never used before (and so do re-created nodes that
# ask for one): viser lets a create supersede a pending remove of the same name in its send
# queue, which can reorder a subtree's removal and re-creation and leave the scene empty.
_SERIAL = itertools.count()

Colour = tuple[int, int, int]


class Canvas:
    """Nodes (``nodes``: key → viser handle) of one view on a viser ``SceneApi``."""

    def __init__(self, scene: Any, prefix: str, labels: Any = None) -> None:
        self.scene, self.prefix = scene, prefix
        self.labels = labels  # the page's HTML labels (overlay.Labels), None: viser's labels
        self.texts: dict[str, str] = {}  # label key → its text (what the page shows)
        self.nodes: dict[str, Any] = {}
        self.root = f"/{prefix}"
        self.scale = 1.0
        self.centre = np.zeros(2)
        self.focus = np.zeros(2)
        self.viewport = Viewport()  # what the browser's camera shows (a scale bar follows its zoom)
        self.light = False  # light drawing: no line per robot (see the module's docstring)
        self.text_scale = 1.0  # labels' size
        self.shown_revision = 0  # bumps whenever a node is shown or hidden (a legend follows it)

    # ------------------------------------------------------------------ lifecycle
    def reset(self, centre: np.ndarray, scale: float) -> None:
        """Drop every node and start a fresh root frame with world ``centre`` in the middle."""
        self.clear()
        self.centre = np.asarray(centre, dtype=float).copy()
        self.focus = self.centre.copy()
        self.scale = float(scale)
        self.root = self.name(self.prefix, fresh=True, under_root=False)
        self.nodes["root"] = self.scene.add_frame(self.root, show_axes=False)

    def clear(self) -> None:
        for node in reversed(list(self.nodes.values())):
            node.remove()
        if self.labels is not None and self.texts:
            self.labels.drop([self.name_of(key) for key in self.texts])
        self.nodes.clear()
        self.shown_revision += 1
        self.texts.clear()

    def name_of(self, key: str) -> str:
        """The scene path of the node kept as ``key``."""
        return str(self.nodes[key].name) if key in self.nodes else self.name(key)

    def name(self, key: str, fresh: bool = False, under_root: bool = True) -> str:
        """The scene path of node ``key`` (``fresh``: a name not used before, for a re-created node)."""
        base = f"{self.root}/{key}" if under_root else f"/{key}"
        return base + (f"_{next(_SERIAL)}" if fresh else "")

    def add(self, key: str, node: Any) -> Any:
        """Keep ``node`` as ``key`` (a node made by a layer itself: meshes, grids, images)."""
        self.nodes[key] = node
        self.shown_revision += 1
        return node

    def drop(self, key: str) -> None:
        node = self.nodes.pop(key, None)
        if node is not None:
            node.remove()
            self.shown_revision += 1
        if self.texts.pop(key, None) is not None and self.labels is not None and node is not None:
            self.labels.drop([str(node.name)])

    def hide(self, *keys: str) -> None:
        for key in keys:
            if key in self.nodes:
                self.show(key, False)

    def show(self, key: str, shown: bool = True) -> None:
        """Show (or hide) node ``key``; a change bumps ``shown_revision``."""
        node = self.nodes[key]
        if bool(node.visible) != shown:
            node.visible = shown
            self.shown_revision += 1

    def group(self, key: str, shown: bool) -> None:
        """A frame node ``key`` whose children (nodes keyed ``key/…``) are shown and hidden with it."""
        if key not in self.nodes:
            self.nodes[key] = self.scene.add_frame(self.name(key), show_axes=False)
            self.shown_revision += 1
        self.show(key, shown)

    def shown(self, key: str) -> bool:
        node = self.nodes.get(key)
        return node is not None and bool(node.visible)

    # ------------------------------------------------------------------ coordinates
    def to_view(self, xy: np.ndarray, z: float = 0.0) -> np.ndarray:
        """World metres (…, d) → coordinates under the root frame (…, 3) float32."""
        return lift((plane(xy) - self.centre) * self.scale, z)

    def to_scene(self, xy: np.ndarray) -> np.ndarray:
        """World metres (…, d) → scene coordinates (…, 2), as the camera sees them."""
        return (plane(xy) - self.focus) * self.scale

    def to_world(self, scene_xy: np.ndarray) -> np.ndarray:
        """Scene coordinates (what clicks and drags report) → world metres."""
        return np.asarray(scene_xy, dtype=float)[..., :2] / self.scale + self.focus

    def ray_to_world(self, origin: Any, direction: Any) -> np.ndarray | None:
        """Where a click ray meets the ground (z = 0), in world metres; None if it misses."""
        p = ray_ground(origin, direction)
        return None if p is None else self.to_world(p)

    def set_focus(self, target: np.ndarray) -> bool:
        """Put world point ``target`` in the middle of the screen; True if the view moved."""
        target = np.asarray(target, dtype=float)
        if all(abs(t - f) <= 1e-8 + 1e-5 * abs(f) for t, f in zip(target.tolist(), self.focus.tolist())):
            return False  # (numpy's allclose, on two plain floats: this runs every draw of every tab)
        self.focus = target.copy()
        off = (self.centre - self.focus) * self.scale
        self.nodes["root"].position = (float(off[0]), float(off[1]), 0.0)
        return True

    # ------------------------------------------------------------------ batched nodes
    def points(self, key: str, xy: np.ndarray, color: Colour | np.ndarray, size: float, shape: str, z: float) -> None:
        """One point cloud: ``size`` in scene units, ``color`` one RGB or one per point."""
        xy = np.asarray(xy, dtype=float)
        xy = plane(xy.reshape(-1, xy.shape[-1]))
        per_point = color if isinstance(color, np.ndarray) and color.ndim == 2 else None  # one RGB per point
        ok = np.isfinite(xy)
        if not ok.all():  # (a robot gone, a best not yet known)
            finite = ok.all(axis=1)
            xy = xy[finite]
            if per_point is not None:
                per_point = per_point[finite]
        pts = lift(((xy if len(xy) else np.zeros((1, 2))) - self.centre) * self.scale, z)  # (xy is planar already)
        if per_point is not None and not len(xy):
            per_point = np.zeros((1, 3), np.uint8)
        colors = color if per_point is None else per_point
        self._put(key, pts, per_point, bool(len(xy)), lambda: self.scene.add_point_cloud(
            self.name(key), pts, colors=colors, point_size=size, point_shape=shape, precision="float32",
            point_shading="flat"))

    def lines(self, key: str, segs: np.ndarray, color: Colour | np.ndarray, px: float, z: float) -> None:
        """One segment list (S, 2, 2) in world metres: ``px`` screen pixels thick, ``color`` one
        RGB or one per segment end (S, 2, 3); an empty list hides the node."""
        segs = np.asarray(segs, dtype=float).reshape(-1, 2, 2)
        pts = self.to_view(segs, z) if len(segs) else np.zeros((1, 2, 3), np.float32)
        per_segment = color if isinstance(color, np.ndarray) and color.ndim == 3 else None  # one RGB per end
        if per_segment is not None and not len(segs):
            per_segment = np.zeros((1, 2, 3), np.uint8)
        colors = color if per_segment is None else per_segment
        self._put(key, pts, per_segment, bool(len(segs)), lambda: self.scene.add_line_segments(
            self.name(key), pts, colors=colors, thickness=px, thickness_units="screen"))

    def _put(self, key: str, pts: np.ndarray, colors: np.ndarray | None, shown: bool,
             create: Callable[[], Any]) -> None:
        """Create node ``key`` the first time, else send its new points (and ``colors`` when given)."""
        node = self.nodes.get(key)
        if node is None:
            self.nodes[key] = create()
            self.shown_revision += 1
        else:
            set_array(node, "points", pts)
            if colors is not None:
                set_array(node, "colors", colors)
        self.show(key, shown)

    def label(self, key: str, text: str, xy: np.ndarray | None, z: float = 0.0, **style: Any) -> None:
        """A text label at world ``xy`` (hidden when None or not finite); ``style``: viser's
        ``add_label`` keywords (anchor, font size), used when it is created."""
        ok = xy is not None and bool(np.all(np.isfinite(xy)))
        pos = tuple(float(v) for v in self.to_view(np.asarray(xy, dtype=float), z)) if ok else (0.0, 0.0, 0.0)
        node = self.nodes.get(key)
        if self.labels is not None:  # HTML over the canvas, placed by an invisible node
            if node is None:
                node = self.nodes[key] = self.scene.add_frame(self.name(key), show_axes=False, position=pos)
                self.shown_revision += 1
                self.labels.put(str(node.name), text, style.get("anchor", "top-left"),
                                style.get("font_screen_scale", 1.0), True)
            else:
                node.position = pos
                if self.texts.get(key) != text:
                    self.labels.put(str(node.name), text)
            self.texts[key] = text
        elif node is None:
            style["font_screen_scale"] = style.get("font_screen_scale", 1.0) * self.text_scale
            self.nodes[key] = self.scene.add_label(self.name(key), text, position=pos, **style)
            self.shown_revision += 1
        else:
            node.position = pos
            if node.text != text:
                node.text = text
        self.show(key, ok)
