"""Turn a validated :class:`Scenario` into engine objects: one build function per scene kind
(each returning a :class:`~shoal.engine.core.contract.Engine`; the kinds' registry,
:mod:`.kinds`, names them), and the keywords that retune a running engine."""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Protocol

import numpy as np

from shoal.engine.core.contract import Engine
from shoal.engine.core.objectives import Objective
from shoal.engine.kinds.fleet import Fleet, FleetParams
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.kinds.sonar import AcousticSwarm, SonarParams
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.coeffs import Constant, Physical, Segment
from shoal.engine.pso.laws import Law
from shoal.engine.robots.world import WorldSpec, empty_arena, forest, obstacle_course
from shoal.engine.slo.positions import Estimated, Oracle, PositionSource
from shoal.engine.slo.sensors import ErrorModel, error_model

from .io import PresetError
from .models import SLO, Acoustics, Controller, ObjectiveModel, Scenario, WorldModel


def policy_for(c: Controller) -> Constant | Physical:
    if c.mode == "raw":
        return Constant(omega=c.omega, c=(c.c1, c.c2))
    segments = (Segment(0.0, c.U, c.A_plus),) + tuple(Segment(s.t_start, s.U, s.A_plus) for s in c.schedule)
    return Physical(segments=segments, c1_share=c.c1_share)


def law_for(c: Controller) -> Law:
    return Law(name=c.law, smooth_width=c.smooth_width)


def _xyz(v: tuple[float, float], d: int = 3) -> np.ndarray:
    """A preset's (x, y) as a point in max(d, 3) dimensions (the others 0): any ``sim.d`` takes its first d."""
    return np.concatenate([np.asarray(v, dtype=float), np.zeros(max(d, 3) - 2)])


def objective_for(o: ObjectiveModel, d: int = 3) -> Objective:
    return Objective(name=o.kind, source=_xyz(o.source, d), scale=o.scale,
                     bounds=None if o.bounds is None else (float(o.bounds[0]), float(o.bounds[1])),
                     boundary=o.boundary or "periodic")


def build_simulation(
    scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0
) -> Simulation:
    """A Chapter 3 swarm for runs ``first_run … first_run + runs − 1`` of the seed (on SLO
    positions with ``[slo] swarm = "host"``)."""
    return Simulation(**_simulation_kwargs(scenario, runs=runs, seed=seed, first_run=first_run),
                      positions=positions_for(scenario))


def _simulation_kwargs(scenario: Scenario, *, runs: int | None, seed: int | None, first_run: int) -> dict:
    s = scenario
    return dict(
        robots=s.sim.robots,
        d=s.sim.d,
        dt=s.controller.dt,
        law=law_for(s.controller),
        policy=policy_for(s.controller),
        objective=objective_for(s.objective, s.sim.d),
        runs=runs or s.sim.runs,
        seed=s.sim.seed if seed is None else seed,
        first_run=first_run,
        attractors=s.bests.attractors,
        pbest_order=s.bests.pbest_order,
        init_center=_xyz(s.init.center, s.sim.d),
        init_spread=s.init.spread,
        init_speed=s.init.speed,
    )


def world_error(msg: str) -> str:
    """A world generator's message ("length: ...") named by its preset field ("world.length: ...")."""
    field, sep, rest = msg.partition(":")
    if not sep or " " in field:
        return f"world: {msg}"
    return f"world.{ {'size': 'width'}.get(field, field)}:{rest}"


def world_for(w: WorldModel) -> WorldSpec:
    """The obstacle world of a ``[world]`` section; :class:`PresetError` naming the field when
    the generator cannot lay it out (the model allows some sizes that do not fit together)."""
    try:
        if w.kind == "obstacle-course":
            world = obstacle_course(seed=w.seed, layers=w.layers, length=w.length, width=w.width,
                                    start_size=w.start_size)
        elif w.kind == "forest":
            world = forest(seed=w.seed, size=w.width, density=w.density, start_size=w.start_size)
        else:
            world = empty_arena(size=w.width, start_size=w.start_size)
    except ValueError as err:
        raise PresetError([world_error(str(err))]) from None
    return world if w.obstacles is None else with_obstacles(world, w.obstacles)


