"""The SLO session (Mai: Simultaneous Localisation and Optimisation): one browser tab's swarm
whose robots act on positions they estimate from noisy ranges and odometry.

It runs Mai's own swarm, ``[slo] swarm = "slo"`` (:class:`SLOSwarm`: SPSO 2011 in each
robot's frame, or a random walk; one step = one generation). A scene's own swarm on SLO
positions (``swarm = "host"``: the Chapter 3 swarm, a fleet, an acoustic swarm) is shown by
that scene's session, with the oracle/SLO switch in its *Positions* folder (:mod:`.positions`).

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

from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.presets.build import build_slo, slo_live_changes
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .base_session import BaseSession
from .ghosts import ghosts_of

KIND_NAMES = {0: "none", 1: "x1", 2: "x2", 3: "x3 (dead reckoning)", 4: "initial guess", 5: "oracle"}
FLAG_NAMES = {0: "geometric {x1, x2, x3}", 1: "fallback {x3}: range failure or no movement",
              2: "mitigated {x3}: thin triangle, |v|/d < δ_v", 3: "mitigated {x3}: |cos α| near 1, δ_cos"}


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


@dataclass(frozen=True)
class SLOSnapshot:
    """A consistent copy of what the SLO view draws, taken under the lock."""

    k: int
    t: float
    x: np.ndarray  # (N, 2) true positions
    trails: np.ndarray  # (M, L, 2)
    selected: int
    ghosts: np.ndarray  # (G, 2) x_i + x̂_ij for the selected i's neighbours j
    ghost_of: np.ndarray  # (G,) which robot each ghost stands for
    ghost_error: np.ndarray  # (G,) e_abs of each ghost
    edges: np.ndarray  # (E, 2, 2) neighbourhood edges (unordered)
    pair: PairView | None
    localising: bool  # False in oracle mode: no beliefs to draw
    revision: int
    half_size: float


def beliefs_of(sim: Any) -> Any | None:
    """The :class:`Beliefs` of an SLO engine, or None (nothing localises)."""
    return sim.state.beliefs if isinstance(sim, SLOSwarm) else None


class SLOSession(BaseSession):
    """SLO engine, selection (observer robot and inspected neighbour) and playback of one tab."""

    METRICS = ("t", "e_abs_mean", "e_abs_median", "e_rel_median", "distance_median", "best", "dead_reckoning")
    NOTES = "slo"

    def __init__(self, scenario: Scenario) -> None:
        self.selected_neighbour: int | None = None  # None: the observer's first neighbour
        self._prev_est: np.ndarray | None = None
        super().__init__(scenario)

    @classmethod
    def accepts(cls, scenario: Scenario) -> bool:
        """Mai's SLO swarm (``[slo] swarm = "slo"``); a host swarm on SLO positions keeps its own view."""
        return scenario.slo is not None and scenario.slo.swarm == "slo"

    @classmethod
    def check(cls, scenario: Scenario) -> Scenario:
        if scenario.slo is None:
            raise PresetError([f"slo: {scenario.name} has no [slo] section"])
        if not cls.accepts(scenario):
            raise PresetError([f"slo.swarm: {scenario.name} puts its own swarm on SLO positions (swarm = "
                               "'host'); its own scene shows it, with a Positions folder"])
        return scenario

    def _build(self, scenario: Scenario) -> Any:
        try:
            return build_slo(scenario, runs=1)
        except ValueError as err:
            raise PresetError([f"slo: {err}"]) from None

    @property
    def robots(self) -> int:
        return int(self.sim.state.x.shape[1])

    @property
    def engine_name(self) -> str:
        return type(self.sim).__name__

    def clock(self) -> float:
        """Generations since reset."""
        return self._t0 + float(self.sim.state.k - self._k0)

    def _clear_history(self) -> None:
        self._prev_est = None
        super()._clear_history()

    # ------------------------------------------------------------------ changes
    def _adopt(self, new: Scenario) -> None:
        old = self.scenario
        same = {**old.model_dump(), "view": None} == {**new.model_dump(), "view": None}
        live = None if same else slo_live_changes(old, new)
        if same:  # only the view: keep running
            self.scenario = new
        elif live is not None:  # errors, selection, w, δ, neighbourhood…: keep running
            self.sim.retune(**live)
            self.scenario = new
        else:  # a new swarm, motion or seed: rebuild with the (same) seed
            self._load(new)
            self.selected_robot = min(self.selected_robot, self.robots - 1)
        self.revision += 1

    def step(self, n: int = 1) -> int:
        done = 0
        with self.lock:
            for _ in range(n):
                b = beliefs_of(self.sim)
                self._prev_est = None if b is None else b.est[0].copy()
                done += super().step(1)
                if not self.playing and self.sim.state.k >= self.scenario.sim.steps:
                    break
        return done

    def select(self, robot: int, neighbour: int | None = None) -> None:
        with self.lock:
            self.selected_robot = int(min(max(robot, 0), self.robots - 1))
            if neighbour is not None:
                self.selected_neighbour = int(min(max(neighbour, 0), self.robots - 1))
            self.revision += 1

    def robot_near(self, x: float, y: float, tol: float) -> int | None:
        with self.lock:
            d = np.hypot(*(self.sim.state.x[0] - (x, y)).T)
            return int(np.argmin(d)) if d.size and d.min() <= tol else None

    # ------------------------------------------------------------------ history
    def _metric_row(self, info: Any) -> tuple[float, ...]:
        info = info if info is not None else self.sim.info()
        return (self.clock(), float(info.e_abs["mean"][0]), float(info.e_abs["median"][0]),
                float(info.e_rel["median"][0]), float(info.distance["median"][0]),
                float(info.best_fitness[0]), float(info.dead_reckoning[0]))

    # ------------------------------------------------------------------ views
    def _pair(self, i: int, b: Any, x: np.ndarray) -> PairView | None:
        adj = b.adjacency[0, i]
        j = self.selected_neighbour
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

    def snapshot(self, max_trails: int = 80, max_trail_points: int = 40) -> SLOSnapshot:
        with self.lock:
            s = self.sim.state
            x = s.x[0, :, :2].copy()
            i = min(self.selected_robot, len(x) - 1)
            b = beliefs_of(self.sim)
            if b is None:
                ghosts, of, err = np.zeros((0, 2)), np.zeros(0, int), np.zeros(0)
                edges, pair = np.zeros((0, 2, 2)), None
            else:
                g = ghosts_of(b, x, i, scale=0.0)  # the view picks the colour scale
                ghosts, of, err = g.points, g.of, g.error
                adj = b.adjacency[0] | b.adjacency[0].T
                a, c = np.nonzero(np.triu(adj, 1))
                edges = np.stack([x[a], x[c]], axis=1) if len(a) else np.zeros((0, 2, 2))
                pair = self._pair(i, b, x)
            return SLOSnapshot(
                k=s.k, t=self.clock(), x=x, trails=self.trails(max_trails, max_trail_points), selected=i,
                ghosts=ghosts, ghost_of=of, ghost_error=err, edges=edges, pair=pair, localising=b is not None,
                revision=self.revision, half_size=float(self.scenario.arena.half_size))

    def _replay_blanks(self, frame: Any) -> dict[str, Any]:
        """Beliefs are not recorded: a recorded frame shows the true positions only."""
        return {"x": frame.x[:, :2].copy(), "ghosts": np.zeros((0, 2)), "ghost_of": np.zeros(0, int),
                "ghost_error": np.zeros(0), "edges": np.zeros((0, 2, 2)), "pair": None,
                "selected": min(self.selected_robot, len(frame.x) - 1)}

    def readout(self) -> dict[str, float]:
        with self.lock:
            m = self.metrics[-1] if self.metrics else (np.nan,) * len(self.METRICS)
            out = dict(zip(self.METRICS, (float(v) for v in m)))
            out["k"] = float(self.sim.state.k)
            return out

    def export_extra(self) -> dict[str, Any]:
        b = beliefs_of(self.sim)
        out: dict[str, Any] = {"engine": self.engine_name}
        if b is not None:
            i = min(self.selected_robot, self.robots - 1)
            out["beliefs"] = {"observer": i, "estimates": b.est[0, i].tolist(), "valid": b.valid[0, i].tolist(),
                              "kind": b.kind[0, i].tolist()}
        return out
