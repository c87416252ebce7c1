"""The Chapter 3 swarm in free space (a :class:`Simulation`), on true or SLO-estimated positions.

Its controller (law, ω, c1, c2 or U, A+, Δt), the swarm size, the bests and the objective
change the running swarm; the SLO error set and localisation settings retune its running SLO
source; the dimension, the start, the oracle/SLO switch and the SLO unit rebuild it with the
same seed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shoal.engine.objectives import Objective
from shoal.engine.sim import Simulation
from shoal.presets.build import build_simulation, law_for, objective_for, policy_for, slo_unit
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.beliefs import host_ghosts
from ..session.history import Frame, frame_of
from ..session.positions import positions_of, slo_retune
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view.canvas import Canvas
from ..view.layers import (
    Ghosts,
    GlobalBest,
    Ground,
    Headings,
    Landscape,
    Layer,
    LegendEntry,
    PersonalBests,
    Robots,
    Static,
    Trails,
    Twin,
)
from ..view.view import KeepSwarmInView
from .base import AppKind, BaseDriver

ROBOT = (220, 50, 50)
ROBOT_SIZE = 0.24  # scene units: the disc drawn has this radius
HEADING = (120, 20, 20)
TRAIL = (80, 120, 255)
PBEST = (110, 110, 110)
GBEST = (240, 170, 0)
SOURCE = (20, 150, 60)
ARENA = (40, 40, 40)
BENCHMARKS = ("sphere", "rastrigin", "ackley", "rosenbrock", "griewank")


def _changed(old: Scenario, new: Scenario, name: str) -> bool:
    return getattr(old, name).model_dump() != getattr(new, name).model_dump()


class SwarmDriver(BaseDriver):
    """A Chapter 3 swarm's side of a session."""

    metrics = ("max_speed", "max_component", "omega", "c_hat")
    scene_sections = ("objective", "arena")
    sim: Simulation

    def build(self, scenario: Scenario) -> Simulation:
        return build_simulation(scenario, runs=1)

    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        return (new.sim.d != old.sim.d or _changed(old, new, "init") or slo_retune(old, new) is None
                or (positions_of(new) == "slo" and slo_unit(new) != slo_unit(old)))

    def live(self, old: Scenario, new: Scenario) -> dict[str, Any]:
        slo = slo_retune(old, new)  # errors, selection, neighbourhood…: the running SLO source keeps its beliefs
        c = new.controller
        return dict(policy=policy_for(c), law=law_for(c), dt=float(c.dt), robots=new.sim.robots,
                    attractors=new.bests.attractors, pbest_order=new.bests.pbest_order,
                    objective=objective_for(new.objective), **({"slo": slo} if slo else {}))

    def frame(self, t: float) -> Frame:
        return frame_of(self.sim.state, t, accelerations=True)

    def metric_row(self, info: Any) -> tuple[float, ...]:
        u = self.sim.state.u[0]
        omega, c_hat = self.coefficients()
        return (float(np.linalg.norm(u, axis=-1).max()), float(np.abs(u).max()), omega, c_hat)

    def snapshot(self, selected: int) -> dict[str, Any]:
        s = self.sim.state
        return {"y": s.y[0].copy(), "yg": s.yg[0].copy(), "ghosts": host_ghosts(self.sim, selected, s.yg[0])}

    def coefficients(self) -> tuple[float, float]:
        """The (ω, ĉ) the controller uses at the current time (means over robots for per-robot policies)."""
        with self.session.lock:
            sim = self.sim
            omega, c = sim.policy.coefficients(sim.t, sim.dt, sim.d)
            c = np.asarray(c, dtype=float)
            c_hat = float(np.sum(c.reshape(c.shape[0], -1).mean(axis=1))) if c.ndim else float(c)
            return float(np.mean(omega)), c_hat

    def readout(self) -> dict[str, float]:
        """Derived quantities for the panel: ω, ĉ, β, U, U_j, A+, A− (NaN where undefined)."""
        omega, c_hat = self.coefficients()
        d, dt = self.sim.d, self.sim.dt
        adapted = self.sim.law.adapted
        bounded = adapted and 0.0 <= omega < 1.0
        U_j = c_hat / (1.0 - omega) if bounded else math.nan
        A_plus = c_hat * math.sqrt(d) / dt if adapted else math.nan
        return {
            "omega": omega, "c_hat": c_hat, "beta": (1.0 - omega) if bounded else math.nan,
            "U": U_j * math.sqrt(d), "U_j": U_j, "A_plus": A_plus, "A_minus": 2 * A_plus,
            "t": self.session.clock(), "k": float(self.sim.state.k), "best": float(self.sim.state.best_fitness[0]),
            "outside": float(self.outside_arena()),
        }

    def outside_arena(self) -> int:
        """How many robots are outside the arena square (a diverging swarm leaves the picture)."""
        with self.session.lock:
            x = self.sim.state.x[0, :, :2]
            return int(np.sum(np.any(np.abs(x) > self.session.scenario.arena.half_size, axis=-1)))

    def particle_history(self, robot: int, dim: int, n: int = 120) -> tuple[np.ndarray, np.ndarray]:
        """The last ``n`` (u_j, a_j) of one particle and dimension, oldest first."""
        with self.session.lock:
            frames = list(self.session.history.frames)[-n:]
        pts = [(f.u[robot, dim], f.a[robot, dim]) for f in frames
               if f.a is not None and robot < f.u.shape[0] and dim < f.u.shape[1]]
        arr = np.array(pts, dtype=float).reshape(-1, 2)
        return arr[:, 0], arr[:, 1]


