"""Chapters 6–8: a swarm localising an acoustic source (an :class:`AcousticSwarm`).

* changes: fields that only shape the next listen or the next move (Q, TBP, D/λ_c, the
  forgetting scale a, U, β, the escort ring r, the source speed and heading, the source
  and noise levels) go into the running swarm at its next step; the algorithm, the
  controller, the swarm size, SNR_0 (which places the source), the deployment and the
  oracle/SLO positions switch rebuild it; the SLO error set and localisation settings retune
  it;
* the source can be moved by hand (a drag in the arena): the swarm keeps running and has
  to find it again; a moving source carries on from where it was put;
* the snapshot carries what the view draws: bearing rays (which of the pair points nearer
  the true source), ray intersections, the selected one, GT-PSO triplets and the ring.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from shoal.engine.acoustics.propagation import snr_db
from shoal.engine.acoustics.receiver import lag_samples
from shoal.engine.acoustics.strategies import STRATEGIES
from shoal.engine.kinds.sonar import AcousticSwarm, SonarParams
from shoal.presets.builders.sonar import build_sonar, sonar_params_for
from shoal.presets.io import PresetError, kept_fields
from shoal.presets.kinds import kind_of
from shoal.presets.models import Acoustics, Scenario, required

from ..markdown import escape
from ..panel.panel import TRAIL_SLIDER
from ..panel.plots import Chart, Line, PlotSpec, Series
from ..panel.positions import positions_choices, positions_folder
from ..panel.selection import robot_number
from ..panel.spec import Dropdown, Folder, KindPanel, PanelAPI, Slider, Tab, Text, fmt
from ..session.history import Frame
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view import shapes
from ..view.camera import VIEW_HALF
from ..view.canvas import Canvas
from ..view.layers import (
    Ghosts,
    GlobalBest,
    Ground,
    Headings,
    Layer,
    LegendEntry,
    PersonalBests,
    Robots,
    Selected,
    Static,
    Trails,
    Twin,
)
from ..view.view import Home, arena_home
from .base import AppKind, BaseDriver

ROBOT_TOL = 0.02  # share of the arena width within which a click picks a robot
LIVE_OVERLAYS = ("rays", "true_ray", "points", "forward", "kept", "pick", "partner", "tri_members", "tri_centroid",
                 "tri_direction", "tri_valid")  # what one listen shows; not recorded


def _acoustics(s: Session) -> Acoustics:
    """The scene's ``[acoustics]`` (an acoustic scene always has one)."""
    return required(s.scenario.acoustics, "acoustics")


def _params(scenario: Scenario) -> SonarParams:
    if scenario.acoustics is None:
        raise PresetError([f"acoustics: {scenario.name} has no [acoustics] section"])
    try:
        return sonar_params_for(scenario.acoustics)
    except ValueError as err:
        raise PresetError([f"acoustics.{err}"]) from None


def true_ray_index(x: np.ndarray, rays: np.ndarray, source: np.ndarray) -> np.ndarray:
    """(N,) 0 or 1: which ray of each robot's pair (N, 2, 2) points closer to the true source."""
    to_src = np.asarray(source, dtype=float) - np.asarray(x, dtype=float)
    dots = np.einsum("nkd,nd->nk", rays, to_src)
    return np.argmax(dots, axis=1)


