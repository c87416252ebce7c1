"""Drawing an environment's arena headless: ``render_mode="rgb_array"`` gives an (H, W, 3) uint8 frame
drawn by matplotlib's Agg canvas (no display, no X server), with the app's colours, glyphs and legend
for each kind and the trails of the last ``view.trail_seconds``; ``"human"`` shows the same frames on
a page served by viser (:mod:`shoal.rl.viewer`).

The colours are the app's (``shoal.app.kinds.*``, ``shoal.app.view.layers``), written out here because
the environments and the app are separate top layers; ``tests/test_rl_render.py`` checks they agree.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .batch import Batch
    from .viewer import Viewer

RENDER_MODES = ("rgb_array", "human")
Colour = tuple[int, int, int]
TRAIL_LIMITS = (80, 40)  # trails and points a trail, as the app draws them (app/session/history.py)
SIZE = (720, 560)  # width, height of a frame in pixels


@dataclass(frozen=True)
class Palette:
    """A kind's colours in the app."""

    robot: Colour
    heading: Colour
    trail: Colour
    pbest: Colour | None = None
    gbest: Colour | None = None
    source: Colour | None = None
    border: Colour = (60, 60, 60)
    collided: Colour | None = None
    extra: tuple[tuple[str, Colour], ...] = ()


PALETTES: dict[str, Palette] = {
    "swarm": Palette(robot=(220, 50, 50), heading=(120, 20, 20), trail=(160, 40, 40), pbest=(110, 110, 110),
                     gbest=(240, 170, 0), source=(20, 150, 60), border=(40, 40, 40)),
    "fleet": Palette(robot=(220, 50, 50), heading=(90, 15, 15), trail=(160, 40, 40), pbest=(120, 120, 120),
                     gbest=(240, 170, 0), source=(20, 150, 60), border=(60, 60, 60), collided=(150, 150, 150),
                     extra=(("obstacle", (70, 78, 95)), ("obstacle_edge", (60, 68, 82)), ("start", (70, 120, 230)),
                            ("layer", (150, 150, 150)), ("wall", (60, 60, 60)))),
    "sonar": Palette(robot=(220, 50, 50), heading=(90, 15, 15), trail=(160, 40, 40), pbest=(110, 110, 110),
                     gbest=(240, 170, 0), source=(20, 150, 60), border=(60, 60, 60),
                     extra=(("d_c", (20, 150, 60)), ("escort", (240, 170, 0)))),
    "slo_swarm": Palette(robot=(220, 50, 50), heading=(120, 20, 20), trail=(160, 40, 40), border=(40, 40, 40),
                         extra=(("neighbours", (175, 175, 175)),)),
}
DEFAULT = Palette(robot=(220, 50, 50), heading=(120, 20, 20), trail=(160, 40, 40))


def rgb(c: Colour) -> tuple[float, float, float]:
    return (c[0] / 255.0, c[1] / 255.0, c[2] / 255.0)


class Trails:
    """Run 0's positions over the last ``steps`` ticks (a ring), oldest first when read."""

    def __init__(self, steps: int) -> None:
        self.steps = max(int(steps), 2)
        self.buffer: np.ndarray | None = None
        self.count = 0

    def restart(self, x: np.ndarray) -> None:
        self.buffer = np.empty((self.steps,) + x.shape)
        self.count = 0
        self.add(x)

    def add(self, x: np.ndarray) -> None:
        if self.buffer is None or self.buffer.shape[1:] != x.shape:
            self.restart(x)
            return
        self.buffer[self.count % self.steps] = x
        self.count += 1

    def read(self) -> np.ndarray:
        """(robots, points, d), at most TRAIL_LIMITS robots of TRAIL_LIMITS points each."""
        if self.buffer is None or self.count < 2:  # a trail needs two points
            return np.zeros((0, 0, 2))
        n = min(self.count, self.steps)
        idx = (np.arange(self.count - n, self.count)) % self.steps
        pts = self.buffer[idx]  # (n, N, d)
        stride = max(1, int(np.ceil(n / TRAIL_LIMITS[1])))
        pts = pts[::-1][::stride][::-1]  # keep the newest point
        return np.swapaxes(pts[:, : TRAIL_LIMITS[0]], 0, 1)


