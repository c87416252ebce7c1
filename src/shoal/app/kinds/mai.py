"""Mai's SLO swarm (Simultaneous Localisation and Optimisation): robots that act on positions
they estimate from noisy ranges and odometry.

It runs Mai's own swarm, ``[slo] swarm = "slo"`` (:class:`SLOSwarm`: SPSO 2011 in each
robot's frame, or a random walk; one step = one generation). A scene's own swarm on SLO
positions (``swarm = "host"``: the Chapter 3 swarm, a fleet, an acoustic swarm) is shown by
that scene's kind, with the oracle/SLO switch in its *Positions* folder.

Changes of the localisation (selection, w, δ_cos, δ_v, entry), the sensor errors, the
neighbourhood and the objective apply to the running swarm: positions and beliefs are kept
and the learner sees the swarm react. Other changes (swarm size, motion, the seed) rebuild
the engine with the same seed, so two settings can be compared run against run. The
snapshot carries what the overlay draws: truth, the selected robot's beliefs (ghosts),
neighbourhood edges and the candidate triangle of one selected pair.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.slo.objectives import slo_objective
from shoal.engine.slo.selection import SELECTIONS
from shoal.engine.slo.sensors import error_model
from shoal.presets.build import build_slo
from shoal.presets.io import PresetError
from shoal.presets.kinds import kind_of
from shoal.presets.models import SLO, Scenario, SLOErrorValues, required

from ..markdown import escape
from ..panel.panel import TRAIL_SLIDER
from ..panel.plots import PlotSpec, Series, log10_abs
from ..panel.positions import ERROR_SETS, label_of
from ..panel.selection import robot_number
from ..panel.spec import Dropdown, Folder, KindPanel, Number, PanelAPI, Slider, Tab, Text, fmt
from ..session.beliefs import ghosts_of
from ..session.history import Frame
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view import shapes
from ..view.canvas import Canvas
from ..view.layers import Ghosts, Ground, Landscape, Layer, LegendEntry, Robots, Selected, Static, Trails, Twin
from ..view.view import KeepSwarmInView
from .base import AppKind, BaseDriver

KIND_NAMES = {0: "none", 1: "x1", 2: "x2", 3: "x3 (dead reckoning)", 4: "initial guess", 5: "oracle"}
FLAG_NAMES = {0: "geometric {x1, x2, x3}", 1: "fallback {x3}: range failure or no movement",
              2: "mitigated {x3}: thin triangle, |v|/d < δ_v", 3: "mitigated {x3}: |cos α| near 1, δ_cos"}
ERROR_SCALE = 10.0  # thesis units: a ghost this far off is drawn fully red


@dataclass(frozen=True)
class PairView:
    """The triangle inspector of the ordered pair (i, j), in world coordinates anchored at the
    observer's true position ``a`` (NaN points where a candidate does not exist)."""

    i: int
    j: int
    a: np.ndarray  # (2,) observer i (true position)
    b: np.ndarray  # (2,) neighbour j (true position)
    prev: np.ndarray  # (2,) i's estimate of j one step earlier, anchored at a
    candidates: np.ndarray  # (3, 2) x1, x2 (the mirror pair) and x3 (dead reckoning), anchored at a
    mask: np.ndarray  # (3,) which candidates exist
    chosen: np.ndarray  # (2,) the estimate kept, anchored at a
    kind: int  # Kind of the estimate (x1, x2, x3, …)
    flag: int  # Flag of the candidate set
    cos_alpha: float
    thinness: float
    round_trip: float  # RTS e_r of the loop used (NaN if none)
    neighbour: bool  # j ∈ N_i this step