class SonarDriver(BaseDriver):
    """An acoustic swarm's side of a session, and the source moved by hand."""

    seed_rebuilds = True  # a new seed builds a new swarm
    scene_sections = ("arena",)
    sim: AcousticSwarm

    def __init__(self, session: Session) -> None:
        super().__init__(session)
        self.source_moved = False  # by hand, since the swarm was built

    def loaded(self) -> None:
        self.source_moved = False

    def build(self, scenario: Scenario) -> AcousticSwarm:
        try:
            return build_sonar(scenario, runs=1)
        except ValueError as err:  # the engine refuses a combination the model allows
            raise PresetError([f"acoustics.{err}" if ":" in str(err) else f"acoustics: {err}"]) from None

    # ------------------------------------------------------------------ changes
    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        """The kind's rule (a new swarm for another size or positions, or an ``[acoustics]`` field
        outside its live ones: the algorithm, the controller, SNR_0, the deployment, …), and a new
        seed; a combination the engine refuses is a :class:`PresetError` by field."""
        _params(new)
        return super().rebuilds(old, new)

    def live(self, old: Scenario, new: Scenario) -> dict[str, Any]:
        _params(new)  # (a combination the engine refuses: PresetError by field)
        return super().live(old, new)  # slo: the running swarm keeps its beliefs

    def _refresh_snr(self) -> None:
        s, p = self.sim.state, self.sim.params
        s.snr_db[:] = snr_db(np.linalg.norm(s.x - s.source[:, None, :], axis=-1), p.psd_s_db, p.psd_n_db)

    # ------------------------------------------------------------------ hand edits
    def move_source(self, x: float, y: float) -> None:
        """Put the source at (x, y) m; the swarm carries on and must find it again."""
        with self.session.lock:
            sw = self.sim
            target = np.array([float(x), float(y)])
            delta = target - sw.state.source[0]
            sw.source0 = sw.source0.copy()
            sw.source0[0] += delta  # a moving source continues from here
            sw.state.source[0] = target
            self.source_moved = True
            self._refresh_snr()
            self.session.live_edits += 1
            self.session.revision += 1
        twin = self.session.twin
        if twin is not None:  # B hears the same source (the arena draws A's)
            driver(twin).move_source(x, y)

    def robot_near(self, x: float, y: float) -> int | None:
        """The robot within 2 % of the arena's width of (x, y)."""
        return self.session.robot_near(x, y, ROBOT_TOL * 2 * self.session.scenario.arena.half_size)

    # ------------------------------------------------------------------ views
    def correlation(self, robot: int | None = None) -> tuple[np.ndarray, np.ndarray, float, float] | None:
        """(lags [s], R(τ), τ_lag [s], ρ) of ``robot`` (default: the selected one) at the last
        listen; None before the first step or for one-hydrophone strategies."""
        with self.session.lock:
            b = self.sim.state.bearing
            if b is None:
                return None
            i = min(self.session.selected_robot if robot is None else robot, b.corr.shape[1] - 1)
            return b.lags.copy(), b.corr[0, i].copy(), float(b.tau[0, i]), float(b.rho[0, i])

    def snapshot(self, selected: int) -> dict[str, Any]:
        s, p = self.sim.state, self.sim.params
        x = s.x[0]
        rays = true_ray = None
        if s.bearing is not None:
            rays = s.bearing.rays[0].copy()
            true_ray = true_ray_index(x, rays, s.source[0])
        loc = s.loc
        pts = fwd = kept = pick = partner = None
        tri: list[Any] = [None] * 4
        if loc is not None:
            if loc.points is not None and loc.forward is not None and loc.kept is not None:
                pts, fwd, kept = loc.points[0].copy(), loc.forward[0].copy(), loc.kept[0].copy()
                pick = loc.selected[0].copy() if loc.selected is not None else None
            if loc.partner is not None:
                partner = loc.partner[0].copy()
            if loc.triangles is not None:
                t = loc.triangles
                tri = [t.members[0].copy(), t.centroid[0].copy(), t.direction[0].copy(), t.valid[0].copy()]
        extras = dict(source=s.source[0].copy(), snr=s.snr_db[0].copy(),
                      half_size=float(self.session.scenario.arena.half_size), r_trap=float(p.r_trap), d_c=float(p.dc),
                      rays=rays, true_ray=true_ray, points=pts, forward=fwd, kept=kept, pick=pick, partner=partner,
                      tri_members=tri[0], tri_centroid=tri[1], tri_direction=tri[2], tri_valid=tri[3])
        return {"y": s.y[0].copy(), "yg": s.y_g[0].copy(), "ghosts": self.ghosts(selected, s.y_g[0]),
                "extras": extras}

    def scene(self) -> dict[str, Any]:
        return {"source": self.sim.state.source[0][None].copy()}  # one row [x, y]: it may move, or be dragged

    def recorded(self, frame: Frame) -> dict[str, Any]:
        """No listen overlays; the source where it was."""
        source = frame.scene.get("source")
        return {**dict.fromkeys(LIVE_OVERLAYS), **({"source": np.array(source[0])} if source is not None else {})}

    def readout(self) -> dict[str, float]:
        info, p = self.sim.info(), self.sim.params
        i = min(self.session.selected_robot, self.sim.robots - 1)
        return {
            "t": self.session.clock(), "k": float(self.sim.state.k), "com_dist": float(info.com_dist[0]),
            "converged_at": float(info.steps_to_converge[0]), "inside": float(info.frac_inside_ring[0]),
            "mean_dist": float(info.mean_dist_to_source[0]),
            "r_ref": p.r_ref, "d_s": p.d_s, "D": p.D, "lambda": p.c / p.f_c,
            "snr_sel": float(self.sim.state.snr_db[0, i]), "source_x": float(self.sim.state.source[0, 0]),
            "source_y": float(self.sim.state.source[0, 1]),
        }

    def kept(self, scenario: Scenario) -> Scenario:
        """The source as moved by hand in ``acoustics.source`` (where it starts: a moving source
        then follows the same path)."""
        if not self.source_moved or scenario.acoustics is None:
            return scenario
        return kept_fields(scenario, "acoustics", source=self.sim.source0[0].tolist())

    def export_extra(self) -> dict[str, Any]:
        s = self.sim.state
        return {"source": s.source[0].tolist(), "global_best": s.y_g[0].tolist(),
                "params": {k: (v if not isinstance(v, float) or np.isfinite(v) else None)
                           for k, v in dataclasses.asdict(self.sim.params).items()}}


