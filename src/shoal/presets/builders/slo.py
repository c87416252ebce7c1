"""Mai's SLO swarm of a scenario (:class:`~shoal.engine.kinds.slo_swarm.SLOSwarm`), the SLO
positions of a host swarm (``[slo] swarm = "host"``), and the keywords that retune either."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.slo.positions import Estimated
from shoal.engine.slo.sensors import ErrorModel, error_model

from ..kinds import SLO_LIVE
from ..models import SLO, Scenario, on_slo_positions, required

if TYPE_CHECKING:
    from shoal.engine.robots.world import WorldSpec


def slo_errors_for(slo: SLO) -> str | ErrorModel:
    """The error set of an ``[slo]`` section, with its single values applied."""
    values = slo.error_values.values()
    return error_model(slo.errors).with_values(**values) if values else slo.errors


def slo_unit(scenario: Scenario, world: WorldSpec | None = None) -> float:
    """Metres per thesis length unit (``slo.unit`` if set). The thesis area is 100 wide
    (docs/readings.md, "Thesis units on a scene (ours)"), so the area the swarm works in over
    100: the larger side of a fleet's world; for an acoustic swarm its deployment disc (2·d_0;
    the drawn arena is a window several times larger, whose unit would make the additive
    odometry errors many times a step); the arena's width otherwise."""
    if scenario.slo is not None and scenario.slo.unit is not None:
        return scenario.slo.unit
    if scenario.world is not None:
        if world is None:
            from .world import world_for  # (a fleet's world: only a fleet on SLO positions lays one out here)

            world = world_for(scenario.world)
        x0, y0, x1, y1 = world.bounds
        return max(x1 - x0, y1 - y0) / 100.0
    if scenario.acoustics is not None and scenario.acoustics.d_0 > 0:
        return 2.0 * scenario.acoustics.d_0 / 100.0
    return 2.0 * scenario.arena.half_size / 100.0


def _unit_from(scenario: Scenario) -> tuple[str, Any]:
    """What :func:`slo_unit` reads for ``scenario`` (equal for two scenarios: the same unit), without
    laying out a world."""
    slo, a = scenario.slo, scenario.acoustics
    if slo is not None and slo.unit is not None:
        return "unit", slo.unit
    if scenario.world is not None:
        return "world", scenario.world.model_dump_json()
    if a is not None and a.d_0 > 0:
        return "d_0", a.d_0
    return "arena", scenario.arena.half_size


def slo_localiser_for(slo: SLO) -> dict:
    """The localisation keywords shared by :class:`SLOSwarm` and the host swarms on SLO
    positions (:class:`~shoal.engine.slo.positions.Estimated`)."""
    return dict(
        errors=slo_errors_for(slo), selection=slo.selection, prediction_weight=slo.prediction_weight,
        delta_cos=slo.delta_cos, delta_v=slo.delta_v, literal_eq_3_1=slo.literal_eq_3_1, entry_policy=slo.entry_policy,
        neighbourhood=slo.neighbourhood, neighbourhood_param=slo.neighbourhood_param,
    )


def estimated_for(scenario: Scenario, world: WorldSpec | None = None) -> Estimated:
    """The SLO-estimated positions of a host swarm (``world``: a fleet's laid-out world)."""
    slo = required(scenario.slo, "slo")
    return Estimated(**slo_localiser_for(slo), unit=slo_unit(scenario, world))


def build_slo_swarm(scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
                    first_run: int = 0) -> SLOSwarm:
    """Mai's SLO swarm of an ``[slo]`` section (``swarm = "slo"``)."""
    slo = required(scenario.slo, "slo")
    return SLOSwarm(
        runs=runs or scenario.sim.runs, seed=scenario.sim.seed if seed is None else seed, first_run=first_run,
        particles=scenario.sim.robots, objective=slo.objective, motion=slo.motion, walk_speed=slo.walk_speed,
        quality_threshold=slo.quality_threshold, radial=slo.radial, ranging=slo.ranging or "all",
        **slo_localiser_for(slo),
    )


# ---------------------------------------------------------------- a running engine, retuned
def slo_keywords(old: Scenario, new: Scenario) -> dict[str, Any]:
    """The engine keywords of the :data:`~shoal.presets.kinds.SLO_LIVE` fields that differ between
    ``old``'s and ``new``'s ``[slo]`` (``errors`` stands for the set and its values)."""
    a, b = required(old.slo, "slo"), required(new.slo, "slo")
    out: dict[str, Any] = {}
    for key in SLO_LIVE:
        if getattr(a, key) != getattr(b, key):
            if key in ("errors", "error_values"):
                out["errors"] = slo_errors_for(b)
            elif key == "neighbourhood":
                out.update(neighbourhood=b.neighbourhood, neighbourhood_param=b.neighbourhood_param)
            else:
                out[key] = getattr(b, key)
    return out


def slo_live_changes(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """The engine keywords that take ``old`` to ``new`` without a rebuild, or None when
    anything else differs (beyond the view)."""
    if old.slo is None or new.slo is None:
        return None
    a, b = old.model_dump(), new.model_dump()
    for d in (a, b):
        d["view"] = None
        d["slo"] = {k: v for k, v in d["slo"].items() if k not in SLO_LIVE}
    return slo_keywords(old, new) if a == b else None


MAI_ONLY = ("objective", "walk_speed", "quality_threshold")  # SLO_LIVE fields only Mai's own swarm takes


def host_slo_retune(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """``retune(slo=...)`` keywords taking a running host swarm from ``old``'s ``[slo]`` to
    ``new``'s: {} when its position source has nothing to change (no change, or true positions
    both), None when the change needs a new engine (the switch between true and SLO positions,
    another length unit, or a setting that cannot change mid-run)."""
    on = on_slo_positions(new)
    if on_slo_positions(old) != on:
        return None
    if not on:
        return {}  # nothing localises: the run is the scene's without SLO
    if _unit_from(old) != _unit_from(new):
        return None
    if old.slo == new.slo:
        return {}
    changes = slo_live_changes(old, old.model_copy(update={"slo": new.slo}))
    return None if changes is None else {k: v for k, v in changes.items() if k not in MAI_ONLY}
