"""What one browser tab may ask of a server that many tabs share.

The preset model allows swarms sized for headless Monte-Carlo runs (``shoal run``); the app
steps and draws every tab on one machine, so a scene far beyond what its sliders offer (an
uploaded preset with ``sim.robots = 100000``, a replay of three million robots, a sweep of
``sim.steps`` up to ten million) would stall every other tab or exhaust the memory. Every
path by which a page asks for work is checked here, against the one cost function
(:func:`shoal.studies.cost.cost`: steps × robots × runs × kind):

- a live scene: at most :data:`MAX_ROBOTS` robots and :data:`MAX_DIMS` dimensions of its
  kind, a tick within :data:`LIVE_TICK_SECONDS` (every term that scales it: robots, ``sim.d``,
  pairs, obstacles, waveforms) and a world laid out within :data:`LIVE_WORLD_SECONDS`
  (:func:`check_app_limits`; an upload, Compare's swarm B and every cell of a sweep pass it);
- a replay (and the Share page drawn from a recording): at most that many robots in any frame,
  swarm A and swarm B (:func:`check_recording`; ``replay.from_bytes`` refuses more robot rows
  in all than a session records before it unpacks them);
- a sweep: every cell as a live scene, its steps within the server's limit whichever field is
  swept, and the estimated CPU of all its runs within a budget (:func:`check_runs`, used by
  :mod:`.experiment.request`);
- ``shoal export-replay`` states the cost before it runs and shows progress (Ctrl-C stops it).

Such a scene is refused by field, like any other bad value; headless runs keep the model's
full range.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.presets.io import PresetError
from shoal.presets.kinds import KINDS, kind_for
from shoal.presets.models import Scenario
from shoal.studies.cost import Cost, cost, costliest_field, forest_trees, tick_cost, world_cost

# Robots and dimensions per kind of scene in one tab: the caps of the kinds' registry entries (presets/kinds.py).
MAX_ROBOTS = {cap.label: cap.robots for kind in KINDS.values() for cap in kind.caps}
MAX_DIMS = {cap.label: cap.d for kind in KINDS.values() for cap in kind.caps if cap.d is not None}
LIVE_TICK_SECONDS = 0.02  # estimated CPU of one live tick (every built-in kind at its robot cap is within it)
LIVE_WORLD_SECONDS = 1.0  # estimated CPU of laying out a live scene's world (the sliders' largest forest is within it)


def scene_kind(scenario: Scenario) -> str:
    """The kind of scene whose robot cap applies to ``scenario`` (its kind's first cap that holds)."""
    return kind_for(scenario).cap(scenario).label


def robot_cap(scenario: Scenario) -> int:
    """The most robots a tab may show of ``scenario``'s kind."""
    return kind_for(scenario).cap(scenario).robots


def check_app_limits(scenario: Scenario) -> Scenario:
    """``scenario`` if one browser tab may run it, else :class:`PresetError` naming the field."""
    limit = kind_for(scenario).cap(scenario)
    kind, cap = limit.label, limit.robots
    if scenario.sim.robots > cap:
        raise PresetError([f"sim.robots = {scenario.sim.robots}: the browser app runs at most {cap} robots "
                           f"in this kind of scene ({kind}); use `shoal run` for larger swarms"])
    if limit.d is not None and scenario.sim.d > limit.d:
        raise PresetError([f"sim.d = {scenario.sim.d}: the browser app runs at most {limit.d} dimensions "
                           f"in this kind of scene ({kind}); use `shoal run` for more"])
    tick = tick_cost(scenario)
    if tick > LIVE_TICK_SECONDS:
        field = costliest_field(scenario)
        raise PresetError([f"{field} = {_value(scenario, field)}: one step of this scene ({kind}) would cost about "
                           f"{tick * 1e3:.3g} ms, more than the {LIVE_TICK_SECONDS * 1e3:.3g} ms a browser tab may; "
                           "use `shoal run` for larger scenes"])
    world = world_cost(scenario)
    if world > LIVE_WORLD_SECONDS:
        raise PresetError([f"world: laying out this world (a forest of about {forest_trees(scenario):,.0f} trees) "
                           f"would cost about {world:.3g} s of CPU, more than the {LIVE_WORLD_SECONDS:.3g} s a browser "
                           "tab may; a smaller world.width or world.density, or `shoal run`"])
    return scenario


def _value(scenario: Scenario, field: str) -> str:
    section, name = field.split(".")
    value = getattr(getattr(scenario, section, None), name, None)
    return f"{len(value):,} circles" if isinstance(value, list) else f"{value}"


def check_runs(scenario: Scenario, *, steps: int, runs: int, max_steps: int, max_seconds: float,
               what: str = "") -> Cost:
    """The :class:`Cost` of ``runs`` runs of ``steps`` ticks of ``scenario`` if a shared server
    may run them (a live scene's limits, at most ``max_steps`` steps, at most ``max_seconds``
    of estimated CPU), else :class:`PresetError` naming the fields (``what``: where, e.g. a cell)."""
    at = f" ({what})" if what else ""
    check_app_limits(scenario)
    if steps > max_steps:
        raise PresetError([f"sim.steps = {steps:,}{at}: this server runs at most {max_steps:,} steps per run"])
    c = cost(scenario, steps=steps, runs=runs)
    if c.seconds > max_seconds:
        raise PresetError([f"{c.describe()}{at}: more than the {max_seconds:,.0f} CPU seconds this server "
                           "gives one request; fewer steps, robots or runs"])
    return c


def check_recording(rec: Any, scenario: Scenario, twin: Scenario | None = None, where: str = "replay") -> None:
    """Refuse (:class:`PresetError`) a recording (``replay.Recording``) of ``scenario`` (and of
    swarm B's ``twin``) a tab may not show: a frame of more robots than a live scene of its
    kind may have (a replay holds at most 3 dimensions: ``replay.from_bytes``)."""
    problems = []
    for swarm, counts, sc in (("", rec.n, scenario), ("swarm B: ", rec.b_n, twin or scenario)):
        cap, kind = robot_cap(sc), scene_kind(sc)
        most = int(np.max(counts)) if len(counts) else 0
        if most > cap:
            problems.append(f"{where}: {swarm}a frame of {most:,} robots; the browser app shows at most {cap} "
                            f"in this kind of scene ({kind})")
    if problems:
        raise PresetError(problems)