# ---------------------------------------------------------------------------- view
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
SIDE = 2 * VIEW_HALF  # the arena's side in scene units
ROBOT_SIZE = 0.009 * SIDE
RAY_SHARE = 0.3  # ray length as a share of the arena side

Z = dict(grid=-0.025, rings=-0.015, triangles=-0.012, rays=-0.01, trails=-0.005, hits=0.0, pbests=0.004,
         source=0.006, gbest=0.008, robots=0.01, headings=0.012, selected=0.014)

SourceDrag = Callable[[float, float, str], None]  # (x, y, phase) in world metres


def _half(snap: Snapshot) -> float:
    return float(snap.scenario.arena.half_size)


class Source(Static):
    """The source (a one-instance disc mesh: drag it to move it), the circle of radius d_c
    round it and, when escorting, the ring r round the source and round the global best."""

    name = "source"
    keys = ("source", "source_label", "dc_ring", "escort")
    legend = (LegendEntry("●", SOURCE, "source"), LegendEntry("○", DC_RING, "d_c"),
              LegendEntry("○", ESCORT, "escort ring"))

    def __init__(self, on_drag: SourceDrag | None) -> None:
        self.on_drag = on_drag
        self.label = "source (drag me)" if on_drag is not None else "source"  # a shared page drags nothing
        self._canvas: Canvas | None = None

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        self._canvas = canvas
        v, f = shapes.disc_mesh(32)
        node = canvas.add("source", canvas.scene.add_batched_meshes_simple(
            canvas.name("source"), v, f, batched_wxyzs=np.array([[1.0, 0, 0, 0]]),
            batched_positions=np.zeros((1, 3), np.float32), batched_scales=np.array([0.022 * SIDE], np.float32),
            batched_colors=SOURCE, lod="off", material="toon3", side="double", cast_shadow=False,
            receive_shadow=False))
        if self.on_drag is not None:
            node.on_drag("left")(self.dragged)
        canvas.label("source_label", self.label, np.zeros(2))

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        e = snap.extras
        src = e["source"]
        canvas.nodes["source"].batched_positions = canvas.to_view(src[None], Z["source"])
        canvas.label("source_label", self.label, src + 0.04 * _half(snap))
        canvas.lines("dc_ring", shapes.circle_segments(src, e["d_c"], 72), DC_RING, 1.0, Z["rings"])
        if e["r_trap"] > 0 and snap.live and snap.yg is not None:
            rings = np.concatenate([shapes.circle_segments(snap.yg, e["r_trap"], 72),
                                    shapes.circle_segments(src, e["r_trap"], 72)])
        else:
            rings = np.zeros((0, 2, 2))
        canvas.lines("escort", rings, ESCORT, 2.0, Z["rings"])

    def dragged(self, event: Any) -> None:
        """viser's drag event on the source: where the pointer is, in world metres."""
        if self.on_drag is None or self._canvas is None:
            return
        xy = self._canvas.to_world(np.asarray(event.end_position, dtype=float)[:2])
        self.on_drag(float(xy[0]), float(xy[1]), str(event.phase))


def ray_segments(snap: Snapshot) -> tuple[np.ndarray, np.ndarray]:
    """(true, mirror) segment lists (N, 2, 2) of the last listen, each starting at a robot."""
    rays, true_ray = snap.extras["rays"], snap.extras["true_ray"]
    if rays is None or true_ray is None:
        return np.zeros((0, 2, 2)), np.zeros((0, 2, 2))
    n = len(snap.x)
    length = RAY_SHARE * 2 * _half(snap)
    idx = np.arange(n)
    true = np.stack([snap.x, snap.x + length * rays[idx, true_ray]], axis=1)
    mirror = np.stack([snap.x, snap.x + length * rays[idx, 1 - true_ray]], axis=1)
    return true, mirror


