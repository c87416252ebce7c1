"""The Chapter 6–8 session: a swarm localising an acoustic source (an :class:`AcousticSwarm`).

Playback, history and export come from :class:`BaseSession`. Here:

* changes: fields that only shape the next listen or the next move (Q, TBP, D/λ_c, the
  forgetting scale a, U, β, the escort ring r, the source speed and heading, the source
  and noise levels) go into the running swarm at its next step; the algorithm, the
  controller, the swarm size, SNR_0 (which places the source), the deployment and the
  oracle/SLO positions switch rebuild it; the SLO error set and localisation settings retune
  it (:mod:`.positions`);
* the source can be moved by hand (a drag in the arena): the swarm keeps running and has
  to find it again; a moving source carries on from where it was put;
* the snapshot carries what the view draws: bearing rays (which of the pair points nearer
  the true source), ray intersections, the selected one, GT-PSO triplets and the ring.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from shoal.engine.acoustics.propagation import snr_db
from shoal.engine.kinds.sonar import AcousticSwarm
from shoal.presets.build import build_sonar, sonar_params_for
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .base_session import BaseSession
from .ghosts import Ghosts, host_ghosts
from .positions import slo_retune

# acoustics fields whose change rebuilds the swarm (everything else applies at the next step)
REBUILD_FIELDS = ("algorithm", "controller", "mode", "snr0_db", "d_0", "start", "source_bearing_deg",
                  "full_lag", "stop_on_converge")
ROBOT_TOL = 0.02  # share of the arena width within which a click picks a robot


@dataclass(frozen=True)
class SonarSnapshot:
    """A consistent copy of what the acoustic view draws, taken under the lock."""

    k: int
    t: float
    x: np.ndarray  # (N, 2)
    heading: np.ndarray  # (N,)
    y: np.ndarray  # (N, 2) personal bests
    yg: np.ndarray  # (2,) global best
    source: np.ndarray  # (2,)
    snr: np.ndarray  # (N,) dB
    trails: np.ndarray  # (M, L, 2)
    revision: int
    selected: int
    half_size: float  # arena half size, m
    r_trap: float
    d_c: float
    rays: np.ndarray | None  # (N, 2, 2) unit vectors [r_+, r_-] of the last listen
    true_ray: np.ndarray | None  # (N,) int: which of the two points nearer the true source
    points: np.ndarray | None  # (N, K, 2) ray intersections
    forward: np.ndarray | None  # (N, K) bool
    kept: np.ndarray | None  # (N, K) bool
    pick: np.ndarray | None  # (N,) int index into K of the selected intersection, −1 none
    partner: np.ndarray | None  # (N,) int
    tri_members: np.ndarray | None  # (N, 3) GT-PSO triplets
    tri_centroid: np.ndarray | None  # (N, 2)
    tri_direction: np.ndarray | None  # (N, 2)
    tri_valid: np.ndarray | None  # (N,)
    live: bool = True  # False: a recorded frame (timeline, replay): no rays, hits or bests
    ghosts: Ghosts | None = None  # the selected robot's beliefs (SLO positions)


def true_ray_index(x: np.ndarray, rays: np.ndarray, source: np.ndarray) -> np.ndarray:
    """(N,) 0 or 1: which ray of each robot's pair (N, 2, 2) points closer to the true source."""
    to_src = np.asarray(source, dtype=float) - np.asarray(x, dtype=float)
    dots = np.einsum("nkd,nd->nk", rays, to_src)
    return np.argmax(dots, axis=1)