def with_obstacles(world: WorldSpec, obstacles: list[tuple[float, float, float]]) -> WorldSpec:
    """``world`` with the circles of ``world.obstacles`` in place of its generated ones; a
    circle whose centre lies outside the world, or that reaches into the start box (the robots
    are placed there), is refused by its index."""
    circles = np.asarray(obstacles, dtype=float).reshape(-1, 3)
    x, y, r = circles.T
    x0, y0, x1, y1 = world.bounds
    outside = np.flatnonzero(~((x0 < x) & (x < x1) & (y0 < y) & (y < y1)))
    if outside.size:
        i = int(outside[0])
        raise PresetError([f"world.obstacles.{i}: centre ({x[i]:g}, {y[i]:g}) m is outside the "
                           f"world ({x0:g} < x < {x1:g}, {y0:g} < y < {y1:g})"])
    sx0, sy0, sx1, sy1 = world.start_box
    gap = np.hypot(x - np.clip(x, sx0, sx1), y - np.clip(y, sy0, sy1)) - r  # surface to the box
    inside = np.flatnonzero(gap < 0.0)
    if inside.size:
        i = int(inside[0])
        raise PresetError([f"world.obstacles.{i}: the circle ({x[i]:g}, {y[i]:g}, r = {r[i]:g}) m reaches into "
                           f"the start box ({sx0:g} < x < {sx1:g}, {sy0:g} < y < {sy1:g}), where the robots start"])
    return dataclasses.replace(world, circles=circles)


def check_world(scenario: Scenario) -> Scenario:
    """``scenario`` if its ``[world]`` (if any) can be laid out, else :class:`PresetError`."""
    if scenario.world is not None:
        _world_fits(scenario.world.model_dump_json())
    return scenario


@functools.lru_cache(maxsize=256)
def _world_fits(section: str) -> None:
    world_for(WorldModel.model_validate_json(section))


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
    if scenario.world is None:
        raise ValueError("this scenario has no [world] section")
    world = world_for(scenario.world)
    return Fleet(world=world, robots=scenario.sim.robots, params=fleet_params_for(scenario),
                 runs=runs or scenario.sim.runs, seed=scenario.sim.seed if seed is None else seed, first_run=first_run,
                 positions=positions_for(scenario, world))


def sonar_params_for(a: Acoustics) -> SonarParams:
    """The engine parameters of an ``[acoustics]`` section (angles in degrees → radians)."""
    return SonarParams(
        algorithm=a.algorithm, controller=a.controller, mode=a.mode, snr0_db=a.snr0_db, psd_s_db=a.psd_s,
        psd_n_db=a.psd_n, f_c=a.f_c, Q=a.Q, tbp=a.tbp, c=a.c, fs=a.fs, d_over_lambda=a.d_over_lambda,
        full_lag=a.full_lag, lag_peak=a.lag_peak, a=a.a, d0=a.d_0, dc=a.d_c, U=a.U, dt=a.dt, beta=a.beta,
        c1_share=a.c1_share,
        alpha_dvc=a.alpha_dvc, sensing_range=a.sensing_range, robot_radius=a.robot_radius, r_trap=a.r, v_n=a.v_n,
        source_heading=np.deg2rad(a.source_heading_deg),
        source_bearing=None if a.source_bearing_deg is None else float(np.deg2rad(a.source_bearing_deg)),
        source=None if a.source is None else (float(a.source[0]), float(a.source[1])),
        start=a.start, guard=a.guard, stop_on_converge=a.stop_on_converge,
    )


