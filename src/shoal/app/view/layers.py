"""What every arena can draw, whatever the kind: a :class:`Layer` draws its nodes on a
:class:`~.canvas.Canvas` from a :class:`~shoal.app.session.snapshot.Snapshot` and names what
they mean (:class:`LegendEntry`), so a legend can be built from the layers drawn.

A kind's view is a list of these (each with the kind's colours, sizes and heights) plus the
kind's own layers. Sizes are in scene units; a :data:`Size` may also depend on the canvas and
the snapshot (markers sized in metres). Heights ``z`` order the layers in the top view.

In the light drawing (``canvas.light``, for a page drawn without a GPU, where every line segment
is a few triangles a frame for the CPU to fill) a layer draws no line per robot: trails become a
few dots each, heading strokes are left out; robots are one point cloud either way.

Trails reach the page as appended pieces (:mod:`.trails`); what depends on the camera alone (the
scale bar) is drawn again only when the camera or the scene's scale moved.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Protocol, Union

import numpy as np

from shoal.presets.models import Scenario

from ..session.snapshot import Snapshot
from .canvas import Canvas, Colour
from .palette import Cue, Pair
from .shapes import circle_segments, grid_segments, plane, polyline
from .trails import DOT, TRAIL_DOT_BUDGET, TRAIL_DOTS, TrailDrawing  # noqa: F401  (the light drawing's dots)

Size = Union[float, Callable[[Canvas, Snapshot], float]]

# Swarm A is drawn in reds (each kind's robots and a maroon trail), swarm B in blues, each with a
# second cue: B's robots are squares, its trail thinner (in the light drawing: square dots).
# Colour pairs that carry meaning are listed by each kind (``AppKind.pairs``, view/palette.py).
TWIN = (0, 140, 210)  # swarm B's robots
TWIN_TRAIL = (20, 80, 200)  # B's trails
TRAIL_A = (160, 40, 40)  # A's trails, every kind: dark enough for the heat map (3:1), apart from B's (ΔE ≥ 30)
OUTLINE = (30, 30, 30)  # round the robots of a scene with a heat map: 3:1 against every colour of it
GHOST = (60, 110, 230)
GHOST_BEST = (30, 80, 220)
ERR_SMALL: Colour = (40, 110, 220)  # a belief's error: blue when small …
ERR_LARGE: Colour = (220, 90, 0)  # … orange when large (and drawn thicker: its second cue)
ERR_LOW, ERR_HIGH = np.array(ERR_SMALL, float), np.array(ERR_LARGE, float)
EMPTY_POINTS = np.zeros((0, 2))
EDGE, EDGE_Z = 1.4, 0.0005  # an outline's size over its marker's, and how far under it


@dataclass(frozen=True)
class LegendEntry:
    """One line of a legend: a glyph (●, ■, ◆, ○, —) in a colour, and what it stands for."""

    glyph: str
    colour: Colour
    label: str


class Layer(Protocol):
    @property
    def name(self) -> str:
        """Unique in its view."""
        ...

    @property
    def keys(self) -> tuple[str, ...]:
        """The canvas nodes it draws."""
        ...

    @property
    def legend(self) -> tuple[LegendEntry, ...]: ...

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
GRID_KEYS = ("grid", "grid_sections")


def draw_grid(canvas: Canvas, lo: np.ndarray, hi: np.ndarray, cell: float, colours: tuple[Colour, Colour],
              z: float) -> None:
    """A grid over the world box ``lo``–``hi`` (m): 1-pixel lines every ``cell`` metres from the
    canvas' centre in ``colours[0]``, every fifth (a section) 1.5 pixels in ``colours[1]``
    (nodes :data:`GRID_KEYS`). A few dozen line segments: viser's grid plane runs a shader on
    every pixel of the ground, a large part of a frame in a software-rendered page. The light
    drawing has the sections only."""
    cells, sections = grid_segments(lo, hi, canvas.centre, cell)
    canvas.lines(GRID_KEYS[0], cells[:0] if canvas.light else cells, colours[0], 1.0, z)
    canvas.lines(GRID_KEYS[1], sections, colours[1], 1.5, z)


class Ground(Static):
    """The arena square around its centre: a grid and a border."""

    name = "ground"
    keys = (*GRID_KEYS, "arena")

    def __init__(self, *, cell: Callable[[float], float], cell_colour: Colour, section_colour: Colour, z: float,
                 border: Colour, border_px: float, border_z: float) -> None:
        """``cell``: half size (m) → grid cell (m); sections are 5 cells."""
        self.cell, self.cell_colour, self.section_colour, self.z = cell, cell_colour, section_colour, z
        self.border, self.border_px, self.border_z = border, border_px, border_z

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        half = float(snap.scenario.arena.half_size)
        c = canvas.centre
        draw_grid(canvas, c - half, c + half, self.cell(half), (self.cell_colour, self.section_colour), self.z)
        box = c + half * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
        canvas.lines("arena", polyline(box, closed=True), self.border, self.border_px, self.border_z)


LANDSCAPE_MAP = "YlGn"  # low cost light (where the swarm gathers), high green
LANDSCAPE_TINT = 0.55  # of the colour map, the rest white: light enough for dark trails and outlined robots (3:1)
LANDSCAPE_SPAN = 0.55  # of the colour map used (from its light end)


def landscape_values(fitness: Callable[[np.ndarray], np.ndarray], half_size: float, n: int = 160) -> np.ndarray:
    """The cost on an ``n × n`` grid over the arena, as viser lays an image on the ground seen from
    above: row 0 at −y (the bottom of the screen); a maximised objective negated."""
    xs = np.linspace(-half_size, half_size, n)
    gx, gy = np.meshgrid(xs, xs)  # image rows run from −y to +y
    f = np.asarray(fitness(np.stack([gx, gy], axis=-1)), dtype=float)
    return -f if getattr(fitness, "maximise", False) else f


class HeatScale:
    """Cost → colour, log-compressed (the many local minima of Rastrigin or Griewank stay visible
    next to the steep walls): 0 at the lowest cost shown, 1 at the highest."""

    def __init__(self, f: np.ndarray) -> None:
        finite = f[np.isfinite(f)]
        self.low = float(finite.min()) if finite.size else 0.0
        self.span = float(np.log1p(finite.max() - self.low)) if finite.size else 0.0

    def level(self, f: np.ndarray) -> np.ndarray:
        v = np.log1p(np.maximum(np.nan_to_num(f, nan=self.low) - self.low, 0.0))
        return np.clip(v / self.span, 0.0, 1.0) if self.span > 0 else np.zeros_like(v)

    def cost(self, level: float) -> float:
        return self.low + float(np.expm1(level * self.span))

    @staticmethod
    def rgb(level: np.ndarray) -> np.ndarray:
        from matplotlib import colormaps

        rgb = colormaps[LANDSCAPE_MAP](0.02 + LANDSCAPE_SPAN * np.asarray(level))[..., :3]  # no dark end
        return (255 * (LANDSCAPE_TINT * rgb + 1 - LANDSCAPE_TINT)).astype(np.uint8)


def landscape_rgb(fitness: Callable[[np.ndarray], np.ndarray], half_size: float, n: int = 160) -> np.ndarray:
    """The objective over the arena as an RGB image (row 0 at −y, see :func:`landscape_values`)."""
    f = landscape_values(fitness, half_size, n)
    return HeatScale(f).rgb(HeatScale(f).level(f))


def cost_text(f: float) -> str:
    return f"{f:.2g}" if abs(f) < 1e4 else f"{f:.0e}"


class Landscape(Static):
    """The objective as a heat map under the arena (when ``objective`` gives one), with a colour
    bar beside the arena's right edge: the cost at its bottom, middle and top."""

    name = "landscape"
    keys = ("landscape", "colour_bar", "bar_low", "bar_mid", "bar_high", "bar_title")
    legend = (LegendEntry("■", (190, 226, 168), "objective (light: low cost)"),)

    def __init__(self, objective: Callable[[Scenario], Callable[[np.ndarray], np.ndarray] | None], z: float) -> None:
        self.objective, self.z = objective, z

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        fitness = self.objective(snap.scenario)
        if fitness is None:
            return
        half = float(snap.scenario.arena.half_size)
        side = 2 * half * canvas.scale
        f = landscape_values(fitness, half)
        heat = HeatScale(f)
        canvas.add("landscape", canvas.scene.add_image(
            canvas.name("landscape"), heat.rgb(heat.level(f)), render_width=side, render_height=side,
            position=(0.0, 0.0, self.z), cast_shadow=False, receive_shadow=False))
        levels = np.linspace(0.0, 1.0, 64)[:, None].repeat(4, axis=1)  # row 0 at the bottom: low cost
        width, gap = 0.035 * side, 0.02 * side
        x = side / 2 + gap + width / 2
        canvas.add("colour_bar", canvas.scene.add_image(
            canvas.name("colour_bar"), heat.rgb(levels), render_width=width, render_height=side,
            position=(x, 0.0, self.z), cast_shadow=False, receive_shadow=False))
        c, right = canvas.centre, half + (gap + width) / canvas.scale
        for key, level in (("bar_low", 0.0), ("bar_mid", 0.5), ("bar_high", 1.0)):
            canvas.label(key, cost_text(heat.cost(level)), c + (right, (2 * level - 1) * half), self.z + 0.06,
                         anchor="center-left", font_screen_scale=0.85)
        canvas.label("bar_title", "cost f", c + (right - width / canvas.scale, 1.035 * half), self.z + 0.06,
                     anchor="bottom-left", font_screen_scale=0.85)


