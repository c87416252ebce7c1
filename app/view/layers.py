"""What every arena can draw, whatever the kind: a :class:`Layer` draws its nodes on a
:class:`~.canvas.Canvas` from a :class:`~shoal.app.session.snapshot.Snapshot` and names what
they mean (:class:`LegendEntry`), so a legend can be built from the layers drawn.

A kind's view is a list of these (each with the kind's colours, sizes and heights) plus the
kind's own layers. Sizes are in scene units; a :data:`Size` may also depend on the canvas and
the snapshot (markers sized in metres). Heights ``z`` order the layers in the top view.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol, Union

import numpy as np

from shoal.engine.core.objectives import Objective
from shoal.presets.models import Scenario

from ..session.snapshot import Snapshot
from .canvas import Canvas, Colour
from .shapes import circle_segments, plane, polyline, trail_segments

Size = Union[float, Callable[[Canvas, Snapshot], float]]

TWIN = (20, 170, 180)  # swarm B's robots
TWIN_TRAIL = (150, 215, 220)  # B's trails
GHOST = (60, 110, 230)
GHOST_BEST = (30, 80, 220)
ERR_LOW = np.array([40, 170, 70], float)
ERR_HIGH = np.array([230, 40, 40], float)
EMPTY_POINTS = np.zeros((0, 2))


@dataclass(frozen=True)
class LegendEntry:
    """One line of a legend: a glyph (●, ■, ◆, ○, —) in a colour, and what it stands for."""

    glyph: str
    colour: Colour
    label: str


class Layer(Protocol):
    name: str  # unique in its view
    keys: tuple[str, ...]  # the canvas nodes it draws
    legend: tuple[LegendEntry, ...]

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        """Static nodes, once per (re)built scene."""
        ...

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        """Nodes that follow the snapshot."""
        ...


def size_of(size: Size, canvas: Canvas, snap: Snapshot) -> float:
    return size(canvas, snap) if callable(size) else float(size)


def metres(m: float) -> Callable[[Canvas, Snapshot], float]:
    """A marker ``m`` metres across in the world, whatever the scale."""
    return lambda canvas, snap: m * canvas.scale


class Static:
    """Base of layers with nothing to build or nothing to draw."""

    name = ""
    keys: tuple[str, ...] = ()
    legend: tuple[LegendEntry, ...] = ()

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        pass

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        pass


# ---------------------------------------------------------------------------- ground
class Ground(Static):
    """The arena square around its centre: a grid and a border."""

    name = "ground"
    keys = ("grid", "arena")

    def __init__(self, *, cell: Callable[[float], float], cell_colour: Colour, section_colour: Colour, z: float,
                 border: Colour, border_px: float, border_z: float, fade: float = 1e4) -> None:
        """``cell``: half size (m) → grid cell (m); sections are 5 cells."""
        self.cell, self.cell_colour, self.section_colour, self.z = cell, cell_colour, section_colour, z
        self.border, self.border_px, self.border_z, self.fade = border, border_px, border_z, fade

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        half = float(snap.scenario.arena.half_size)
        side, cell = 2 * half * canvas.scale, self.cell(half) * canvas.scale
        canvas.add("grid", canvas.scene.add_grid(
            canvas.name("grid"), width=side, height=side, plane="xy", cell_size=float(cell),
            section_size=float(5 * cell), cell_color=self.cell_colour, section_color=self.section_colour,
            position=(0.0, 0.0, self.z), shadow_opacity=0.0, infinite_grid=False, fade_distance=self.fade))
        c = canvas.centre
        box = c + half * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
        canvas.lines("arena", polyline(box, closed=True), self.border, self.border_px, self.border_z)


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


class Landscape(Static):
    """The objective as a heat map under the arena (when ``objective`` gives one)."""

    name = "landscape"
    keys = ("landscape",)
    legend = (LegendEntry("■", (40, 90, 160), "objective (dark: low)"),)

    def __init__(self, objective: Callable[[Scenario], Objective | None], z: float) -> None:
        self.objective, self.z = objective, z

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        objective = self.objective(snap.scenario)
        if objective is None:
            return
        half = float(snap.scenario.arena.half_size)
        side = 2 * half * canvas.scale
        canvas.add("landscape", canvas.scene.add_image(
            canvas.name("landscape"), landscape_rgb(objective, half), render_width=side, render_height=side,
            position=(0.0, 0.0, self.z), cast_shadow=False, receive_shadow=False))


# ---------------------------------------------------------------------------- robots
class Robots(Static):
    """Run 0's robots as discs (``collided``: a colour of their own for disabled robots)."""

    name = "robots"
    keys = ("robots",)

    def __init__(self, colour: Colour, size: Size, z: float, *, collided: Colour | None = None) -> None:
        self.colour, self.size, self.z, self.collided = colour, size, z, collided
        self.legend = (LegendEntry("●", colour, "robot"),) + (
            (LegendEntry("●", collided, "collided robot"),) if collided is not None else ())

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        colour: Colour | np.ndarray = self.colour
        if self.collided is not None:
            colour = np.where((snap.status != 0)[:, None], self.collided, self.colour).astype(np.uint8)
        canvas.points("robots", snap.x, colour, size_of(self.size, canvas, snap), "circle", self.z)


