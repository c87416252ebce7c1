"""Turn a validated :class:`Scenario` into engine objects."""

from __future__ import annotations

import numpy as np

from shoal.engine.coeffs import Constant, Physical, Segment
from shoal.engine.laws import Law
from shoal.engine.objectives import Objective
from shoal.engine.sim import Simulation

from .models import Controller, ObjectiveModel, Scenario


def policy_for(c: Controller) -> Constant | Physical:
    if c.mode == "raw":
        return Constant(omega=c.omega, c=(c.c1, c.c2))
    segments = (Segment(0.0, c.U, c.A_plus),) + tuple(Segment(s.t_start, s.U, s.A_plus) for s in c.schedule)
    return Physical(segments=segments, c1_share=c.c1_share)


def law_for(c: Controller) -> Law:
    return Law(name=c.law, smooth_width=c.smooth_width)


def objective_for(o: ObjectiveModel) -> Objective:
    return Objective(name=o.kind, source=np.asarray(o.source, dtype=float), scale=o.scale)


def build_simulation(
    scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0
) -> Simulation:
    """A Chapter 3 swarm for runs ``first_run … first_run + runs − 1`` of the seed."""
    s = scenario
    return Simulation(
        robots=s.sim.robots,
        d=s.sim.d,
        dt=s.controller.dt,
        law=law_for(s.controller),
        policy=policy_for(s.controller),
        objective=objective_for(s.objective),
        runs=runs or s.sim.runs,
        seed=s.sim.seed if seed is None else seed,
        first_run=first_run,
        attractors=s.bests.attractors,
        pbest_order=s.bests.pbest_order,
        init_center=np.asarray(s.init.center, dtype=float),
        init_spread=s.init.spread,
        init_speed=s.init.speed,
    )
