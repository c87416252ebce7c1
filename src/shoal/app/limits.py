"""What one browser tab may ask of a server that many tabs share.

The preset model allows swarms sized for headless Monte-Carlo runs (``shoal run``); the app
steps and draws every tab on one machine, so a scene far beyond what its sliders offer (an
uploaded preset with ``sim.robots = 100000``, say) would stall every other tab or exhaust the
memory. Such a scene is refused by field, like any other bad value; headless runs keep the
model's full range.
"""

from __future__ import annotations

from shoal.presets.io import PresetError
from shoal.presets.kinds import KINDS, kind_for
from shoal.presets.models import Scenario

# Robots per kind of scene in one tab: the caps of the kinds' registry entries (presets/kinds.py).
MAX_ROBOTS = {cap.label: cap.robots for kind in KINDS.values() for cap in kind.caps}


def scene_kind(scenario: Scenario) -> str:
    """The kind of scene whose robot cap applies to ``scenario`` (its kind's first cap that holds)."""
    return kind_for(scenario).cap(scenario).label


def check_app_limits(scenario: Scenario) -> Scenario:
    """``scenario`` if one browser tab may run it, else :class:`PresetError` naming the field."""
    limit = kind_for(scenario).cap(scenario)
    kind, cap = limit.label, limit.robots
    if scenario.sim.robots > cap:
        raise PresetError([f"sim.robots = {scenario.sim.robots}: the browser app runs at most {cap} robots "
                           f"in this kind of scene ({kind}); use `shoal run` for larger swarms"])
    return scenario