# ---------------------------------------------------------------------------- view
class Optimum(Static):
    """Where the objective is best (a benchmark's optimum, or the source), with its name."""

    name = "optimum"
    keys = ("source", "source_label")
    legend = (LegendEntry("●", SOURCE, "optimum / source"),)

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        o = snap.scenario.objective
        if o.kind == "linear":
            return
        where = np.asarray(o.source, dtype=float) if snap.scenario.sim.d >= 2 else np.array([o.source[0], 0.0])
        canvas.points("source", where[None], SOURCE, 0.3, "circle", 0.01)
        canvas.label("source_label", "source" if o.kind == "source-distance" else "optimum", where + 0.5 / canvas.scale)


def landscape(scenario: Scenario) -> Objective | None:
    """The benchmark objectives of a 2-D (or 3-D) swarm are drawn as a heat map."""
    o = scenario.objective
    return objective_for(o) if o.kind in BENCHMARKS and scenario.sim.d >= 2 else None


def layers(panels: Any) -> tuple[Layer, ...]:
    """The Chapter 3 arena: the square with its grid, the landscape or the source, the robots
    with their headings, trails and bests; swarm B and the selected robot's beliefs."""
    return (
        Ground(cell=lambda half: half / 10, cell_colour=(225, 225, 225), section_colour=(185, 185, 185), z=-0.02,
               border=ARENA, border_px=2.5, border_z=0.0, fade=100.0),
        Landscape(landscape, z=-0.04),
        Optimum(),
        Trails(TRAIL, 1.5, 0.0),
        PersonalBests(PBEST, 0.1, 0.005),
        Headings(HEADING, lambda canvas, snap: 0.35 / canvas.scale, 0.015),
        Robots(ROBOT, ROBOT_SIZE, 0.02),
        GlobalBest(GBEST, 0.4, 0.012),
        Twin(ROBOT_SIZE, (0.018, -0.001), px=1.5),
        Ghosts(ROBOT_SIZE),
    )


def supported(scenario: Scenario) -> None:
    """A free-space swarm needs mode raw or physical (DVC needs a [world])."""
    if scenario.world is None and scenario.controller.mode not in ("raw", "physical"):
        raise PresetError([f"controller.mode: {scenario.controller.mode!r} needs a [world]; the browser app "
                           "offers 'raw' and 'physical' without one"])


def accepts(scenario: Scenario) -> bool:
    """Free-space swarms, on true or (``[slo] swarm = "host"``) SLO-estimated positions."""
    return scenario.world is None and (scenario.slo is None or scenario.slo.swarm == "host")


def refuse(scenario: Scenario) -> None:
    supported(scenario)
    if scenario.world is not None:
        raise PresetError([f"world: {scenario.name} has obstacles; it runs as a fleet, not a free swarm"])
    if not accepts(scenario):
        raise PresetError([f"slo.swarm: {scenario.name} runs Mai's SLO swarm (swarm = 'slo'), not the "
                           "Chapter 3 swarm; set slo.swarm = 'host' for the Chapter 3 swarm on SLO positions"])


KIND = AppKind(name="swarm", title="Chapter 3 swarm", priority=10, accepts=accepts, refuse=refuse,
               make_driver=SwarmDriver, notes="ch3", layers=layers, camera=KeepSwarmInView)


def driver(session: Session) -> SwarmDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, SwarmDriver), session.kind.name
    return session.driver
