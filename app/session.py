"""The Chapter 3 session: one browser tab's free-space swarm (a :class:`Simulation`).

Playback, history and export come from :class:`BaseSession`; this module adds what is
particular to the Chapter 3 swarm: its controller changes without restart, the (ω, ĉ)
readout, the phase-plane history and the arena snapshot.

The swarm may act on SLO-estimated positions (``[slo] swarm = "host"``: its
:class:`~shoal.engine.slo.positions.Estimated` positions, the *Positions* folder of
:mod:`.positions_panel`). Controller, swarm size and objective changes reach it like the
oracle swarm; the error set and the localisation settings retune its running SLO source;
the oracle/SLO switch (and the SLO unit) rebuild it with the same seed.

Every change goes through the pydantic :class:`Scenario` first (``apply``): a value the model
refuses raises :class:`PresetError` and leaves both the scenario and the swarm untouched.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from shoal.engine.core.recorder import TRAJECTORY_COLUMNS
from shoal.engine.kinds.swarm import Simulation
from shoal.presets import io as presets_io
from shoal.presets.build import build_simulation, law_for, objective_for, policy_for, slo_unit
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .base_session import MAX_UPLOAD_BYTES, BaseSession, Frame
from .ghosts import Ghosts, host_ghosts
from .positions import positions_of, slo_retune

__all__ = ["MAX_UPLOAD_BYTES", "TRAJECTORY_COLUMNS", "Frame", "Session", "Snapshot", "app_presets",
           "check_supported"]


def check_supported(scenario: Scenario) -> Scenario:
    """Refuse scenes the browser app cannot show: a free-space swarm needs mode raw or physical
    (DVC needs a [world]); scenes with a [world] run as fleets."""
    if scenario.world is None and scenario.controller.mode not in ("raw", "physical"):
        raise PresetError([f"controller.mode: {scenario.controller.mode!r} needs a [world]; the browser app "
                           "offers 'raw' and 'physical' without one"])
    return scenario


@functools.lru_cache(maxsize=1)
def app_presets() -> dict[str, str]:
    """Shipped presets the browser app can run, name → one-line description."""
    out = {}
    for name, description in presets_io.list_presets().items():
        try:
            check_supported(presets_io.load_shipped(name))
        except PresetError:
            continue
        out[name] = description
    return out


@dataclass(frozen=True)
class Snapshot:
    """A consistent copy of what the arena draws, taken under the lock."""

    k: int
    t: float
    x: np.ndarray  # (N, d)
    heading: np.ndarray  # (N,)
    y: np.ndarray  # (N, d) personal bests
    yg: np.ndarray  # (d,) global best
    trails: np.ndarray  # (M, L, d) oldest first, M ≤ N
    revision: int
    live: bool = True  # False: a recorded frame (timeline, replay): bests not known
    ghosts: Ghosts | None = None  # the selected robot's beliefs (SLO positions)


def _section_changed(old: Scenario, new: Scenario, name: str) -> bool:
    return getattr(old, name).model_dump() != getattr(new, name).model_dump()


class Session(BaseSession):
    """Simulation and playback state of one browser tab running a Chapter 3 swarm."""

    METRICS = ("t", "max_speed", "max_component", "omega", "c_hat")
    NOTES = "ch3"

    def __init__(self, scenario: Scenario) -> None:
        self.selected_dim = 0
        super().__init__(scenario)

    @classmethod
    def accepts(cls, scenario: Scenario) -> bool:
        """Free-space swarms, on true or (``[slo] swarm = "host"``) SLO-estimated positions."""
        return scenario.world is None and (scenario.slo is None or scenario.slo.swarm == "host")

    @classmethod
    def check(cls, scenario: Scenario) -> Scenario:
        check_supported(scenario)
        if scenario.world is not None:
            raise PresetError([f"world: {scenario.name} has obstacles; it runs as a fleet, not a free swarm"])
        if not cls.accepts(scenario):
            raise PresetError([f"slo.swarm: {scenario.name} runs Mai's SLO swarm (swarm = 'slo'), not the "
                               "Chapter 3 swarm; set slo.swarm = 'host' for the Chapter 3 swarm on SLO positions"])
        return scenario

    def _build(self, scenario: Scenario) -> Simulation:
        return build_simulation(scenario, runs=1)

    def load_scenario(self, scenario: Scenario) -> None:
        super().load_scenario(scenario)
        with self.lock:
            self.selected_dim = min(self.selected_dim, scenario.sim.d - 1)

    # ------------------------------------------------------------------ changes
    def _adopt(self, new: Scenario) -> None:
        old, sim = self.scenario, self.sim
        retune = slo_retune(old, new)  # None: the positions switch or the SLO unit changed
        if (new.sim.d != old.sim.d or _section_changed(old, new, "init") or retune is None
                or (positions_of(new) == "slo" and slo_unit(new) != slo_unit(old))):
            self._load(new)
            self.selected_robot = min(self.selected_robot, new.sim.robots - 1)
            self.revision += 1
            return
        if _section_changed(old, new, "controller"):
            self._keep_clock()
        # errors, selection, neighbourhood… (``slo``): the running SLO source keeps its beliefs
        changed = sim.retune(policy=policy_for(new.controller), law=law_for(new.controller),
                             dt=float(new.controller.dt), robots=new.sim.robots, attractors=new.bests.attractors,
                             pbest_order=new.bests.pbest_order, objective=objective_for(new.objective),
                             **({"slo": retune} if retune else {}))
        self.scenario = new
        if "robots" in changed:
            self.selected_robot = min(self.selected_robot, new.sim.robots - 1)
        if "objective" in changed:
            self.scene_revision += 1
        if _section_changed(old, new, "arena"):
            self.scene_revision += 1
        if new.sim.seed != old.sim.seed:
            self._reset_locked(new.sim.seed)
        self.revision += 1

    # ------------------------------------------------------------------ history
    def _frame(self) -> Frame:
        s = self.sim.state
        return Frame(k=s.k, t=self.clock(), x=s.x[0].copy(), u=s.u[0].copy(), a=s.a[0].copy(),
                     heading=s.heading[0].copy(), status=s.status[0].copy())

    def _metric_row(self, info: Any) -> tuple[float, ...]:
        s = self.sim.state
        omega, c_hat = self.coefficients()
        speed = np.linalg.norm(s.u[0], axis=-1)
        return (self.clock(), float(speed.max()), float(np.abs(s.u[0]).max()), omega, c_hat)

    def _replay_blanks(self, frame: Frame) -> dict[str, Any]:
        return {"y": frame.x.copy()}  # bests are not recorded (and not drawn)

    def coefficients(self) -> tuple[float, float]:
        """The (ω, ĉ) the controller uses at the current time (means over robots for per-robot policies)."""
        with self.lock:
            omega, c = self.sim.policy.coefficients(self.sim.t, self.sim.dt, self.sim.d)
            c = np.asarray(c, dtype=float)
            c_hat = float(np.sum(c.reshape(c.shape[0], -1).mean(axis=1))) if c.ndim else float(c)
            return float(np.mean(omega)), c_hat

    def readout(self) -> dict[str, float]:
        """Derived quantities for the panel: ω, ĉ, β, U, U_j, A+, A− (NaN where undefined)."""
        with self.lock:
            omega, c_hat = self.coefficients()
            d, dt = self.sim.d, self.sim.dt
            adapted = self.sim.law.adapted
            bounded = adapted and 0.0 <= omega < 1.0
            U_j = c_hat / (1.0 - omega) if bounded else math.nan
            A_plus = c_hat * math.sqrt(d) / dt if adapted else math.nan
            return {
                "omega": omega, "c_hat": c_hat, "beta": (1.0 - omega) if bounded else math.nan,
                "U": U_j * math.sqrt(d), "U_j": U_j, "A_plus": A_plus, "A_minus": 2 * A_plus,
                "t": self.clock(), "k": float(self.sim.state.k), "best": float(self.sim.state.best_fitness[0]),
                "outside": float(self.outside_arena()),
            }

    def outside_arena(self) -> int:
        """How many robots are outside the arena square (a diverging swarm leaves the picture)."""
        with self.lock:
            x = self.sim.state.x[0, :, :2]
            return int(np.sum(np.any(np.abs(x) > self.scenario.arena.half_size, axis=-1)))

    def snapshot(self, max_trails: int = 80, max_trail_points: int = 40) -> Snapshot:
        """What the arena draws now: positions, bests and trails of the last ``view.trail_seconds``."""
        with self.lock:
            s = self.sim.state
            return Snapshot(k=s.k, t=self.clock(), x=s.x[0].copy(), heading=s.heading[0].copy(), y=s.y[0].copy(),
                            yg=s.yg[0].copy(), trails=self.trails(max_trails, max_trail_points),
                            revision=self.revision,
                            ghosts=host_ghosts(self.sim, min(self.selected_robot, self.sim.robots - 1), s.yg[0]))

    def particle_history(self, robot: int, dim: int, n: int = 120) -> tuple[np.ndarray, np.ndarray]:
        """The last ``n`` (u_j, a_j) of one particle and dimension, oldest first."""
        with self.lock:
            frames = list(self.frames)[-n:]
            pts = [(f.u[robot, dim], f.a[robot, dim]) for f in frames
                   if robot < f.u.shape[0] and dim < f.u.shape[1]]
            arr = np.array(pts, dtype=float).reshape(-1, 2)
            return arr[:, 0], arr[:, 1]