class MaiDriver(BaseDriver):
    """Mai's swarm's side of a session: beliefs kept one step back for the pair inspector.
    Errors, selection, w, δ, neighbourhood, objective… retune the running swarm (the kind's live rule)."""

    seed_rebuilds = True  # a new seed builds a new swarm
    sim: SLOSwarm

    def __init__(self, session: Session) -> None:
        super().__init__(session)
        self._prev_est: np.ndarray | None = None

    def build(self, scenario: Scenario) -> SLOSwarm:
        try:
            swarm = build_slo(scenario, runs=1)
        except ValueError as err:
            raise PresetError([f"slo: {err}"]) from None
        if not isinstance(swarm, SLOSwarm):  # (the kind refuses a host swarm on SLO positions)
            raise PresetError([f"slo.swarm: {scenario.name} is not Mai's SLO swarm"])
        return swarm

    def cleared(self) -> None:
        self._prev_est = None

    def before_step(self) -> None:
        self._prev_est = self.sim.state.beliefs.est[0].copy()

    # ------------------------------------------------------------------ views
    def _pair(self, i: int, b: Any, x: np.ndarray) -> PairView | None:
        adj = b.adjacency[0, i]
        j = self.session.selected_neighbour
        if j is None or j == i or j >= len(x):
            others = np.flatnonzero(adj)
            if not len(others):
                return None
            geometric = others[b.flag[0, i, others] == 0]  # prefer a pair with its mirror pair
            j = int(geometric[0] if len(geometric) else others[0])
        nan2 = np.full(2, np.nan)
        a = x[i]
        if b.candidates is not None:
            c = b.candidates
            pts, mask = c.points[0, i, j], c.mask[0, i, j].astype(bool)
            cos_alpha, thin = float(c.cos_alpha[0, i, j]), float(c.thinness[0, i, j])
        else:
            pts, mask, cos_alpha, thin = np.full((3, 2), np.nan), np.zeros(3, bool), np.nan, np.nan
        prev = a + self._prev_est[i, j] if self._prev_est is not None else nan2
        rt = float(b.round_trip[0, i, j]) if b.round_trip is not None else np.nan
        return PairView(
            i=i, j=j, a=a.copy(), b=x[j].copy(), prev=prev, candidates=np.where(mask[:, None], a + pts, np.nan),
            mask=mask, chosen=a + b.est[0, i, j], kind=int(b.kind[0, i, j]), flag=int(b.flag[0, i, j]),
            cos_alpha=cos_alpha, thinness=thin, round_trip=rt, neighbour=bool(adj[j]))

    def snapshot(self, selected: int) -> dict[str, Any]:
        s = self.sim.state
        x = s.x[0, :, :2]
        b = s.beliefs
        unit = self.session.scenario.arena.half_size / 50.0  # thesis units on screen
        adj = b.adjacency[0] | b.adjacency[0].T
        a, c = np.nonzero(np.triu(adj, 1))
        edges = np.stack([x[a], x[c]], axis=1) if len(a) else np.zeros((0, 2, 2))
        return {"ghosts": ghosts_of(b, x, selected, scale=ERROR_SCALE * unit),
                "extras": {"edges": edges, "pair": self._pair(selected, b, x),
                           "half_size": float(self.session.scenario.arena.half_size)}}

    def recorded(self, frame: Frame) -> dict[str, Any]:
        """Beliefs are not recorded: a recorded frame shows the true positions only."""
        return {"edges": np.zeros((0, 2, 2)), "pair": None}

    def readout(self) -> dict[str, float]:
        h = self.session.history
        m = h.metrics[-1] if h.metrics else (np.nan,) * len(h.names)
        out = dict(zip(h.names, (float(v) for v in m)))
        out["k"] = float(self.sim.state.k)
        return out

    def export_extra(self) -> dict[str, Any]:
        b = self.sim.state.beliefs
        i = min(self.session.selected_robot, self.session.robots - 1)
        return {"engine": self.session.engine_name,
                "beliefs": {"observer": i, "estimates": b.est[0, i].tolist(), "valid": b.valid[0, i].tolist(),
                            "kind": b.kind[0, i].tolist()}}


# ---------------------------------------------------------------------------- view
ROBOT = (220, 50, 50)
ROBOT_SIZE = 0.24  # scene units
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
PAIR_LINES = ("tri_truth", "tri_mirror", "tri_dr")
PAIR_POINTS = ("mirror", "dr", "prev", "chosen", "truth")
PAIR_LABELS = ("label_x1", "label_x2", "label_x3")