def nice_length(most: float) -> float:
    """The longest 1, 2 or 5 × 10^k not above ``most`` (> 0)."""
    k = math.floor(math.log10(most))
    return max(m for m in (1.0, 2.0, 5.0, 10.0) if m * 10**k <= most * (1 + 1e-9)) * 10**k


def metre_text(m: float) -> str:
    return f"{m / 1000:g} km" if m >= 1000 else f"{m:g} m" if m >= 1 else f"{m * 100:g} cm"


class ScaleBar(Static):
    """A bar of a round number of metres near the bottom left of what the camera shows, about a
    sixth of its width: it follows the user's zoom and pan (``canvas.viewport``)."""

    name = "scale"
    keys = ("scale", "scale_label")
    COLOUR = (30, 30, 30)

    def __init__(self, z: float = 0.05) -> None:
        self.z = z
        self._drawn: tuple | None = None  # what the bar was drawn for

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        """Drawn again only when the camera, the scene's scale or the world's place moved."""
        vp = canvas.viewport
        key = (canvas.root, vp, canvas.scale, tuple(canvas.focus), tuple(canvas.centre))
        if key == self._drawn:
            return
        self._drawn = key
        hh = vp.half_height
        hw = hh * max(vp.aspect, 1e-3)
        length = nice_length(0.35 * hw / canvas.scale)
        start = canvas.to_world(np.array(vp.centre) + (-0.8 * hw, -0.96 * hh))
        end, tick = start + (length, 0.0), np.array([0.0, 0.018 * hh / canvas.scale])
        segs = np.array([[start, end], [start - tick, start + tick], [end - tick, end + tick]])
        canvas.lines("scale", segs, self.COLOUR, 3.0, self.z)
        canvas.label("scale_label", metre_text(length), end + 0.5 * tick[::-1], self.z, anchor="center-left",
                     font_screen_scale=1.1)