class Headings(Static):
    """A short stroke from each robot along its heading (or the direction ``angle`` gives)."""

    name = "headings"
    keys = ("headings",)

    def __init__(self, colour: Colour, length: Callable[[Canvas, Snapshot], float], z: float, *,
                 angle: Callable[[Snapshot], np.ndarray] | None = None, px: float = 2.0) -> None:
        """``length`` in metres."""
        self.colour, self.length, self.z, self.angle, self.px = colour, length, z, angle, px
        self.legend = (LegendEntry("—", colour, "heading"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        x = plane(snap.x)
        a = self.angle(snap) if self.angle is not None else snap.heading
        tip = x + self.length(canvas, snap) * np.column_stack([np.cos(a), np.sin(a)])
        canvas.lines("headings", np.stack([x, tip], axis=1), self.colour, self.px, self.z)


class Trails(Static):
    """Each robot's path over the last ``view.trail_seconds``."""

    name = "trails"
    keys = ("trails",)

    def __init__(self, colour: Colour, px: float, z: float) -> None:
        self.colour, self.px, self.z = colour, px, z
        self.legend = (LegendEntry("—", colour, "trail"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        canvas.lines("trails", trail_segments(snap.trails), self.colour, self.px, self.z)


class PersonalBests(Static):
    """Each robot's personal best (a square) on a live frame."""

    name = "pbests"
    keys = ("pbests",)

    def __init__(self, colour: Colour, size: Size, z: float) -> None:
        self.colour, self.size, self.z = colour, size, z
        self.legend = (LegendEntry("■", colour, "personal best"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        y = snap.y if snap.live and snap.y is not None else EMPTY_POINTS
        canvas.points("pbests", y, self.colour, size_of(self.size, canvas, snap), "square", self.z)


class GlobalBest(Static):
    """The swarm's global best (a diamond) on a live frame."""

    name = "gbest"
    keys = ("gbest",)

    def __init__(self, colour: Colour, size: Size, z: float) -> None:
        self.colour, self.size, self.z = colour, size, z
        self.legend = (LegendEntry("◆", colour, "global best"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        yg = snap.yg[None] if snap.live and snap.yg is not None else EMPTY_POINTS
        canvas.points("gbest", yg, self.colour, size_of(self.size, canvas, snap), "diamond", self.z)


class Selected(Static):
    """A ring round the selected robot (``live_only``: not on recorded frames)."""

    name = "selected"
    keys = ("selected",)

    def __init__(self, colour: Colour, radius: Callable[[Canvas, Snapshot], float], z: float, *, px: float = 3.0,
                 segments: int = 32, live_only: bool = False) -> None:
        """``radius`` in metres."""
        self.colour, self.radius, self.z, self.px = colour, radius, z, px
        self.segments, self.live_only = segments, live_only
        self.legend = (LegendEntry("○", colour, "selected robot"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        if self.live_only and not snap.live:
            segs = np.zeros((0, 2, 2))
        else:
            segs = circle_segments(plane(snap.x[snap.selected]), self.radius(canvas, snap), self.segments)
        canvas.lines("selected", segs, self.colour, self.px, self.z)


# ---------------------------------------------------------------------------- swarm B and beliefs
class Twin(Static):
    """Swarm B (compare): its robots just under A's and its trails, in teal; hidden without B."""

    name = "twin"
    keys = ("twin", "twin_trails")
    legend = (LegendEntry("●", TWIN, "swarm B"), LegendEntry("—", TWIN_TRAIL, "swarm B's trail"))

    def __init__(self, size: Size, z: tuple[float, float], px: float = 1.2) -> None:
        self.size, self.z, self.px = size, z, px

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        if snap.twin is None:
            canvas.hide(*self.keys)
            return
        x, trails = snap.twin
        canvas.points("twin", x, TWIN, size_of(self.size, canvas, snap), "circle", self.z[0])
        canvas.lines("twin_trails", trail_segments(trails), TWIN_TRAIL, self.px, self.z[1])


def error_colors(err: np.ndarray, scale: float) -> np.ndarray:
    """(G, 2, 3) uint8: green for no error to red at ``scale`` and beyond."""
    f = np.clip(np.asarray(err, dtype=float) / max(scale, 1e-12), 0.0, 1.0)[:, None]
    rgb = (ERR_LOW + (ERR_HIGH - ERR_LOW) * f).astype(np.uint8)
    return np.repeat(rgb[:, None, :], 2, axis=1)


class Ghosts(Static):
    """The selected robot's beliefs: a ghost (blue diamond) where it believes each robot it
    localised is, joined to the truth by a segment from green (no error) to red; the large
    ghost is where it believes the global best is. Hidden on true positions and recorded frames."""

    name = "ghosts"
    keys = ("ghost_errors", "ghosts", "ghost_best", "ghost_best_error")
    legend = (LegendEntry("◆", GHOST, "believed position"), LegendEntry("—", (40, 170, 70), "belief error"),
              LegendEntry("◆", GHOST_BEST, "believed global best"))

    def __init__(self, size: Size, z: tuple[float, float] = (0.004, 0.008)) -> None:
        """``size``: a robot's marker size (ghosts are a little smaller)."""
        self.size, self.z = size, z

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        g = snap.ghosts
        if g is None:
            canvas.hide(*self.keys)
            return
        z_err, z_ghost = self.z
        size = size_of(self.size, canvas, snap)
        errs = np.stack([g.points, g.truth], axis=1) if len(g.of) else np.zeros((0, 2, 2))
        canvas.lines("ghost_errors", errs, error_colors(g.error, g.scale), 2.0, z_err)
        canvas.points("ghosts", g.points, GHOST, 0.8 * size, "diamond", z_ghost)
        if g.best is None or g.true_best is None:
            canvas.hide("ghost_best", "ghost_best_error")
            return
        err = float(np.hypot(*(g.best - g.true_best)))
        canvas.lines("ghost_best_error", np.stack([g.best, g.true_best])[None],
                     error_colors(np.array([err]), g.scale), 1.5, z_err)
        canvas.points("ghost_best", g.best[None], GHOST_BEST, 1.2 * size, "diamond", z_ghost)