def view_centre(snap: Snapshot) -> np.ndarray:
    """World point at the middle of the view: where the swarm starts."""
    if snap.scenario.slo is not None and snap.scenario.slo.motion == "random_walk":
        return np.array([50.0, 50.0])  # the walk starts in [0, 100]²
    return np.zeros(2)


class Edges(Static):
    """Who localises whom: the neighbourhood's edges (computed from truth)."""

    name = "edges"
    keys = ("edges",)
    legend = (LegendEntry("—", EDGE, "neighbours"),)

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        canvas.lines("edges", snap.extras["edges"], EDGE, 1.0, Z["edges"])


class Pair(Static):
    """The triangle inspector of one pair (i, j): the true B (green), the mirror pair x1/x2
    (purple), dead reckoning x3 (orange), the previous estimate (grey) and the one kept (blue)."""

    name = "pair"
    keys = PAIR_LINES + PAIR_POINTS + PAIR_LABELS
    legend = (LegendEntry("—", TRUTH, "true neighbour"), LegendEntry("■", MIRROR, "x1, x2"),
              LegendEntry("■", DEAD_RECKONING, "x3"), LegendEntry("●", PREVIOUS, "previous estimate"),
              LegendEntry("●", CHOSEN, "estimate kept"))

    def draw(self, canvas: Canvas, snap: Snapshot) -> None:
        p: PairView | None = snap.extras["pair"]
        if p is None:
            canvas.hide(*self.keys)
            return
        a, (x1, x2, x3) = p.a, p.candidates
        canvas.lines("tri_truth", np.array([[a, p.b]]), TRUTH, 2.0, Z["inspector"])
        mirror = [[a, c] for c in (x1, x2) if np.all(np.isfinite(c))]
        if np.all(np.isfinite(x1)) and np.all(np.isfinite(x2)):
            mirror += list(shapes.dashed(x1, x2, 0.6 / canvas.scale, 0.4 / canvas.scale))
        canvas.lines("tri_mirror", np.array(mirror).reshape(-1, 2, 2), MIRROR, 1.5, Z["inspector"])
        dr = (shapes.dashed(a, x3, 0.5 / canvas.scale, 0.3 / canvas.scale) if np.all(np.isfinite(x3))
              else np.zeros((0, 2, 2)))
        canvas.lines("tri_dr", dr, DEAD_RECKONING, 1.5, Z["inspector"])
        canvas.points("mirror", np.array([x1, x2]), MIRROR, 0.6 * ROBOT_SIZE, "square", Z["points"])
        canvas.points("dr", x3[None], DEAD_RECKONING, 0.6 * ROBOT_SIZE, "square", Z["points"])
        canvas.points("prev", p.prev[None], PREVIOUS, 0.5 * ROBOT_SIZE, "circle", Z["points"])
        canvas.points("chosen", p.chosen[None], CHOSEN, 1.1 * ROBOT_SIZE, "circle", Z["ghosts"] - 0.001)
        canvas.points("truth", p.b[None], TRUTH, 1.3 * ROBOT_SIZE, "circle", Z["robots"] - 0.001)
        for key, xy in zip(PAIR_LABELS, (x1, x2, x3)):
            canvas.label(key, key[-2:], xy + 0.5 / canvas.scale, 0.02)


def landscape(scenario: Scenario) -> Callable[[np.ndarray], np.ndarray] | None:
    """The benchmark a PSO-moved SLO swarm minimises (a random walk minimises nothing)."""
    slo = scenario.slo
    return slo_objective(slo.objective) if slo is not None and slo.motion == "pso" else None


def layers(part: KindPanel | None) -> tuple[Layer, ...]:
    """Truth against belief: the true robots (red) and their neighbourhood (grey), trails, the
    observer (yellow ring) and its ghosts, the triangle inspector; swarm B."""
    return (
        Ground(cell=lambda half: half / 10, cell_colour=(228, 228, 224), section_colour=(200, 200, 196), z=Z["grid"],
               border=ARENA, border_px=2.5, border_z=0.0),
        Landscape(landscape, z=-0.04),
        Edges(),
        Trails(TRAIL, 1.2, Z["trails"]),
        Robots(ROBOT, ROBOT_SIZE, Z["robots"]),
        Selected(SELECTED, lambda canvas, snap: 1.7 * ROBOT_SIZE / canvas.scale, Z["selected"]),
        Ghosts(ROBOT_SIZE, (Z["errors"], Z["ghosts"])),
        Pair(),
        Twin(ROBOT_SIZE, (0.009, -0.006)),
    )


