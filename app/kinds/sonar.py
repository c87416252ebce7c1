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
from typing import Any

import numpy as np

from shoal.engine.dvc import w_max
from shoal.engine.localisation import make_strategy
from shoal.engine.propagation import snr_db
from shoal.engine.sonar import AcousticSwarm, SonarParams
from shoal.engine.tuning import from_beta, split
from shoal.presets.build import build_sonar, sonar_params_for
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.beliefs import host_ghosts
from ..session.history import Frame
from ..session.positions import slo_retune
from ..session.session import Session
from .base import AppKind, BaseDriver

# acoustics fields whose change rebuilds the swarm (everything else applies at the next step)
REBUILD_FIELDS = ("algorithm", "controller", "mode", "snr0_db", "d_0", "start", "source_bearing_deg",
                  "full_lag", "stop_on_converge")
ROBOT_TOL = 0.02  # share of the arena width within which a click picks a robot
LIVE_OVERLAYS = ("rays", "true_ray", "points", "forward", "kept", "pick", "partner", "tri_members", "tri_centroid",
                 "tri_direction", "tri_valid")  # what one listen shows; not recorded


def true_ray_index(x: np.ndarray, rays: np.ndarray, source: np.ndarray) -> np.ndarray:
    """(N,) 0 or 1: which ray of each robot's pair (N, 2, 2) points closer to the true source."""
    to_src = np.asarray(source, dtype=float) - np.asarray(x, dtype=float)
    dots = np.einsum("nkd,nd->nk", rays, to_src)
    return np.argmax(dots, axis=1)


class SonarDriver(BaseDriver):
    """An acoustic swarm's side of a session, and the source moved by hand."""

    metrics = ("com_dist", "snr_mean", "snr_max", "inside_ring")
    scene_sections = ("arena",)
    sim: AcousticSwarm

    def build(self, scenario: Scenario) -> AcousticSwarm:
        try:
            return build_sonar(scenario, runs=1)
        except ValueError as err:  # the engine refuses a combination the model allows
            raise PresetError([f"acoustics.{err}" if ":" in str(err) else f"acoustics: {err}"]) from None

    # ------------------------------------------------------------------ changes
    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        a, b = old.acoustics, new.acoustics
        return (new.sim.robots != old.sim.robots or new.sim.seed != old.sim.seed or slo_retune(old, new) is None
                or any(getattr(a, f) != getattr(b, f) for f in REBUILD_FIELDS))

    def retune(self, old: Scenario, new: Scenario) -> None:
        try:
            params = sonar_params_for(new.acoustics)
        except ValueError as err:
            raise PresetError([f"acoustics.{err}"]) from None
        sw = self.sim
        before = sw.params
        if (params.v_n, params.source_heading, params.U, params.dt) != (before.v_n, before.source_heading, before.U,
                                                                       before.dt):
            self._restart_source_motion(params)
        sw.params = params
        sw.band = params.band
        sw.strategy = make_strategy(params.algorithm, a=params.a)
        tune = from_beta(params.dt, params.U, params.beta, d=2)
        sw.omega = tune.omega
        sw.c = np.array(split(tune.c_hat, params.c1_share))
        sw.w_max = w_max(params.U, params.dt)
        retune = slo_retune(old, new)
        if retune:  # errors, selection, neighbourhood…: the running swarm keeps its beliefs
            sw.retune_slo(**retune)  # type: ignore[attr-defined]
        self._refresh_snr()

    def _restart_source_motion(self, params: SonarParams) -> None:
        """A new speed or heading: the source carries on from where it is now."""
        sw = self.sim
        h = params.source_heading
        step = np.array([np.cos(h), np.sin(h)]) * params.v_n * params.U * params.dt
        sw.source0 = sw.state.source - sw.state.steps[:, None] * step

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
            self._refresh_snr()
            self.session.live_edits += 1
            self.session.revision += 1
        twin = self.session.twin
        if twin is not None:  # B hears the same source (the arena draws A's)
            driver(twin).move_source(x, y)

    def robot_near(self, x: float, y: float) -> int | None:
        """The robot within 2 % of the arena's width of (x, y)."""
        return self.session.robot_near(x, y, ROBOT_TOL * 2 * self.session.scenario.arena.half_size)

    # ------------------------------------------------------------------ history and views
    def metric_row(self, info: Any) -> tuple[float, ...]:
        info = info if info is not None else self.sim.info()
        snr = self.sim.state.snr_db[0]
        return (float(info.com_dist[0]), float(snr.mean()), float(snr.max()), float(info.frac_inside_ring[0]))

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
            if loc.points is not None:
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
        return {"y": s.y[0].copy(), "yg": s.y_g[0].copy(), "ghosts": host_ghosts(self.sim, selected, s.y_g[0]),
                "extras": extras}

    def recorded(self, frame: Frame) -> dict[str, Any]:
        return dict.fromkeys(LIVE_OVERLAYS)

    def readout(self) -> dict[str, float]:
        info, p = self.sim.info(), self.sim.params
        i = min(self.session.selected_robot, self.sim.robots - 1)
        return {
            "t": self.session.clock(), "k": float(self.sim.state.k), "com_dist": float(info.com_dist[0]),
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


def accepts(scenario: Scenario) -> bool:
    return scenario.acoustics is not None


def refuse(scenario: Scenario) -> None:
    if not accepts(scenario):
        raise PresetError([f"acoustics: {scenario.name} has no [acoustics] section"])


KIND = AppKind(name="sonar", title="Chapter 6–8 acoustic swarm", priority=30, accepts=accepts, refuse=refuse,
               make_driver=SonarDriver, notes="ch6-8")


def driver(session: Session) -> SonarDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, SonarDriver), session.kind.name
    return session.driver