def build_sonar(scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
                first_run: int = 0) -> AcousticSwarm:
    """A Chapter 7–8 acoustic swarm (needs an ``[acoustics]`` section; on SLO positions with
    ``[slo] swarm = "host"``)."""
    if scenario.acoustics is None:
        raise ValueError("this scenario has no [acoustics] section")
    return AcousticSwarm(sonar_params_for(scenario.acoustics), robots=scenario.sim.robots,
                         runs=runs or scenario.sim.runs, seed=scenario.sim.seed if seed is None else seed,
                         first_run=first_run, positions=positions_for(scenario))


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
        x0, y0, x1, y1 = (world or world_for(scenario.world)).bounds
        return max(x1 - x0, y1 - y0) / 100.0
    if scenario.acoustics is not None and scenario.acoustics.d_0 > 0:
        return 2.0 * scenario.acoustics.d_0 / 100.0
    return 2.0 * scenario.arena.half_size / 100.0


def positions_for(scenario: Scenario, world: WorldSpec | None = None) -> PositionSource:
    """Where the scene's own swarm gets its positions: SLO estimates with ``[slo] swarm = "host"``,
    ``positions = "slo"``, else the truth."""
    slo = scenario.slo
    if slo is None or slo.swarm != "host" or slo.positions == "oracle":
        return Oracle()
    return Estimated(**slo_localiser_for(slo), unit=slo_unit(scenario, world))


def slo_localiser_for(slo: SLO) -> dict:
    """The localisation keywords shared by :class:`SLOSwarm` and the host swarms on SLO
    positions (:class:`~shoal.engine.slo.positions.Estimated`)."""
    return dict(
        errors=slo_errors_for(slo), selection=slo.selection, prediction_weight=slo.prediction_weight,
        delta_cos=slo.delta_cos, delta_v=slo.delta_v, literal_eq_3_1=slo.literal_eq_3_1, entry_policy=slo.entry_policy,
        neighbourhood=slo.neighbourhood, neighbourhood_param=slo.neighbourhood_param,
    )


# [slo] fields an engine can change mid-run (SLOSwarm.retune, a host swarm's retune(slo=...)).
SLO_LIVE = ("selection", "prediction_weight", "delta_cos", "delta_v", "literal_eq_3_1", "entry_policy", "neighbourhood",
            "neighbourhood_param", "errors", "error_values", "objective", "walk_speed", "quality_threshold")