# ---------------------------------------------------------------------------- panel
SELECTION_LABELS = SELECTIONS.labels()  # label → slo.selection
NEIGHBOURHOODS = ("knn", "radius", "full", "random", "ring")
OBJECTIVES = ("sphere", "ackley", "griewank", "rastrigin", "rosenbrock", "plane", "line")
MOTIONS = ("pso", "random_walk")
PARAM_DEFAULT = {"knn": 5, "radius": 25, "ring": 2, "random": 0.5, "full": math.nan}
ERROR_FIELDS = tuple(SLOErrorValues.model_fields)
EXPORT_NOTE = " The JSON export adds the selected robot's estimates of the others."


def _slo(s: Session) -> SLO:
    """The scene's ``[slo]`` (Mai's swarm always has one)."""
    return required(s.scenario.slo, "slo")


def _error_range(name: str) -> tuple[float, float]:
    """On-screen (max, step) of one single error slider."""
    if name.endswith("p_fail"):
        return 0.5, 0.01
    if name.endswith("sigma_a"):
        return 3.0, 0.01
    return 0.5, 0.005


def _error_value(s: Session, name: str) -> float:
    """The single error ``name`` in force: set by hand, or the error set's."""
    slo = _slo(s)
    set_value = getattr(slo.error_values, name)
    if set_value is not None:
        return float(set_value)
    part, _, field = name.partition("_")
    return float(getattr(getattr(error_model(slo.errors), part), field))


def _error_slider(name: str) -> Slider:
    hi, step = _error_range(name)

    def write(s: Session, value: Any) -> dict[str, Any] | None:
        return None if math.isclose(value, _error_value(s, name), abs_tol=1e-12) else {
            f"slo.error_values.{name}": value}

    return Slider(f"slo.error_values.{name}", name, 0.0, hi, step,
                  SLOErrorValues.model_fields[name].description or name,
                  read=lambda s: _error_value(s, name), write=write, widen=True)


def _mapped(path: str, mapping: dict[str, str]) -> tuple[Any, Any]:
    """(read, write) of a dropdown of labels for the values of the ``[slo]`` field ``path``."""
    name = path.split(".")[1]

    def read(s: Session) -> str:
        return label_of(mapping, getattr(s.scenario.slo, name))

    def write(s: Session, label: str) -> dict[str, Any] | None:
        value = mapping.get(label, label)
        return None if value == getattr(s.scenario.slo, name) else {path: value}

    return read, write


def _set_errors(s: Session, label: str) -> dict[str, Any] | None:
    value, slo = ERROR_SETS.get(label, label), _slo(s)
    if value == slo.errors and not slo.error_values.values():
        return None
    return {"slo.errors": value, "slo.error_values": {}}


def _set_neighbourhood(s: Session, value: str) -> dict[str, Any] | None:
    if value == _slo(s).neighbourhood:
        return None
    return {"slo.neighbourhood": value, "slo.neighbourhood_param": None}


def _neighbourhood_param(s: Session) -> float | None:
    slo = _slo(s)
    p = slo.neighbourhood_param if slo.neighbourhood_param is not None else PARAM_DEFAULT[slo.neighbourhood]
    return None if math.isnan(p) else float(p)


def _set_neighbourhood_param(s: Session, value: Any) -> dict[str, Any] | None:
    return None if value == _slo(s).neighbourhood_param else {"slo.neighbourhood_param": value}


def _neighbour(s: Session) -> int:
    return -1 if s.selected_neighbour is None else s.selected_neighbour


def _pick_neighbour(panel: PanelAPI, value: Any) -> None:
    j = int(value)
    panel.session.select_neighbour(None if j < 0 else j)


def _engine(s: Session) -> str:
    slo = _slo(s)
    what = "SPSO 2011 in each robot's frame" if slo.motion == "pso" else "a random walk"
    return (f"engine: **{escape(s.engine_name)}**, Mai's SLO swarm ({what}) · "
            f"selection {escape(slo.selection.upper())}")