class SonarSession(BaseSession):
    """Acoustic swarm, hand-moved source and playback state of one browser tab (Ch. 6–8)."""

    METRICS = ("t", "com_dist", "snr_mean", "snr_max", "inside_ring")
    NOTES = "ch6-8"

    sim: AcousticSwarm

    @classmethod
    def accepts(cls, scenario: Scenario) -> bool:
        return scenario.acoustics is not None

    @classmethod
    def check(cls, scenario: Scenario) -> Scenario:
        if not cls.accepts(scenario):
            raise PresetError([f"acoustics: {scenario.name} has no [acoustics] section"])
        return scenario

    def _build(self, scenario: Scenario) -> AcousticSwarm:
        try:
            return build_sonar(scenario, runs=1)
        except ValueError as err:  # the engine refuses a combination the model allows
            raise PresetError([f"acoustics.{err}" if ":" in str(err) else f"acoustics: {err}"]) from None

    # ------------------------------------------------------------------ changes
    def rebuilds(self, new: Scenario) -> bool:
        """Does going to ``new`` rebuild the swarm (rather than change it at the next step)?"""
        old = self.scenario
        a, b = old.acoustics, new.acoustics
        return (new.sim.robots != old.sim.robots or new.sim.seed != old.sim.seed or slo_retune(old, new) is None
                or any(getattr(a, f) != getattr(b, f) for f in REBUILD_FIELDS))

    def _adopt(self, new: Scenario) -> None:
        if self.rebuilds(new):
            self._load(new)  # builds first: a refused scene leaves everything as it was
            self.selected_robot = min(self.selected_robot, new.sim.robots - 1)
            self.revision += 1
            return
        try:
            params = sonar_params_for(new.acoustics)
        except ValueError as err:
            raise PresetError([f"acoustics.{err}"]) from None
        sw = self.sim
        old_arena = self.scenario.arena
        if params.dt != sw.params.dt:
            self._keep_clock()
        retune = slo_retune(self.scenario, new)  # errors, selection, neighbourhood…: the swarm keeps its beliefs
        sw.retune(**{k: getattr(params, k) for k in sw.LIVE - {"slo"}}, **({"slo": retune} if retune else {}))
        self.scenario = new
        if new.arena != old_arena:
            self.scene_revision += 1
        self.revision += 1

    def _refresh_snr(self) -> None:
        s, p = self.sim.state, self.sim.params
        s.snr_db[:] = snr_db(np.linalg.norm(s.x - s.source[:, None, :], axis=-1), p.psd_s_db, p.psd_n_db)

    # ------------------------------------------------------------------ hand edits
    def move_source(self, x: float, y: float) -> None:
        """Put the source at (x, y) m; the swarm carries on and must find it again."""
        with self.lock:
            sw = self.sim
            target = np.array([float(x), float(y)])
            delta = target - sw.state.source[0]
            sw.source0 = sw.source0.copy()
            sw.source0[0] += delta  # a moving source continues from here
            sw.state.source[0] = target
            self._refresh_snr()
            self.live_edits += 1
            self.revision += 1
        if self.twin is not None:  # B hears the same source (the arena draws A's)
            self.twin.move_source(x, y)

    def robot_near(self, x: float, y: float, tol: float | None = None) -> int | None:
        with self.lock:
            tol = ROBOT_TOL * 2 * self.scenario.arena.half_size if tol is None else tol
            d = np.hypot(*(self.sim.state.x[0] - (x, y)).T)
            return int(np.argmin(d)) if d.size and d.min() <= tol else None

    # ------------------------------------------------------------------ history and views
    def _metric_row(self, info: Any) -> tuple[float, ...]:
        info = info if info is not None else self.sim.info()
        snr = self.sim.state.snr_db[0]
        return (self.clock(), float(info.com_dist[0]), float(snr.mean()), float(snr.max()),
                float(info.frac_inside_ring[0]))

    def correlation(self, robot: int | None = None) -> tuple[np.ndarray, np.ndarray, float, float] | None:
        """(lags [s], R(τ), τ_lag [s], ρ) of ``robot`` (default: the selected one) at the last
        listen; None before the first step or for one-hydrophone strategies."""
        with self.lock:
            b = self.sim.state.bearing
            if b is None:
                return None
            i = min(self.selected_robot if robot is None else robot, b.corr.shape[1] - 1)
            return b.lags.copy(), b.corr[0, i].copy(), float(b.tau[0, i]), float(b.rho[0, i])

    def snapshot(self, max_trails: int = 80, max_trail_points: int = 40) -> SonarSnapshot:
        with self.lock:
            s, p = self.sim.state, self.sim.params
            x = s.x[0].copy()
            rays = true_ray = None
            if s.bearing is not None:
                rays = s.bearing.rays[0].copy()
                true_ray = true_ray_index(x, rays, s.source[0])
            loc = s.loc
            pts = fwd = kept = pick = partner = None
            tri = [None] * 4
            if loc is not None:
                if loc.points is not None:
                    pts, fwd, kept = loc.points[0].copy(), loc.forward[0].copy(), loc.kept[0].copy()
                    pick = loc.selected[0].copy() if loc.selected is not None else None
                if loc.partner is not None:
                    partner = loc.partner[0].copy()
                if loc.triangles is not None:
                    t = loc.triangles
                    tri = [t.members[0].copy(), t.centroid[0].copy(), t.direction[0].copy(), t.valid[0].copy()]
            return SonarSnapshot(
                k=s.k, t=self.clock(), x=x, heading=s.heading[0].copy(), y=s.y[0].copy(), yg=s.y_g[0].copy(),
                source=s.source[0].copy(), snr=s.snr_db[0].copy(), trails=self.trails(max_trails, max_trail_points),
                revision=self.revision, selected=min(self.selected_robot, self.sim.robots - 1),
                half_size=float(self.scenario.arena.half_size), r_trap=float(p.r_trap), d_c=float(p.dc),
                rays=rays, true_ray=true_ray, points=pts, forward=fwd, kept=kept, pick=pick, partner=partner,
                tri_members=tri[0], tri_centroid=tri[1], tri_direction=tri[2], tri_valid=tri[3],
                ghosts=host_ghosts(self.sim, min(self.selected_robot, self.sim.robots - 1), s.y_g[0]),
            )

    def _replay_blanks(self, frame: Any) -> dict[str, Any]:
        blank = dict.fromkeys(("rays", "true_ray", "points", "forward", "kept", "pick", "partner", "tri_members",
                               "tri_centroid", "tri_direction", "tri_valid"))
        return {**blank, "y": np.zeros((0, 2)), "selected": min(self.selected_robot, len(frame.x) - 1)}

    def readout(self) -> dict[str, float]:
        with self.lock:
            info, p = self.sim.info(), self.sim.params
            i = min(self.selected_robot, self.sim.robots - 1)
            return {
                "t": self.clock(), "k": float(self.sim.state.k), "com_dist": float(info.com_dist[0]),
                "converged_at": float(info.steps_to_converge[0]), "inside": float(info.frac_inside_ring[0]),
                "r_ref": p.r_ref, "d_s": p.d_s, "D": p.D, "lambda": p.c / p.f_c,
                "snr_sel": float(self.sim.state.snr_db[0, i]), "source_x": float(self.sim.state.source[0, 0]),
                "source_y": float(self.sim.state.source[0, 1]),
            }

    def export_extra(self) -> dict[str, Any]:
        s = self.sim.state
        return {"source": s.source[0].tolist(), "global_best": s.y_g[0].tolist(),
                "params": {k: (v if not isinstance(v, float) or np.isfinite(v) else None)
                           for k, v in dataclasses.asdict(self.sim.params).items()}}