# ---------------------------------------------------------------------------- robots
class Robots(Static):
    """Run 0's robots as discs (``collided``: a colour of their own for disabled robots)."""

    name = "robots"
    keys = ("robots", "robots_edge")

    def __init__(self, colour: Colour, size: Size, z: float, *, collided: Colour | None = None,
                 outline: Colour | None = None) -> None:
        """``outline``: a dark edge round each disc (a scene with a heat map: every robot reads on it)."""
        self.colour, self.size, self.z, self.collided, self.outline = colour, size, z, collided, outline
        self.legend = (LegendEntry("●", colour, "robot"),) + (
            (LegendEntry("●", collided, "collided"),) if collided is not None else ())

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        colour: Colour | np.ndarray = self.colour
        if self.collided is not None:
            colour = np.where((snap.status != 0)[:, None], self.collided, self.colour).astype(np.uint8)
        size = size_of(self.size, canvas, snap)
        if self.outline is not None:
            canvas.points("robots_edge", snap.x, self.outline, EDGE * size, "circle", self.z - EDGE_Z)
        canvas.points("robots", snap.x, colour, size, "circle", self.z)


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
        if canvas.light:
            canvas.hide(*self.keys)
            return
        x = plane(snap.x)
        a = self.angle(snap) if self.angle is not None else snap.heading
        tip = x + self.length(canvas, snap) * np.column_stack([np.cos(a), np.sin(a)])
        canvas.lines("headings", np.stack([x, tip], axis=1), self.colour, self.px, self.z)