def _inspector(s: Session, snap: Snapshot) -> str:
    p: PairView | None = snap.extras["pair"]
    if p is None:
        return f"Robot {snap.selected:d} has no neighbour this step."
    cand = " · ".join(f"{n}" for n, m in zip(("x1", "x2", "x3"), p.mask) if m)
    err = float(np.hypot(*(p.chosen - p.b)))
    lines = [
        f"**pair ({p.i:d} → {p.j:d})**{'' if p.neighbour else ' (not a neighbour this step: stale)'}",
        f"candidates: {cand or '—'} · {FLAG_NAMES.get(p.flag, escape(p.flag))}",
        f"chosen: **{KIND_NAMES.get(p.kind, escape(p.kind))}** · error |x̂ − r| = {fmt(err)}",
        f"cos α = {fmt(p.cos_alpha)} · |v|/d = {fmt(p.thinness)}",
    ]
    if _slo(s).selection == "rts":
        lines.append(f"RTS loop error e_r = {fmt(p.round_trip)}")
    localised = len(snap.ghosts.of) if snap.ghosts is not None else 0
    lines.append(f"robot {snap.selected} localised {localised} neighbour(s) this step")
    return "  \n".join(lines)


def _status(s: Session, r: dict[str, float], state: str) -> str:
    sc = s.scenario
    return (f"**{escape(sc.name)}** · {state} · {s.progress('gen')} · "
            f"mean e_abs {fmt(r['e_abs_mean'])} · best f {fmt(r['generation_best'])}")


def _compare(s: Session) -> dict[str, dict[str, Any]]:
    """B with another candidate selection."""
    here = _slo(s).selection
    return {f"selection: {label}": {"slo.selection": value} for label, value in SELECTION_LABELS.items()
            if value != here}


def _rebuilt(s: Session, what: str, changes: dict[str, Any]) -> tuple[str, str] | None:
    if all(k.startswith("view.") for k in changes):
        return None
    return "Run restarted", f"{what}: same seed, step 0 ({s.engine_name})"


def _click(panel: PanelAPI, x: float, y: float, modifier: str | None) -> str:
    """Click a robot: it becomes the observer; shift-click: the inspected neighbour."""
    s = panel.session
    j = s.robot_near(x, y, 0.04 * s.scenario.arena.half_size)
    if j is None:
        return "nothing"
    if modifier == "shift":
        s.select_neighbour(j)
        panel.set_quietly(panel.handles["neighbour"], j)
        return "neighbour"
    panel.select_robot(j)
    return "observer"


ERROR_PLOT = PlotSpec("error", "localisation error", (
    Series("mean e_abs", "e_abs_mean", "rgb(220,50,50)", 2),
    Series("median e_abs", "e_abs_median", "rgb(240,150,30)", 2, dash=(6.0, 4.0)),
    Series("median e_rel", "e_rel_median", "rgb(60,110,230)", 1, scale="rel"),
), x_label="generation", more_scales={"rel": {"range": (0.0, None)}}, nan_to=0.0, twin="e_abs_mean", history=2000,
    aspect=1.8, more_axes=({"scale": "rel", "side": 1, "size": 40},))
DISTANCE_PLOT = PlotSpec("distance", "median distance between robots", (
    Series("median distance between robots", "distance_median", "rgb(30,140,70)", 2),), x_label="generation",
    history=2000, aspect=2.2)
FITNESS_PLOT = PlotSpec("fitness", "best fitness, log10 |f|", (
    Series("log10 |best f|", lambda m, sc: log10_abs(m["generation_best"]), "rgb(120,60,200)", 2),),
    x_label="generation", y_range=(None, None), history=2000, aspect=2.2)


