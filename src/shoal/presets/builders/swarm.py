"""The Chapter 3 swarm of a scenario (:class:`~shoal.engine.kinds.swarm.Simulation`), and the
keywords that retune a running one."""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.engine.core.objectives import Objective
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.coeffs import Constant, Physical, Segment
from shoal.engine.pso.laws import Law

from ..models import Controller, ObjectiveModel, Scenario
from .positions import positions_for


def policy_for(c: Controller) -> Constant | Physical:
    if c.mode == "raw":
        return Constant(omega=c.omega, c=(c.c1, c.c2))
    segments = (Segment(0.0, c.U, c.A_plus),) + tuple(Segment(s.t_start, s.U, s.A_plus) for s in c.schedule)
    return Physical(segments=segments, c1_share=c.c1_share)


def law_for(c: Controller) -> Law:
    return Law(name=c.law, smooth_width=c.smooth_width)


def xyz(v: tuple[float, float], d: int = 3) -> np.ndarray:
    """A preset's (x, y) as a point in max(d, 3) dimensions (the others 0): any ``sim.d`` takes its first d."""
    return np.concatenate([np.asarray(v, dtype=float), np.zeros(max(d, 3) - 2)])


def objective_for(o: ObjectiveModel, d: int = 3) -> Objective:
    return Objective(name=o.kind, source=xyz(o.source, d), scale=o.scale,
                     bounds=None if o.bounds is None else (float(o.bounds[0]), float(o.bounds[1])),
                     boundary=o.boundary or "periodic")


def build_simulation(
    scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0
) -> Simulation:
    """A Chapter 3 swarm for runs ``first_run … first_run + runs − 1`` of the seed (on SLO
    positions with ``[slo] swarm = "host"``)."""
    s = scenario
    return Simulation(
        robots=s.sim.robots, d=s.sim.d, dt=s.controller.dt, law=law_for(s.controller), policy=policy_for(s.controller),
        objective=objective_for(s.objective, s.sim.d), runs=runs or s.sim.runs,
        seed=s.sim.seed if seed is None else seed, first_run=first_run, attractors=s.bests.attractors,
        pbest_order=s.bests.pbest_order, init_center=xyz(s.init.center, s.sim.d), init_spread=s.init.spread,
        init_speed=s.init.speed, positions=positions_for(scenario),
    )


def swarm_keywords(s: Scenario) -> dict[str, Any]:
    """The ``Simulation.retune`` keywords of a scenario's controller, swarm size, bests and objective."""
    c = s.controller
    return dict(policy=policy_for(c), law=law_for(c), dt=float(c.dt), robots=s.sim.robots,
                attractors=s.bests.attractors, pbest_order=s.bests.pbest_order,
                objective=objective_for(s.objective, s.sim.d))


def swarm_retune(old: Scenario, new: Scenario) -> dict[str, Any]:
    """The keywords that take a running swarm to ``new`` (all of them: the engine keeps what did not change)."""
    return swarm_keywords(new)