# Heights above Z["rays"], true rays over mirror rays, the selected pair over the rest. Nodes at the
# same depth (within the depth buffer's resolution, about 0.0015 here) are drawn in the order they
# were made and the later one wins: the mirror rays are made first.
RAY_Z = dict(mirror=-0.002, true=0.0, sel_mirror=0.002, sel_true=0.004)


class Rays(Static):
    """Each robot's pair of bearing rays (green: the one nearer the true source; orange: its
    mirror), the selected robot's thicker. A true ray lies over every mirror ray: where a robot
    faces the source the two nearly coincide, and the ray through the source reads green."""

    name = "rays"
    keys = ("rays_mirror", "rays_true", "rays_sel_mirror", "rays_sel_true")  # (the order they are drawn in)
    legend = (LegendEntry("—", RAY_TRUE, "bearing ray"), LegendEntry("—", RAY_MIRROR, "mirror ray"))

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        true, mirror = ray_segments(snap)
        i, z = snap.selected, Z["rays"]
        canvas.lines("rays_mirror", mirror, RAY_MIRROR, 1.2, z + RAY_Z["mirror"])
        canvas.lines("rays_true", true, RAY_TRUE, 1.2, z + RAY_Z["true"])
        canvas.lines("rays_sel_mirror", mirror[i:i + 1], RAY_MIRROR, 3.0, z + RAY_Z["sel_mirror"])
        canvas.lines("rays_sel_true", true[i:i + 1], RAY_TRUE, 3.0, z + RAY_Z["sel_true"])


class Hits(Static):
    """Ray intersections ahead of both rays (purple; grey: dropped by the ρ test [7.12]), each
    robot's chosen one (pink diamonds) and the selected robot's partner."""

    name = "hits"
    keys = ("hits_kept", "hits_dropped", "picks", "partner")
    legend = (LegendEntry("●", HIT_KEPT, "intersection"), LegendEntry("●", HIT_DROPPED, "dropped (ρ test)"),
              LegendEntry("◆", PICK, "chosen"))

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        e = snap.extras
        empty = np.zeros((0, 2))
        kept = dropped = picks = empty
        partner = np.zeros((0, 2, 2))
        points = e["points"]
        if points is not None and e["tri_members"] is None:  # B/XB-PSO: up to four per robot
            fwd, keep = e["forward"].astype(bool), e["kept"].astype(bool)
            kept, dropped = points[keep], points[fwd & ~keep]
        if points is not None and e["pick"] is not None:
            idx = np.flatnonzero(e["pick"] >= 0)
            picks = points[idx, e["pick"][idx]]
        if e["partner"] is not None:
            i = snap.selected
            j = int(e["partner"][i])
            if 0 <= j < len(snap.x) and j != i:
                partner = np.stack([snap.x[i], snap.x[j]])[None]
        size = 0.006 * SIDE
        canvas.points("hits_kept", kept, HIT_KEPT, size, "circle", Z["hits"])
        canvas.points("hits_dropped", dropped, HIT_DROPPED, size, "circle", Z["hits"])
        canvas.points("picks", picks, PICK, 1.8 * size, "diamond", Z["hits"] + 0.001)
        canvas.lines("partner", partner, PARTNER, 1.5, Z["rays"] + 0.002)