def panel(api: PanelAPI) -> KindPanel:
    """Candidate selection, prediction weight and mitigation thresholds, the error set and its
    single errors, the neighbourhood, objective, motion and swarm size; the observer robot and
    the pair whose triangle is inspected; live plots. A change that needs a new swarm rebuilds
    it with the same seed (the panel says so)."""
    selection = _mapped("slo.selection", SELECTION_LABELS)
    return KindPanel(
        tabs=(
            Tab("SLO", (
                Dropdown("slo.selection", "selection", tuple(SELECTION_LABELS), read=selection[0], write=selection[1],
                         hint="which candidate becomes the estimate [3.7]-[3.9]"),
                Slider("slo.prediction_weight", "w (prediction weight)", 0.0, 1.0, 0.01,
                       "CSS: how far the kept estimate leans to dead reckoning x3 [3.7]"),
                Slider("slo.delta_cos", "δ_cos", 0.0, 0.2, 0.005,
                       "mitigation: dead reckoning when |cos α| is within δ_cos of 1"),
                Slider("slo.delta_v", "δ_v", 0.0, 0.5, 0.005,
                       "mitigation: dead reckoning when |v|/d < δ_v (thin triangle)"),
                Dropdown("slo.errors", "error set", tuple(ERROR_SETS),
                         read=lambda s: label_of(ERROR_SETS, _slo(s).errors), write=_set_errors,
                         hint="Tab. 4.3; choosing a set clears the single errors below"),
                Folder("single errors", expand=False, items=tuple(_error_slider(name) for name in ERROR_FIELDS)),
                Dropdown("slo.neighbourhood", "neighbourhood", NEIGHBOURHOODS, write=_set_neighbourhood,
                         hint="who localises whom (computed from truth)"),
                Number("slo.neighbourhood_param", "neighbourhood parameter", read=_neighbourhood_param,
                       write=_set_neighbourhood_param, step=0.1, hint="k (knn), r (radius), n (ring), p (random)",
                       visible=lambda s: _slo(s).neighbourhood != "full"),
                Text("engine", compute=_engine),
                Text(text="*An SLO change restarts the run with the same seed, so settings compare run for run.*"),
            )),
            Tab("Swarm", (
                Dropdown("slo.motion", "motion", MOTIONS,
                         hint="SLO swarm: SPSO 2011 in each robot's frame, or a random walk"),
                Dropdown("slo.objective", "objective", OBJECTIVES, hint="SLO swarm: 2-D benchmark, minimised",
                         visible=lambda s: _slo(s).motion == "pso"),
                Slider("slo.walk_speed", "walk speed", 0.5, 20.0, 0.5, "random walk: longest step (thesis units)",
                       visible=lambda s: _slo(s).motion == "random_walk"),
                Slider("sim.robots", "robots", 2, 60, 1, "swarm size P; RTS and Akcan slow down above ~30",
                       integer=True),
                TRAIL_SLIDER,
            )),
            Tab("Inspect", (
                robot_number("observer robot", "whose beliefs are drawn as ghosts; or click a robot"),
                Number("neighbour", "inspected neighbour", read=_neighbour, act=_pick_neighbour, low=-1,
                       high=lambda s: s.robots - 1,
                       hint="the pair of the triangle inspector; −1 = the first neighbour"),
                Text("inspector", on_snapshot=_inspector),
            )),
            Tab("Plots", (ERROR_PLOT, DISTANCE_PLOT, FITNESS_PLOT)),
        ),
        status=_status, compare=_compare, rebuilt=_rebuilt, click=_click, export_note=EXPORT_NOTE)


def accepts(scenario: Scenario) -> bool:
    """Mai's SLO swarm (``[slo] swarm = "slo"``); a host swarm on SLO positions keeps its own view."""
    return kind_of(scenario) == "slo_swarm"


def refuse(scenario: Scenario) -> None:
    if scenario.slo is None:
        raise PresetError([f"slo: {scenario.name} has no [slo] section"])
    if not accepts(scenario):
        raise PresetError([f"slo.swarm: {scenario.name} puts its own swarm on SLO positions (swarm = "
                           "'host'); its own scene shows it, with a Positions folder"])


KIND = AppKind(name="mai", title="Mai's SLO swarm", engine="slo_swarm", refuse=refuse,
               make_driver=MaiDriver, notes="slo", layers=layers,
               camera=lambda: KeepSwarmInView(view_centre, home_first=False), make_panel=panel)


def driver(session: Session) -> MaiDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, MaiDriver), session.kind.name
    return session.driver
