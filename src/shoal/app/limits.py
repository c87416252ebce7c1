"""What one browser tab may ask of a server that many tabs share.

The preset model allows swarms sized for headless Monte-Carlo runs (``shoal run``); the app
steps and draws every tab on one machine, so a scene far beyond what its sliders offer (an
uploaded preset with ``sim.robots = 100000``, say) would stall every other tab or exhaust the
memory. Such a scene is refused by field, like any other bad value; headless runs keep the
model's full range.
"""

from __future__ import annotations

from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

# Robots per scene kind, where one step still costs a few tens of ms at most: the compiled
# kinematic fleet tick takes 1000 robots in a few ms, pymunk physics 200 in about 20 ms; the
# SLO and acoustic swarms grow faster than linearly with the robots (about 2× the slider's top).
MAX_ROBOTS = {"free-space swarm": 2000, "fleet": 1000, "fleet, pymunk physics": 200, "acoustic swarm": 100,
              "SLO swarm": 100}


def scene_kind(scenario: Scenario) -> str:
    if scenario.slo is not None:
        return "SLO swarm"
    if scenario.acoustics is not None:
        return "acoustic swarm"
    if scenario.world is None:
        return "free-space swarm"
    return "fleet, pymunk physics" if scenario.robot.motion == "physics" else "fleet"


def check_app_limits(scenario: Scenario) -> Scenario:
    """``scenario`` if one browser tab may run it, else :class:`PresetError` naming the field."""
    kind = scene_kind(scenario)
    cap = MAX_ROBOTS[kind]
    if scenario.sim.robots > cap:
        raise PresetError([f"sim.robots = {scenario.sim.robots}: the browser app runs at most {cap} robots "
                           f"in this kind of scene ({kind}); use `shoal run` for larger swarms"])
    return scenario