class Renderer:
    """Frames of a batch's run 0 (see the module)."""

    def __init__(self, batch: Batch) -> None:
        self.batch = batch
        sc = batch.scene.scenario
        dt = float(batch.scene.engine.dt)
        self.trails = Trails(int(round(sc.view.trail_seconds / dt)) if dt > 0 else 100)
        self.palette = PALETTES.get(batch.scene.kind.name, DEFAULT)
        self.viewer: Viewer | None = None
        self.restart()

    def restart(self) -> None:
        self.trails.restart(self._x())

    def record(self, restarted: np.ndarray | None = None) -> None:
        if restarted is not None and restarted[0]:
            self.restart()
        else:
            self.trails.add(self._x())

    def _x(self) -> np.ndarray:
        x = self.batch.engine.state.x[0]
        return x[:, :2] if x.shape[1] >= 2 else np.concatenate([x, np.zeros_like(x)], axis=1)

    # ------------------------------------------------------------------ drawing
    def frame(self) -> np.ndarray:
        """Run 0's arena now, (H, W, 3) uint8."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        w, h = SIZE
        fig = Figure(figsize=(w / 100, h / 100), dpi=100, facecolor="white")
        canvas = FigureCanvasAgg(fig)
        ax = fig.add_axes((0.08, 0.06, 0.62, 0.86))
        ax.set_aspect("equal")
        ax.set_facecolor("white")
        legend: list[tuple[Any, str]] = []
        kind = self.batch.scene.kind.name
        draw = {"swarm": self._swarm, "fleet": self._fleet, "sonar": self._sonar, "slo_swarm": self._slo}.get(kind)
        if draw is not None:
            draw(ax, legend)
        self._robots(ax, legend)
        b = self.batch
        ax.set_title(f"{b.scene.scenario.name}  ·  step {int(b.elapsed[0])}  ·  t = {b.scene.engine.t:g} s",
                     fontsize=9, loc="left")
        ax.tick_params(labelsize=7)
        if legend:
            fig.legend([g for g, _ in legend], [t for _, t in legend], loc="upper left", bbox_to_anchor=(0.72, 0.93),
                       fontsize=8, frameon=False)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()

    def _glyph(self, marker: str, colour: Colour, line: bool = False, filled: bool = True) -> Any:
        from matplotlib.lines import Line2D

        if line:
            return Line2D([], [], color=rgb(colour), lw=2)
        return Line2D([], [], ls="", marker=marker, markersize=7, markerfacecolor=rgb(colour) if filled else "none",
                      markeredgecolor=rgb(colour))

    def _robots(self, ax: Any, legend: list) -> None:
        p, s = self.palette, self.batch.engine.state
        x = self._x()
        trails = self.trails.read()
        if trails.size:
            from matplotlib.collections import LineCollection

            ax.add_collection(LineCollection(list(trails), colors=[rgb(p.trail)], linewidths=1.2, zorder=2))
            legend.append((self._glyph("", p.trail, line=True), "trail"))
        y = getattr(s, "y", None)
        if p.pbest is not None and y is not None and np.ndim(y) == 3:
            yy = np.asarray(y[0], dtype=float)[:, :2] if y.shape[-1] >= 2 else np.zeros((y.shape[1], 2))
            ax.scatter(yy[:, 0], yy[:, 1], s=14, marker="s", color=rgb(p.pbest), zorder=3)
            legend.append((self._glyph("s", p.pbest), "personal best"))
        status = np.asarray(s.status[0])
        colours = np.array([rgb(p.collided if (p.collided is not None and st != 0) else p.robot) for st in status])
        heading = np.asarray(s.heading[0], dtype=float)
        span = self._span(ax)
        tip = x + 0.025 * span * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(list(np.stack([x, tip], axis=1)), colors=[rgb(p.heading)], linewidths=1.5,
                                         zorder=5))
        ax.scatter(x[:, 0], x[:, 1], s=36, color=colours, edgecolors="white", linewidths=0.5, zorder=4)
        legend.insert(0, (self._glyph("o", p.robot), "robot"))
        if p.collided is not None:
            legend.insert(1, (self._glyph("o", p.collided), "collided"))
        legend.insert(1, (self._glyph("", p.heading, line=True), "heading"))
        g = self._gbest()
        if p.gbest is not None and g is not None:
            ax.scatter([g[0]], [g[1]], s=60, marker="D", color=rgb(p.gbest), edgecolors="black", linewidths=0.5,
                       zorder=6)
            legend.append((self._glyph("D", p.gbest), "global best"))

    def _span(self, ax: Any) -> float:
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        return float(max(x1 - x0, y1 - y0))

    def _gbest(self) -> np.ndarray | None:
        s = self.batch.engine.state
        for name in ("yg", "y_g"):
            g = getattr(s, name, None)
            if g is not None:
                g = np.asarray(g[0], dtype=float)
                return g[:2] if g.shape[0] >= 2 else np.array([g[0], 0.0])
        return None

    def _frame_box(self, ax: Any, box: tuple[float, float, float, float], pad: float = 0.05) -> None:
        from matplotlib.patches import Rectangle

        x0, y0, x1, y1 = box
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec=rgb(self.palette.border), lw=1.2, zorder=1))
        m = pad * max(x1 - x0, y1 - y0)
        ax.set_xlim(x0 - m, x1 + m)
        ax.set_ylim(y0 - m, y1 + m)

    def _swarm(self, ax: Any, legend: list) -> None:
        sc, e = self.batch.scene.scenario, self.batch.engine
        h = sc.arena.half_size
        self._frame_box(ax, (-h, -h, h, h))
        src = np.asarray(e.objective.source, dtype=float)[:2]
        if self.palette.source is not None and e.objective.name != "linear":
            ax.scatter([src[0]], [src[1]], s=80, color=rgb(self.palette.source), zorder=3)
            legend.append((self._glyph("o", self.palette.source), "optimum / source"))

    def _fleet(self, ax: Any, legend: list) -> None:
        from matplotlib.collections import LineCollection, PatchCollection
        from matplotlib.patches import Circle, Polygon, Rectangle

        e, p = self.batch.engine, self.palette
        extra = dict(p.extra)
        w = e.world
        self._frame_box(ax, tuple(float(v) for v in w.bounds), pad=0.02)  # type: ignore[arg-type]
        sx0, sy0, sx1, sy1 = w.start_box
        ax.add_patch(Rectangle((sx0, sy0), sx1 - sx0, sy1 - sy0, color=rgb(extra["start"]), alpha=0.25, zorder=1))
        legend.append((self._glyph("s", extra["start"]), "start box"))
        x0, y0, x1, y1 = w.bounds
        layers = np.asarray(w.layer_x, dtype=float)
        if layers.size:
            ax.add_collection(LineCollection([[(lx, y0), (lx, y1)] for lx in layers], colors=[rgb(extra["layer"])],
                                             linestyles="dotted", linewidths=1.0, zorder=1))
            legend.append((self._glyph("", extra["layer"], line=True), "layer"))
        circles = np.asarray(w.circles, dtype=float).reshape(-1, 3)
        if circles.size:
            ax.add_collection(PatchCollection([Circle((cx, cy), r) for cx, cy, r in circles],
                                              facecolor=rgb(extra["obstacle"]), edgecolor=rgb(extra["obstacle_edge"]),
                                              lw=0.6, zorder=2))
            legend.append((self._glyph("o", extra["obstacle"]), "obstacle"))
        walls = np.asarray(w.walls, dtype=float).reshape(-1, 4)
        if walls.size:
            ax.add_collection(LineCollection(list(walls.reshape(-1, 2, 2)), colors=[rgb(extra["wall"])],
                                             linewidths=2.0, zorder=2))
        for poly in w.polygons:
            ax.add_patch(Polygon(np.asarray(poly, dtype=float), closed=True, facecolor=rgb(extra["obstacle"]),
                                 edgecolor=rgb(extra["obstacle_edge"]), zorder=2))
        src = np.asarray(w.source, dtype=float)
        ax.scatter([src[0]], [src[1]], s=80, color=rgb(p.source or (0, 0, 0)), zorder=3)
        legend.append((self._glyph("o", p.source or (0, 0, 0)), "source"))

    def _sonar(self, ax: Any, legend: list) -> None:
        from matplotlib.patches import Circle

        e, p = self.batch.engine, self.palette
        extra = dict(p.extra)
        s = e.state
        src = np.asarray(s.source[0], dtype=float)
        reach = max(e.params.dc, e.params.r_trap)
        lo = np.minimum(s.x[0].min(axis=0), src - reach)
        hi = np.maximum(s.x[0].max(axis=0), src + reach)
        c, half = (lo + hi) / 2.0, float((hi - lo).max()) / 2.0 * 1.08
        self._frame_box(ax, (c[0] - half, c[1] - half, c[0] + half, c[1] + half), pad=0.0)
        ax.add_patch(Circle(tuple(src), e.params.dc, fill=False, ec=rgb(extra["d_c"]), lw=1.2, ls="--", zorder=1))
        if e.params.r_trap > 0:
            ax.add_patch(Circle(tuple(src), e.params.r_trap, fill=False, ec=rgb(extra["escort"]), lw=1.2, zorder=1))
        ax.scatter([src[0]], [src[1]], s=80, color=rgb(p.source or (0, 0, 0)), zorder=3)
        legend += [(self._glyph("o", p.source or (0, 0, 0)), "source"), (self._glyph("o", extra["d_c"], filled=False),
                                                                         "d_c")]
        if e.params.r_trap > 0:
            legend.append((self._glyph("o", extra["escort"], filled=False), "escort ring"))

    def _slo(self, ax: Any, legend: list) -> None:
        from matplotlib.collections import LineCollection

        e, p = self.batch.engine, self.palette
        lo, hi = e.config.area()
        x = e.state.x[0]
        box_lo, box_hi = np.minimum(x.min(axis=0), lo), np.maximum(x.max(axis=0), hi)
        self._frame_box(ax, (float(box_lo[0]), float(box_lo[1]), float(box_hi[0]), float(box_hi[1])))
        adj = np.asarray(e.state.adjacency[0], dtype=bool)
        i, j = np.nonzero(np.triu(adj | adj.T, 1))
        if i.size:
            edge = dict(p.extra)["neighbours"]
            ax.add_collection(LineCollection(list(np.stack([x[i], x[j]], axis=1)), colors=[rgb(edge)], linewidths=0.6,
                                             zorder=1))
            legend.append((self._glyph("", edge, line=True), "neighbours"))

    # ------------------------------------------------------------------ human
    def show(self, frame: np.ndarray | None = None) -> None:
        """Put ``frame`` (or a new one) on the viser page, starting its server the first time."""
        from .viewer import Viewer

        if self.viewer is None:
            self.viewer = Viewer(self.batch.scene.scenario.name)
        self.viewer.show(self.frame() if frame is None else frame)

    def close(self) -> None:
        if self.viewer is not None:
            self.viewer.close()
            self.viewer = None
