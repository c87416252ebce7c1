"""The Chapter 4–5 fleet of a scenario (:class:`~shoal.engine.kinds.fleet.Fleet`), and the
keywords that retune a running one."""

from __future__ import annotations

from typing import Any

from shoal.engine.kinds.fleet import Fleet, FleetParams

from ..models import Scenario, required
from .positions import positions_for
from .world import world_for


def fleet_params_for(s: Scenario) -> FleetParams:
    c, r = s.controller, s.robot
    return FleetParams(
        law=c.law, dvc=c.mode == "dvc", dt=c.dt, omega=c.omega, c=(c.c1, c.c2, c.c3), alpha=c.alpha, beta=c.beta,
        gamma=c.gamma, c1_share=c.c1_share, sensing_range=s.sensing.range, robot_radius=r.radius, v_max=r.v_max,
        a_max=r.a_max, motion=r.motion, drive=r.drive, r_min=c.r_min, s_min=c.s_min,
        rotational_energy=c.rotational_energy, update=c.update, guard=c.guard, spawn_gap=r.spawn_gap,
        contact_tolerance=r.contact_tolerance,
    )


def build_fleet(scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Fleet:
    """A Chapter 4–5 fleet (needs a ``[world]`` section; on SLO positions with ``[slo]
    swarm = "host"``)."""
    world = world_for(required(scenario.world, "world"))
    return Fleet(world=world, robots=scenario.sim.robots, params=fleet_params_for(scenario),
                 runs=runs or scenario.sim.runs, seed=scenario.sim.seed if seed is None else seed, first_run=first_run,
                 positions=positions_for(scenario, world))


def fleet_keywords(s: Scenario) -> dict[str, Any]:
    """The ``Fleet.retune`` keywords of a scenario (its :class:`FleetParams` in ``Fleet.LIVE``)."""
    params = fleet_params_for(s)
    return {k: getattr(params, k) for k in Fleet.LIVE - {"slo"}}


def fleet_retune(old: Scenario, new: Scenario) -> dict[str, Any]:
    """The keywords that take a running fleet to ``new`` (all of them: the engine keeps what did not change)."""
    return fleet_keywords(new)
