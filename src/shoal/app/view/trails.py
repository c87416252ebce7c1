"""Trails sent to the page as appended pieces: never the whole trail again.

viser has no "append" message, so a trail is drawn as several nodes under one group node of the
canvas (``key``: hiding it hides them all). A trail's points are recorded frames
(:class:`~shoal.app.session.history.Trails`: the step of every column and the history's epoch),
and within an epoch the robots at a step never move, so the segment between two consecutive
stride points, once drawn, never changes:

- the closed segments are laid in **pieces** of up to :data:`BLOCK` consecutive segments by step
  number (every robot's segments in one line-segment list): a piece in the middle of the trail is
  created once and removed when the horizon has passed it; the newest piece grows as stride
  points arrive and the oldest shrinks as they leave, and only those two are sent again, every
  ``stride`` steps;
- the **open** piece, from the last stride point to the frame shown (the robots now), is sent
  with every draw (when the frame shown is a stride point, it repeats the last closed segment).

So a step costs about the robots' own update (one segment per trail) plus a piece every stride
steps, whatever the horizon; a new epoch (reset, replay), other trails (the robots' count) or a
scrub far away draws the pieces afresh. In the light drawing the same holds for the dots: every
``every``-th stride point by step number (so a dot stays where it is until it leaves), in
pieces of :data:`BLOCK` dot columns, and the newest point of each trail in the open piece.
"""

from __future__ import annotations

import itertools
import math
from typing import Any, Hashable

import numpy as np

from ..session.history import Trails
from .canvas import Canvas, Colour
from .node_update import set_array

BLOCK = 4  # stride segments (or dot columns) in one piece
TRAIL_DOTS = 16  # dots a trail at most, in the light drawing …
TRAIL_DOT_BUDGET = 4000  # … and all trails together at most (1000 robots: 4 dots each), 2 a trail at least
DOT = 0.07  # scene units: a trail's dot in the light drawing (about 2–3 pixels at the home view)
_PIECES = itertools.count()


