"""Presets at the edges of their ranges, in the browser app's sessions.

Every numeric field of the preset model has a range. For each shipped kind of scene, a sample
of fields (hypothesis) is set to its lowest or highest allowed value: the scene is either
refused with the field named, or it builds and runs a few steps with finite positions and
velocities and no exception. The app's own limits (``app/limits.py``) are among the refusals.
"""

from __future__ import annotations

import math
from typing import Any, get_origin

import annotated_types as at
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from shoal.app.kinds.registry import session_for
from shoal.app.limits import MAX_ROBOTS, check_app_limits, scene_kind
from shoal.presets.io import PresetError, list_presets, load, read_raw, set_dotted, validate
from shoal.presets.kinds import sections
from shoal.presets.models import Scenario
from shoal.testing import variant_presets

# One shipped preset for each kind of scene a tab tells apart (each robot cap of each registered
# kind: a fleet in physics, a swarm on SLO positions, …); the sampled cases draw from every preset.
KINDS = tuple(variant_presets())
STEPS = 3


def bounds(model: type[BaseModel], prefix: str = "") -> dict[str, tuple[float, ...]]:
    """Dotted path → the extreme values a numeric field allows (open bounds: the nearest value inside)."""
    out: dict[str, tuple[float, ...]] = {}
    for name, field in model.model_fields.items():
        if get_origin(field.annotation) is list:
            continue  # (list items, e.g. controller.schedule, have no dotted path of their own)
        args = getattr(field.annotation, "__args__", (field.annotation,))
        sub = next((a for a in args if isinstance(a, type) and issubclass(a, BaseModel)), None)
        if sub is not None:
            out.update(bounds(sub, f"{prefix}{name}."))
            continue
        num = next((a for a in args if a in (int, float)), None)
        if num is None:
            continue
        ends = []
        for m in field.metadata:
            if isinstance(m, at.Ge):
                ends.append(num(m.ge))
            elif isinstance(m, at.Le):
                ends.append(num(m.le))
            elif isinstance(m, at.Gt):
                ends.append(m.gt + 1 if num is int else math.nextafter(m.gt, math.inf))
            elif isinstance(m, at.Lt):
                ends.append(m.lt - 1 if num is int else math.nextafter(m.lt, -math.inf))
        if ends:
            out[f"{prefix}{name}"] = tuple(ends)
    return out


BOUNDS = bounds(Scenario)


def fields_of(preset: str) -> list[str]:
    """The bounded fields that apply to ``preset``: its own sections and the ones every scene has."""
    raw = read_raw(preset)
    optional = set(sections())  # the sections that ask for a scene kind (the kinds' registry)
    return sorted(p for p in BOUNDS if p.split(".")[0] not in optional or p.split(".")[0] in raw)


@st.composite
def extreme_case(draw: st.DrawFn) -> tuple[str, dict[str, Any]]:
    preset = draw(st.sampled_from(sorted(list_presets())))
    paths = draw(st.lists(st.sampled_from(fields_of(preset)), min_size=1, max_size=4, unique=True))
    changes = {p: draw(st.sampled_from(BOUNDS[p])) for p in paths}
    if "sim.robots" in changes and draw(st.booleans()):  # the app's own cap is an edge too
        changes["sim.robots"] = MAX_ROBOTS[scene_kind(load(preset))]
    return preset, changes


def named(err: PresetError, changes: dict[str, Any]) -> bool:
    """Does some message name a changed field (or its section, for a rule across fields)?"""
    heads = {p for p in changes} | {p.split(".")[0] for p in changes} | {p.split(".")[-1] for p in changes}
    return any(h in m for m in err.messages for h in heads)


def run_or_refuse(preset: str, changes: dict[str, Any]) -> str:
    data = read_raw(preset)
    for path, value in changes.items():
        set_dotted(data, path, value)
    try:
        session = session_for(validate(data))
    except PresetError as err:
        assert named(err, changes), (changes, err.messages)
        return "refused"
    session.play()
    session.step(STEPS)
    state = session.sim.state
    for name in ("x", "u"):
        value = np.asarray(getattr(state, name))
        assert np.isfinite(value).all(), f"{preset} {changes}: {name} is not finite"
    assert session.sim.state.k >= 1
    return "ran"


@settings(max_examples=30, suppress_health_check=[HealthCheck.too_slow])
@given(extreme_case())
def test_extreme_values_are_refused_by_name_or_run_finite(case):
    run_or_refuse(*case)


@pytest.mark.parametrize("preset", KINDS)
def test_every_kind_runs_with_its_smallest_values_or_names_them(preset):
    """All bounded fields of a kind at their lowest at once (a corner hypothesis rarely draws)."""
    changes = {p: min(BOUNDS[p]) for p in fields_of(preset)}
    run_or_refuse(preset, changes)


@pytest.mark.parametrize("preset", KINDS)
def test_the_models_largest_swarm_is_refused_by_the_app_by_name(preset):
    """``sim.robots`` at the model's top (100 000) would stall a shared server: refused, field named."""
    sc = load(preset, ["sim.robots=100000"])
    with pytest.raises(PresetError, match=r"^sim\.robots = 100000: the browser app runs at most"):
        check_app_limits(sc)
    with pytest.raises(PresetError, match="sim.robots"):
        session_for(sc)
