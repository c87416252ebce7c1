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

from dataclasses import dataclass
from typing import Any

import numpy as np

from shoal.engine.slo import SLOSwarm
from shoal.presets.build import build_slo, slo_live_changes
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.beliefs import ghosts_of
from ..session.history import Frame
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view import shapes
from ..view.canvas import Canvas
from ..view.layers import Ghosts, Ground, Layer, LegendEntry, Robots, Selected, Static, Trails, Twin
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
    """Mai's swarm's side of a session: beliefs kept one step back for the pair inspector."""

    metrics = ("e_abs_mean", "e_abs_median", "e_rel_median", "distance_median", "best", "dead_reckoning")
    sim: SLOSwarm

    def __init__(self, session: Session) -> None:
        super().__init__(session)
        self._prev_est: np.ndarray | None = None

    def build(self, scenario: Scenario) -> SLOSwarm:
        try:
            return build_slo(scenario, runs=1)
        except ValueError as err:
            raise PresetError([f"slo: {err}"]) from None

    def cleared(self) -> None:
        self._prev_est = None

    def before_step(self) -> None:
        self._prev_est = self.sim.state.beliefs.est[0].copy()

    # ------------------------------------------------------------------ changes
    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        return not _same_run(old, new) and slo_live_changes(old, new) is None

    def live(self, old: Scenario, new: Scenario) -> dict[str, Any]:
        """Errors, selection, w, δ, neighbourhood, objective…: the swarm keeps running."""
        return {} if _same_run(old, new) else slo_live_changes(old, new) or {}

    # ------------------------------------------------------------------ history
    def metric_row(self, info: Any) -> tuple[float, ...]:
        info = info if info is not None else self.sim.info()
        return (float(info.e_abs["mean"][0]), float(info.e_abs["median"][0]), float(info.e_rel["median"][0]),
                float(info.distance["median"][0]), float(info.best_fitness[0]), float(info.dead_reckoning[0]))

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
    legend = (LegendEntry("—", TRUTH, "true neighbour"), LegendEntry("■", MIRROR, "mirror pair x1, x2"),
              LegendEntry("■", DEAD_RECKONING, "dead reckoning x3"), LegendEntry("●", PREVIOUS, "previous estimate"),
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


def layers(panels: Any) -> tuple[Layer, ...]:
    """Truth against belief: the true robots (red) and their neighbourhood (grey), trails, the
    observer (yellow ring) and its ghosts, the triangle inspector; swarm B."""
    return (
        Ground(cell=lambda half: half / 10, cell_colour=(228, 228, 224), section_colour=(200, 200, 196), z=Z["grid"],
               border=ARENA, border_px=2.5, border_z=0.0),
        Edges(),
        Trails(TRAIL, 1.2, Z["trails"]),
        Robots(ROBOT, ROBOT_SIZE, Z["robots"]),
        Selected(SELECTED, lambda canvas, snap: 1.7 * ROBOT_SIZE / canvas.scale, Z["selected"]),
        Ghosts(ROBOT_SIZE, (Z["errors"], Z["ghosts"])),
        Pair(),
        Twin(ROBOT_SIZE, (0.009, -0.006)),
    )


def _same_run(old: Scenario, new: Scenario) -> bool:
    """Do ``old`` and ``new`` differ only in the view?"""
    return {**old.model_dump(), "view": None} == {**new.model_dump(), "view": None}


def accepts(scenario: Scenario) -> bool:
    """Mai's SLO swarm (``[slo] swarm = "slo"``); a host swarm on SLO positions keeps its own view."""
    return scenario.slo is not None and scenario.slo.swarm == "slo"


def refuse(scenario: Scenario) -> None:
    if scenario.slo is None:
        raise PresetError([f"slo: {scenario.name} has no [slo] section"])
    if not accepts(scenario):
        raise PresetError([f"slo.swarm: {scenario.name} puts its own swarm on SLO positions (swarm = "
                           "'host'); its own scene shows it, with a Positions folder"])


KIND = AppKind(name="mai", title="Mai's SLO swarm", priority=40, accepts=accepts, refuse=refuse,
               make_driver=MaiDriver, notes="slo", layers=layers,
               camera=lambda: KeepSwarmInView(view_centre, home_first=False))


def driver(session: Session) -> MaiDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, MaiDriver), session.kind.name
    return session.driver