class Trails(Static):
    """Each robot's path over the last ``view.trail_seconds`` (lines, or dots in the light drawing),
    sent as appended pieces (:class:`~.trails.TrailDrawing`)."""

    name = "trails"
    keys = ("trails", "trails_dots")

    def __init__(self, colour: Colour, px: float, z: float) -> None:
        self.colour, self.px, self.z = colour, px, z
        self.legend = (LegendEntry("━" if px >= 2.0 else "—", colour, "trail"),)
        self.drawing = TrailDrawing("trails")

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        self.drawing.draw(canvas, snap.trails, self.colour, self.px, self.z)


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
        self.legend = (LegendEntry("○", colour, "selected"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        if self.live_only and not snap.live:
            segs = np.zeros((0, 2, 2))
        else:
            segs = circle_segments(plane(snap.x[snap.selected]), self.radius(canvas, snap), self.segments)
        canvas.lines("selected", segs, self.colour, self.px, self.z)


# ---------------------------------------------------------------------------- swarm B and beliefs
class Twin(Static):
    """Swarm B (compare): its robots (blue squares) just under A's and its trails (thinner than
    A's, square dots in the light drawing); hidden without B. ``outline`` as :class:`Robots`."""

    name = "twin"
    keys = ("twin", "twin_edge", "twin_trails", "twin_trails_dots")
    legend = (LegendEntry("■", TWIN, "swarm B"), LegendEntry("—", TWIN_TRAIL, "swarm B's trail"))

    def __init__(self, size: Size, z: tuple[float, float], px: float = 1.0, outline: Colour | None = None) -> None:
        self.size, self.z, self.px, self.outline = size, z, px, outline
        self.drawing = TrailDrawing("twin_trails")

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        if snap.twin is None:
            canvas.hide("twin", "twin_edge")
            self.drawing.hide(canvas)
            return
        x, trails = snap.twin
        size = size_of(self.size, canvas, snap)
        if self.outline is not None:
            canvas.points("twin_edge", x, self.outline, EDGE * size, "square", self.z[0] - EDGE_Z)
        canvas.points("twin", x, TWIN, size, "square", self.z[0])
        self.drawing.draw(canvas, trails, TWIN_TRAIL, self.px, self.z[1], dot="square")


def error_colors(err: np.ndarray, scale: float) -> np.ndarray:
    """(G, 2, 3) uint8: blue for no error to orange at ``scale`` and beyond."""
    f = np.clip(np.asarray(err, dtype=float) / max(scale, 1e-12), 0.0, 1.0)[:, None]
    rgb = (ERR_LOW + (ERR_HIGH - ERR_LOW) * f).astype(np.uint8)
    return np.repeat(rgb[:, None, :], 2, axis=1)


class Ghosts(Static):
    """The selected robot's beliefs: a ghost (blue diamond) where it believes each robot it
    localised is, joined to the truth by a segment from blue (no error) to orange, thin below
    half of the error scale and thick above it; the large ghost is where it believes the global
    best is. Hidden on true positions and recorded frames."""

    name = "ghosts"
    keys = ("ghost_errors", "ghost_errors_large", "ghosts", "ghost_best", "ghost_best_error")
    legend = (LegendEntry("◆", GHOST, "believed position"),
              LegendEntry("—", ERR_SMALL, "belief error: small"), LegendEntry("━", ERR_LARGE, "large"),
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
        large = np.asarray(g.error, dtype=float) > 0.5 * g.scale if len(g.of) else np.zeros(0, bool)
        colours = error_colors(g.error, g.scale)
        canvas.lines("ghost_errors", errs[~large], colours[~large], 1.5, z_err)
        canvas.lines("ghost_errors_large", errs[large], colours[large], 3.5, z_err)
        canvas.points("ghosts", g.points, GHOST, 0.8 * size, "diamond", z_ghost)
        if g.best is None or g.true_best is None:
            canvas.hide("ghost_best", "ghost_best_error")
            return
        err = float(np.hypot(*(g.best - g.true_best)))
        canvas.lines("ghost_best_error", np.stack([g.best, g.true_best])[None],
                     error_colors(np.array([err]), g.scale), 1.5, z_err)
        canvas.points("ghost_best", g.best[None], GHOST_BEST, 1.2 * size, "diamond", z_ghost)


def compare_pairs(robot: Colour, trail: Colour = TRAIL_A) -> tuple[Pair, ...]:
    """Swarm A (a kind's ``robot`` discs and ``trail``) against swarm B: colour and a second cue."""
    return (Pair("Compare: A's robots / B's robots", Cue(robot, "●", shape="circle"), Cue(TWIN, "■", shape="square")),
            Pair("Compare: A's trail / B's trail", Cue(trail, "━", width=2.0), Cue(TWIN_TRAIL, "—", width=1.0)))