def slo_live_changes(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """The engine keywords that take ``old`` to ``new`` without a rebuild, or None when
    anything else differs (beyond the view). ``errors`` stands for the set and its values."""
    if old.slo is None or new.slo is None:
        return None
    a, b = old.model_dump(), new.model_dump()
    for d in (a, b):
        d["view"] = None
        d["slo"] = {k: v for k, v in d["slo"].items() if k not in SLO_LIVE}
    if a != b:
        return None
    out: dict[str, Any] = {}
    for key in SLO_LIVE:
        if getattr(old.slo, key) != getattr(new.slo, key):
            if key in ("errors", "error_values"):
                out["errors"] = slo_errors_for(new.slo)
            elif key == "neighbourhood":
                out.update(neighbourhood=new.slo.neighbourhood, neighbourhood_param=new.slo.neighbourhood_param)
            else:
                out[key] = getattr(new.slo, key)
    return out


def build_slo_swarm(scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
                    first_run: int = 0) -> SLOSwarm:
    """Mai's SLO swarm of an ``[slo]`` section (``swarm = "slo"``)."""
    slo = scenario.slo
    if slo is None:
        raise ValueError("this scenario has no [slo] section")
    return SLOSwarm(
        runs=runs or scenario.sim.runs, seed=scenario.sim.seed if seed is None else seed, first_run=first_run,
        particles=scenario.sim.robots, objective=slo.objective, motion=slo.motion, walk_speed=slo.walk_speed,
        quality_threshold=slo.quality_threshold, radial=slo.radial, **slo_localiser_for(slo),
    )


class Builder(Protocol):
    def __call__(self, scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
                 first_run: int = 0) -> Engine: ...


# ---------------------------------------------------------------- a running engine, retuned
def swarm_keywords(s: Scenario) -> dict[str, Any]:
    """The ``Simulation.retune`` keywords of a scenario's controller, swarm size, bests and objective."""
    c = s.controller
    return dict(policy=policy_for(c), law=law_for(c), dt=float(c.dt), robots=s.sim.robots,
                attractors=s.bests.attractors, pbest_order=s.bests.pbest_order,
                objective=objective_for(s.objective, s.sim.d))


def fleet_keywords(s: Scenario) -> dict[str, Any]:
    """The ``Fleet.retune`` keywords of a scenario (its :class:`FleetParams` in ``Fleet.LIVE``)."""
    params = fleet_params_for(s)
    return {k: getattr(params, k) for k in Fleet.LIVE - {"slo"}}


def sonar_keywords(s: Scenario) -> dict[str, Any]:
    """The ``AcousticSwarm.retune`` keywords of a scenario (its :class:`SonarParams` in ``LIVE``)."""
    assert s.acoustics is not None
    params = sonar_params_for(s.acoustics)
    return {k: getattr(params, k) for k in AcousticSwarm.LIVE - {"slo"}}


def _same_but(old: Scenario, new: Scenario, *paths: str) -> bool:
    """Do ``old`` and ``new`` agree on everything but ``paths`` (sections or dotted fields), the
    view, the name, the description and the horizon?"""
    dumps = []
    for sc in (old, new):
        d = sc.model_dump()
        for path in (*paths, "view", "name", "description", "sim.steps"):
            section, _, name = path.partition(".")
            if name and isinstance(d.get(section), dict):
                d[section].pop(name, None)
            elif not name:
                d.pop(section, None)
        dumps.append(d)
    return dumps[0] == dumps[1]


def _fixed_same(a: object, b: object, live: frozenset[str]) -> bool:
    return all(getattr(a, f.name) == getattr(b, f.name) for f in dataclasses.fields(a) if f.name not in live)  # type: ignore[arg-type]


def swarm_live(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """``retune`` keywords taking a running Chapter 3 swarm from ``old`` to ``new``, or None when
    something else changed (the start, the dimension, the positions: a new swarm is needed)."""
    if not _same_but(old, new, "controller", "bests", "objective", "sim.robots"):
        return None
    return swarm_keywords(new)


def fleet_live(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """``retune`` keywords taking a running fleet from ``old`` to ``new`` (None: it needs a new one)."""
    if not _same_but(old, new, "controller", "robot", "sensing", "init", "objective", "bests") or \
            not _fixed_same(fleet_params_for(old), fleet_params_for(new), Fleet.LIVE):
        return None
    return fleet_keywords(new)


def sonar_live(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """``retune`` keywords taking a running acoustic swarm from ``old`` to ``new`` (None: a new one)."""
    if old.acoustics is None or new.acoustics is None or \
            not _same_but(old, new, "acoustics", "controller", "robot", "sensing", "init", "objective", "bests") or \
            not _fixed_same(sonar_params_for(old.acoustics), sonar_params_for(new.acoustics), AcousticSwarm.LIVE):
        return None
    return sonar_keywords(new)


def kind_of(scenario: Scenario) -> str:
    """The scene kind a scenario describes (the name of its :class:`~.kinds.SceneKind`): Mai's SLO
    swarm (``[slo] swarm = "slo"``), an acoustic swarm (``[acoustics]``, Ch. 7–8), a fleet in a
    world (``[world]``, Ch. 4–5), a plug-in kind (its own section) or the free-space swarm (Ch. 3);
    the fleet, the acoustic and the free-space swarm on SLO or true positions as ``[slo]`` says."""
    from .kinds import kind_for  # (the kinds' registry holds this module's build functions)

    return kind_for(scenario).name


def build(scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Engine:
    """The engine of whatever the scenario describes (:func:`kind_of`), for runs ``first_run …
    first_run + runs − 1`` of the seed (default: the preset's)."""
    from .kinds import kind_for

    return kind_for(scenario).build(scenario, runs=runs, seed=seed, first_run=first_run)


def build_slo(scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Engine:
    """An ``[slo]`` scene: Mai's SLO swarm, or the scene's own swarm (``swarm = "host"``) on
    SLO-estimated (or, with ``positions = "oracle"``, true) positions with the same seed."""
    if scenario.slo is None:
        raise ValueError("this scenario has no [slo] section")
    return build(scenario, runs=runs, seed=seed, first_run=first_run)