class Triangles(Static):
    """GT-PSO triplets: each valid triangle, its centroid and the direction it points."""

    name = "triangles"
    keys = ("triangles", "tri_rays", "tri_centroids")
    legend = (LegendEntry("—", TRIANGLE, "GT-PSO triangle"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        e = snap.extras
        segs = rays = np.zeros((0, 2, 2))
        cents = np.zeros((0, 2))
        if e["tri_members"] is not None and e["tri_valid"] is not None:
            ok = e["tri_valid"].astype(bool) & np.all(e["tri_members"] >= 0, axis=1)
            m = e["tri_members"][ok]
            if len(m):
                p = snap.x[m]  # (T, 3, 2)
                segs = np.concatenate([np.stack([p[:, a], p[:, b]], axis=1) for a, b in ((0, 1), (1, 2), (2, 0))])
                cents = e["tri_centroid"][ok]
                rays = np.stack([cents, cents + 0.08 * _half(snap) * e["tri_direction"][ok]], axis=1)
        canvas.lines("triangles", segs, TRIANGLE, 1.0, Z["triangles"])
        canvas.lines("tri_rays", rays, TRIANGLE, 2.0, Z["triangles"])
        canvas.points("tri_centroids", cents, TRIANGLE, 0.008 * SIDE, "circle", Z["triangles"])


class SourceCamera:
    """The arena square; shifted to keep the swarm's centre and the source on screen (a source
    may run away)."""

    def home(self, snap: Snapshot) -> Home:
        return arena_home(snap)

    def reset(self) -> None:
        pass

    def interest(self, snap: Snapshot) -> np.ndarray:
        return np.vstack([snap.x, snap.extras["source"][None]])

    def follow(self, canvas: Canvas, snap: Snapshot) -> None:
        com, src = snap.x.mean(axis=0), snap.extras["source"]
        lim = 0.92 * _half(snap)
        if np.all(np.abs(com - canvas.focus) < lim) and np.all(np.abs(src - canvas.focus) < lim):
            return
        canvas.set_focus((com + src) / 2)


def layers(part: KindPanel | None) -> tuple[Layer, ...]:
    """The acoustic arena: the source (drag it), the robots with their rays, intersections and
    triangles, headings, trails and bests; swarm B, the beliefs."""
    return (
        Ground(cell=lambda half: 10 ** np.floor(np.log10(half / 4)), cell_colour=(228, 228, 224),
               section_colour=(205, 205, 200), z=Z["grid"], border=BORDER, border_px=1.5, border_z=Z["grid"]),
        Source(part.drag if part is not None else None),
        Robots(ROBOT, ROBOT_SIZE, Z["robots"]),
        Headings(HEADING, lambda canvas, snap: 0.025 * _half(snap), Z["headings"]),
        Trails(TRAIL, 1.2, Z["trails"]),
        PersonalBests(PBEST, 0.006 * SIDE, Z["pbests"]),
        GlobalBest(GBEST, 0.016 * SIDE, Z["gbest"]),
        Selected(SELECTED, lambda canvas, snap: 0.02 * _half(snap), Z["selected"]),
        Rays(),
        Hits(),
        Triangles(),
        Ghosts(ROBOT_SIZE),
        Twin(ROBOT_SIZE, (0.009, -0.006)),
    )


# ---------------------------------------------------------------------------- panel
ALGORITHMS = STRATEGIES.labels()  # label → acoustics.algorithm
LABELS = {v: k for k, v in ALGORITHMS.items()}
CORR = "rgb(40,90,200)"
MARK = "rgb(220,50,50)"
REBUILD_NOTE = "*SNR₀, the algorithm and the swarm size rebuild the swarm; the rest applies at the next step.*"
GLYPHS = "Drag the green source in the arena to move it; click a robot to select it (the legend names the glyphs)."
EXPORT_NOTE = (" A source dragged by hand goes into the downloaded preset (acoustics.source, where it starts); "
               "the JSON export has that preset and where the source is now; a replay keeps it where it was at "
               "each step.")


WINDOW = "rgba(120,120,120,0.9)"
HIDDEN = "rgba(0,0,0,0)"


def corr_series() -> tuple[dict[str, Any], ...]:
    """R(τ) as a line through its samples, the samples as dots, τ_lag as a red line up to a dot at
    ρ, and the window ±D/c as dashed lines (the legend names them; no hover values: the marker
    series lie off the plot where they are not drawn)."""
    return (
        {"label": "τ [ms]"},
        {"label": "R(τ)", "stroke": CORR, "width": 2, "points": {"show": False}},
        {"label": "samples", "stroke": HIDDEN, "width": 1,
         "points": {"show": True, "size": 6, "stroke": CORR, "fill": CORR}},
        {"label": "τ_lag, ρ", "stroke": MARK, "width": 2, "points": {"show": True, "size": 8, "stroke": MARK,
                                                                     "fill": MARK}},
        {"label": "window ±D/c", "stroke": WINDOW, "width": 1, "dash": (4.0, 4.0), "points": {"show": False}},
    )


def corr_range(corr: np.ndarray, rho: float) -> tuple[float, float]:
    """The y range of the plot: from 0 (or below, for a negative R) to a little over the peak."""
    corr = np.asarray(corr, dtype=float)
    corr = corr[np.isfinite(corr)]
    lo = float(min(corr.min(initial=0.0), 0.0))
    hi = float(max(corr.max(initial=0.0), rho if np.isfinite(rho) else 0.0))
    if hi <= lo:
        hi = lo + 1.0
    return lo, hi + 0.05 * (hi - lo)


def corr_data(lags: np.ndarray, corr: np.ndarray, tau: float, rho: float,
              window: float | None = None) -> tuple[np.ndarray, ...]:
    """(τ [ms], R(τ), its samples, τ_lag, the window): on the lag grid with τ_lag and ±``window``
    (s) inserted, each next to a point a hair before and after it. R(τ) is interpolated at the
    inserted points (the line is unchanged) and its samples are dots on the grid only; τ_lag rises
    from below the plot to ρ (a dot there), the window's edges to the top. Where a marker is not
    drawn it lies far below the plot, which uPlot clips (it draws NaN as a line, not a gap)."""
    lags, corr = np.asarray(lags, dtype=float), np.asarray(corr, dtype=float)
    if len(lags) < 2:
        x = np.array([0.0, 1e-6])
        return (x, np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2))
    lo, hi = corr_range(corr, rho)
    off = lo - 10.0 * (hi - lo)  # below the plot: not drawn
    eps = 1e-9 * max(float(lags[-1] - lags[0]), 1e-12)
    marks = [(tau, rho, 1)] + ([(-window, hi, 2), (window, hi, 2)] if window is not None else [])
    extra = np.array([[m - eps, m, m + eps] for m, _, _ in marks]).ravel()
    x = np.concatenate([lags, extra])
    order = np.argsort(x, kind="stable")
    x = x[order]
    line = np.interp(x, lags, corr)
    samples = np.where(order < len(lags), line, off)
    lag_mark, window_mark = np.full(len(x), off), np.full(len(x), off)
    for j, (_, top, kind) in enumerate(marks):
        at = np.flatnonzero(order == len(lags) + 3 * j + 1)  # the mark itself (its neighbours stay off)
        (lag_mark if kind == 1 else window_mark)[at] = top
    return (x * 1e3, line, samples, lag_mark, window_mark)


def corr_scales(data: tuple[np.ndarray, ...], rho: float) -> dict[str, Any]:
    x, line = data[0], data[1]
    return {"x": {"time": False, "range": (float(x[0]), float(x[-1]))}, "y": {"range": corr_range(line, rho)}}


def corr_note(s: Session) -> str:
    """What the R(τ) plot is drawn from: the sample rate, the lags and the window, and why a low
    rate draws a coarse curve."""
    p = _params(s.scenario)
    c = driver(s).correlation()
    lags = c[0] if c is not None else lag_samples(p.band, p.D) / p.fs
    n, window = len(lags), p.D / p.c
    text = (f"*f_s = {p.fs / 1e3:g} kHz: a dot a sample, {1e3 / p.fs:.3g} ms apart; {n} lags over "
            f"±{1e3 * float(np.max(np.abs(lags))):.3g} ms; dashed: the window ±D/c = ±{1e3 * window:.3g} ms.")
    if p.lag_peak == "sample":
        inside = int(np.floor(window * p.fs + 1e-9))  # sample lags within the window on each side of 0
        text += (f" Only {inside} samples each side of 0: a coarse curve, and τ_lag is the "
                 "highest sample (Algorithm 5, no interpolation).*")
    else:
        text += " τ_lag: the top of a parabola through the highest sample and its neighbours.*"
    return text


def snr_series() -> tuple[dict[str, Any], ...]:
    return (
        {"label": "robot"},
        {"label": "SNR [dB]", "stroke": "rgb(30,140,70)", "width": 2, "fill": "rgba(30,140,70,0.25)"},
        {"label": "0 dB", "stroke": "rgba(120,120,120,0.9)", "width": 1, "dash": (4.0, 4.0)},
    )


def snr_data(snr: np.ndarray) -> tuple[np.ndarray, ...]:
    """A bar-like stepped outline: robot i spans [i − 0.4, i + 0.4] at height SNR_i."""
    snr = np.asarray(snr, dtype=float)
    n = len(snr)
    if n == 0:
        return (np.array([0.0, 1.0]), np.zeros(2), np.zeros(2))
    i = np.arange(n, dtype=float)
    x = np.stack([i - 0.45, i - 0.4, i + 0.4, i + 0.45], axis=1).ravel()
    base = float(min(snr.min(), 0.0))
    y = np.stack([np.full(n, base), snr, snr, np.full(n, base)], axis=1).ravel()
    return (x, y, np.zeros(len(x)))


def snr_scales(snr: np.ndarray) -> dict[str, Any]:
    snr = np.asarray(snr, dtype=float)
    n = len(snr)
    lo = float(min(snr.min(initial=0.0), 0.0))
    hi = float(max(snr.max(initial=0.0), 0.0))
    return {"x": {"time": False, "range": (-0.6, n - 0.4)}, "y": {"range": (lo - 1.0, hi + 2.0)}}


def _corr(s: Session) -> tuple[np.ndarray, ...]:
    c = driver(s).correlation()
    if c is None:
        return corr_data(np.zeros(0), np.zeros(0), 0.0, 0.0)
    p = _params(s.scenario)
    return corr_data(*c, window=p.D / p.c)


def _corr_scales(s: Session, data: tuple[np.ndarray, ...]) -> dict[str, Any]:
    c = driver(s).correlation()
    return corr_scales(data, c[3] if c is not None else 0.0)


def _snr(s: Session) -> np.ndarray:
    with s.lock:
        return s.sim.state.snr_db[0].copy()


CORR_PLOT = Chart("corr", "selected robot: R(τ) · red: τ_lag and ρ", corr_series(), _corr, _corr_scales,
                  x_label="τ [ms]", y_label="R(τ)", aspect=1.8, legend={"live": False},
                  visible=lambda s: _two_hydrophones(s))
CORR_NOTE = Text(compute=corr_note, visible=lambda s: _two_hydrophones(s))
NO_CORR = Text(text="*R(τ): only the algorithms with two hydrophones (X-, B- and XB-PSO) measure a bearing.*",
               visible=lambda s: not _two_hydrophones(s))
DIST = PlotSpec("dist", "|CoM − source| [m]",
                (Series("|CoM − source| [m]", "com_dist", "rgb(220,50,50)", 2),),
                lines=lambda s: (Line("d_c", float(_acoustics(s).d_c)),), twin="com_dist", history=2000,
                aspect=1.8)
SNR_PLOT = Chart("snr", "SNR [dB] at each robot", snr_series(), lambda s: snr_data(_snr(s)),
                 lambda s, data: snr_scales(_snr(s)), x_label="robot", legend={"show": False})


def _algorithm(s: Session) -> str:
    return LABELS[_acoustics(s).algorithm]


def _set_algorithm(s: Session, label: str) -> dict[str, Any] | None:
    algo = ALGORITHMS.get(label)
    return {"acoustics.algorithm": algo} if algo is not None and algo != _acoustics(s).algorithm else None


def _hearing(s: Session, snap: Snapshot) -> str:
    e, i = snap.extras, snap.selected
    text = f"robot {i:d}: SNR {e['snr'][i]:.1f} dB, {np.hypot(*(snap.x[i] - e['source'])):.0f} m from the source"
    corr = driver(s).correlation(i)
    if corr is not None:
        _, _, tau, rho = corr
        text += f" · τ_lag = {tau * 1e3:.3f} ms · ρ = {rho:.3g}"
    if e["true_ray"] is not None:
        text += " · true ray: " + ("r₊" if e["true_ray"][i] == 0 else "r₋")
    return text


def _readout(s: Session) -> str:
    r, ac = s.readout(), _acoustics(s)
    start = (f"source starts at ({ac.source[0]:.1f}, {ac.source[1]:.1f}) m (acoustics.source)" if ac.source is not None
             else f"source starts at d_s = {fmt(r['d_s'], 'm')}")
    return (f"R_ref = {fmt(r['r_ref'], 'm')} (SNR 0 dB) · {start} · "
            f"λ_c = {fmt(r['lambda'], 'm')} · D = {fmt(r['D'], 'm')} · window ±D/c = "
            f"{r['D'] / ac.c * 1e3:.3g} ms · controller {escape(ac.controller)}")


def _status(s: Session, r: dict[str, float], state: str) -> str:
    sc, ac = s.scenario, _acoustics(s)
    conv = f" · reached d_c at step {int(r['converged_at'])}" if r["converged_at"] >= 0 else ""
    ring = (f" · robots {r['mean_dist']:.0f} m from the source on average, {100 * r['inside']:.0f}% inside r"
            if ac.r > 0 else "")
    return (f"**{escape(sc.name)}** · {LABELS[ac.algorithm]} · {state} · t = {r['t']:.0f} s · "
            f"{s.progress()} · |CoM − source| = {r['com_dist']:.0f} m{conv}{ring}")


def _compare(s: Session) -> dict[str, dict[str, Any]]:
    """B with another localisation algorithm, or on the other positions (oracle vs SLO)."""
    sc = s.scenario
    here = _acoustics(s).algorithm
    return {**{f"algorithm: {label}": {"acoustics.algorithm": alg} for label, alg in ALGORITHMS.items()
               if alg != here}, **positions_choices(sc)}


def _click(panel: PanelAPI, x: float, y: float, modifier: str | None) -> str:
    """A click in the arena: near a robot selects it; shift-click puts the source there."""
    if modifier == "shift":
        driver(panel.session).move_source(x, y)
        return "source"
    robot = driver(panel.session).robot_near(x, y)
    if robot is not None:
        panel.select_robot(robot)
        return "selected"
    return "none"


def _two_hydrophones(s: Session) -> bool:
    return STRATEGIES[_acoustics(s).algorithm].hydrophones == 2


def panel(api: PanelAPI) -> KindPanel:
    """The selected robot's hearing, the signal (SNR_0, Q, D/λ_c, TBP), the algorithm and
    forgetting, the swarm and the source, live plots. Signal, forgetting, speed, escort and
    source-motion changes reach the running swarm at its next step; the algorithm, the swarm
    size and SNR_0 rebuild it (the panel says so)."""
    def drag(x: float, y: float, phase: str) -> None:  # the source dragged to (x, y) m
        if phase != "start":
            driver(api.session).move_source(x, y)

    return KindPanel(
        folders=(
            Folder("Selected robot", expand=False, items=(
                robot_number(hint="whose rays are drawn thick and whose R(τ) is plotted; or click a robot"),
                Text("hearing", on_snapshot=_hearing),
            )),
            positions_folder(),
        ),
        tabs=(
            Tab("Acoustics", (
                Dropdown("acoustics.algorithm", "algorithm", tuple(ALGORITHMS), read=_algorithm, write=_set_algorithm,
                         hint="A: amplitude · X: correlation peak · B: ray intersections · XB: both · "
                              "GT: triangulation"),
                Slider("acoustics.snr0_db", "SNR₀ [dB]", -10.0, 30.0, 0.5,
                       "SNR at the start; places the source at d_s = R_ref·10^(−SNR₀/20) (rebuilds)",
                       marks=((-5.0, "−5"), (0.0, "0"), (4.0, "4"), (10.0, "10"))),
                Slider("acoustics.Q", "Q = f_c/B", 0.5, 20.0, 0.1, "quality factor: high Q = narrow band, side peaks",
                       marks=((1.0, "1"), (1.5, "1.5"), (10.0, "10"))),
                Slider("acoustics.d_over_lambda", "D/λ_c", 0.1, 4.0, 0.05,
                       "hydrophone separation in wavelengths; above ½ the phase wraps",
                       marks=((0.5, "½"), (1.0, "1"), (2.0, "2")), visible=_two_hydrophones),
                Slider("acoustics.tbp", "TBP = B·T", 10.0, 1000.0, 10.0,
                       "time-bandwidth product of one listening window"),
                Slider("acoustics.a", "forgetting a", 0.0, 5.0, 0.05,
                       "memory × e^(−a) each step [7.2]; 0 = never forget"),
                Text("readout", compute=_readout),
                Text(text=REBUILD_NOTE),
            )),
            Tab("Swarm", (
                Slider("sim.robots", "swarm size", 2, 60, 1, "number of robots (rebuilds the swarm)", integer=True),
                Slider("acoustics.U", "U [m/s]", 0.2, 10.0, 0.1, "top speed"),
                Slider("acoustics.r", "escort radius r [m]", 0.0, 200.0, 1.0,
                       "keep this distance from the global best (needs the non-omni controller, Ch. 8.2)",
                       visible=lambda s: _acoustics(s).controller == "nonomni"),
                Slider("acoustics.v_n", "source speed v_n", 0.0, 1.0, 0.01, "source speed as a share of U [8.8]"),
                Slider("acoustics.source_heading_deg", "source heading [°]", -180.0, 180.0, 5.0,
                       "direction the source moves (0 = +x)"),
                TRAIL_SLIDER,
                Text(text=GLYPHS),
            )),
            Tab("Plots", (CORR_PLOT, CORR_NOTE, NO_CORR, DIST, SNR_PLOT)),
        ),
        status=_status, compare=_compare, export_note=EXPORT_NOTE, click=_click, drag=drag,
        rebuilt=lambda s, what, changes: ("Swarm rebuilt", f"{what}: the robots start again"))


def accepts(scenario: Scenario) -> bool:
    return kind_of(scenario) == "sonar"


def refuse(scenario: Scenario) -> None:
    if not accepts(scenario):
        raise PresetError([f"acoustics: {scenario.name} has no [acoustics] section"])


KIND = AppKind(name="sonar", title="Chapter 6–8 acoustic swarm", engine="sonar", refuse=refuse,
               make_driver=SonarDriver, notes="ch6-8", layers=layers, camera=SourceCamera, make_panel=panel)


def driver(session: Session) -> SonarDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, SonarDriver), session.kind.name
    return session.driver