def dots_per_trail(trails: int) -> int:
    """The most dots one of ``trails`` trails gets in the light drawing."""
    return max(2, min(TRAIL_DOTS, TRAIL_DOT_BUDGET // max(trails, 1)))


class Pieces:
    """The nodes of one group (``key``) of a canvas, each a piece with an id and its content."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.root: str | None = None  # the canvas build they were drawn in
        self.nodes: dict[Hashable, tuple[Hashable, str]] = {}  # id → (content, canvas key)

    def start(self, canvas: Canvas, shown: bool) -> None:
        """Forget the pieces of an earlier build; show or hide the group."""
        if self.root != canvas.root:
            self.root, self.nodes = canvas.root, {}
        canvas.group(self.key, shown)

    def keep(self, canvas: Canvas, want: dict[Hashable, tuple[Hashable, Any]], make: Any, update: Any) -> None:
        """Make the group hold exactly the pieces ``want`` (id → (content, build: a function giving
        its points)): a piece gone is removed, a new one created, one whose content changed sent again."""
        for pid in [p for p in self.nodes if p not in want]:
            canvas.drop(self.nodes.pop(pid)[1])
        for pid, (content, build) in want.items():
            had = self.nodes.get(pid)
            if had is None:
                key = f"{self.key}/{next(_PIECES)}"
                make(key, build())
                self.nodes[pid] = (content, key)
            elif had[0] != content:
                update(canvas.nodes[had[1]], build())
                self.nodes[pid] = (content, had[1])

    def clear(self, canvas: Canvas) -> None:
        """No pieces (the group hidden)."""
        if self.root == canvas.root:
            for _, key in self.nodes.values():
                canvas.drop(key)
        self.root, self.nodes = canvas.root, {}
        canvas.group(self.key, False)


def _closed(steps: np.ndarray, stride: int) -> np.ndarray:
    """Columns j whose segment j → j + 1 joins two stride points (the frame shown ends the last one
    only if it is a stride point itself)."""
    return np.flatnonzero(np.asarray(steps[1:]) % stride == 0)


def _blocks(cols: np.ndarray, keys: np.ndarray) -> list[tuple[int, list[int]]]:
    """``cols`` grouped by ``keys`` (non-decreasing, one a column): (key, its columns) in order, as
    plain ints (this runs every draw of every tab)."""
    if not len(cols):
        return []
    cut = (np.flatnonzero(keys[1:] != keys[:-1]) + 1).tolist()
    c, k = cols.tolist(), keys.tolist()
    return [(k[a], c[a:b]) for a, b in zip([0, *cut], [*cut, len(c)])]


class TrailDrawing:
    """One layer's trails on a canvas: lines under group ``key``, dots under ``key + "_dots"``."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.lines = Pieces(key)
        self.dots = Pieces(key + "_dots")
        self.every = 0  # dots every this many stride points (kept while it still fits: no dots jump)

    @property
    def keys(self) -> tuple[str, str]:
        return (self.key, self.key + "_dots")

    def hide(self, canvas: Canvas) -> None:
        self.lines.clear(canvas)
        self.dots.clear(canvas)

    def draw(self, canvas: Canvas, trails: Trails, colour: Colour, px: float, z: float, dot: str = "circle") -> None:
        """Trails (M, L, d) as segments ``px`` pixels thick or, in the light drawing, as at most
        :func:`dots_per_trail` dots each, of shape ``dot``."""
        p = np.asarray(trails.points)
        empty = p.ndim != 3 or not p.shape[0] or p.shape[1] < 2
        if canvas.light:
            self.lines.clear(canvas)
            if empty:
                self.dots.clear(canvas)
            else:
                self._dots(canvas, trails, colour, z, dot)
        else:
            self.dots.clear(canvas)
            if empty:
                self.lines.clear(canvas)
            else:
                self._lines(canvas, trails, colour, px, z)

    def _lines(self, canvas: Canvas, trails: Trails, colour: Colour, px: float, z: float) -> None:
        p, steps, s = trails.points, np.asarray(trails.steps), max(int(trails.stride), 1)
        m, last = p.shape[0], len(steps) - 1
        self.lines.start(canvas, True)
        base = (trails.epoch, m, s)

        def segments(cols: Any) -> Any:
            def build() -> np.ndarray:
                j = np.asarray(cols)
                if p.shape[-1] < 2:
                    segs = np.stack([p[:, j], p[:, j + 1]], axis=2)  # (M, S, 2, d)
                    return canvas.to_view(segs.reshape(-1, 2, segs.shape[-1]), z)
                out = np.empty((m, len(j), 2, 3), np.float32)  # (canvas.to_view's numbers, without the stack)
                out[:, :, 0, :2] = (p[:, j, :2] - canvas.centre) * canvas.scale
                out[:, :, 1, :2] = (p[:, j + 1, :2] - canvas.centre) * canvas.scale
                out[..., 2] = z
                return out.reshape(-1, 2, 3)
            return build

        want: dict[Hashable, tuple[Hashable, Any]] = {}
        closed = _closed(steps, s)
        at = steps.tolist()
        for b, cols in _blocks(closed, steps[closed] // (s * BLOCK)):
            want[(*base, b)] = ((at[cols[0]], at[cols[-1] + 1]), segments(cols))
        # (when the frame shown is a stride point itself, the open piece repeats the last closed
        # segment: drawn twice it looks the same, and the node stays instead of going and coming back)
        want["open"] = ((*base, int(steps[last - 1]), int(steps[last])), segments([last - 1]))

        def make(key: str, pts: np.ndarray) -> None:
            canvas.add(key, canvas.scene.add_line_segments(
                canvas.name(key, fresh=True), pts, colors=colour, thickness=px, thickness_units="screen"))

        def update(node: Any, pts: np.ndarray) -> None:
            set_array(node, "points", pts)

        self.lines.keep(canvas, want, make, update)

    def _dots(self, canvas: Canvas, trails: Trails, colour: Colour, z: float, dot: str) -> None:
        p, steps, s = trails.points, np.asarray(trails.steps), max(int(trails.stride), 1)
        m, last = p.shape[0], len(steps) - 1
        need = max(1, math.ceil(last / (dots_per_trail(m) - 1)))  # (the end's dot and one every e before it)
        if not need <= self.every <= need + 1:
            self.every = need
        e = self.every
        self.dots.start(canvas, True)
        base = (trails.epoch, m, s, e, dot)

        def points(cols: Any) -> Any:
            def build() -> np.ndarray:
                return canvas.to_view(p[:, np.asarray(cols)].reshape(-1, p.shape[-1]), z)
            return build

        want: dict[Hashable, tuple[Hashable, Any]] = {}
        head = steps[:last]
        kept = np.flatnonzero((head % s == 0) & ((head // s) % e == 0))
        at = steps.tolist()
        for b, cols in _blocks(kept, head[kept] // (s * e * BLOCK)):
            want[(*base, b)] = ((at[cols[0]], at[cols[-1]]), points(cols))
        want["open"] = ((*base, int(steps[last])), points([last]))

        def make(key: str, pts: np.ndarray) -> None:
            canvas.add(key, canvas.scene.add_point_cloud(
                canvas.name(key, fresh=True), pts, colors=colour, point_size=DOT, point_shape=dot,
                precision="float32", point_shading="flat"))

        def update(node: Any, pts: np.ndarray) -> None:
            set_array(node, "points", pts)

        self.dots.keep(canvas, want, make, update)


def drawn_points(canvas: Canvas, key: str) -> np.ndarray:
    """(P, 3) every point of the pieces under group ``key`` (segments' ends twice): what a page
    shows of one trail drawing (for tests and the Share page's checks)."""
    pts = [np.asarray(node.points).reshape(-1, 3) for k, node in canvas.nodes.items() if k.startswith(key + "/")]
    return np.concatenate(pts) if pts else np.zeros((0, 3), np.float32)
