"""The obstacle world of a ``[world]`` section (Chapters 4–5), refused by field when it cannot
be laid out."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from shoal.engine.robots.world import WorldSpec, empty_arena, forest, obstacle_course

from ..errors import PresetError
from ..models import Scenario, WorldModel


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
