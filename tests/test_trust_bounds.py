"""Every shipped preset with any numeric field at or near the edge of its range, headless.

Hypothesis picks a shipped preset (all of them, not one per kind as in
``test_trust_extremes.py``), one bounded numeric field of the preset model that applies to
it, an end of the field's range and a value at that end, one step inside it or a thousandth
of the range inside it. The scene is built as ``shoal run`` builds it and runs a few steps:
either it is refused with a :class:`PresetError` that names the field (or its section, for a
rule across fields), or the robots' positions and velocities stay finite and so does every
metric that is finite in the preset as shipped (the SLO's error statistics are NaN by design
while no neighbour is in range, and its round-trip error [3.8] with fewer than three robots).

The top ends of the sizes (``sim.robots``, ``sim.runs``, ``sim.steps``) are a matter of memory
and time, not of numbers (100 000 robots of an acoustic swarm need 149 GiB of pairwise
arrays; ``shoal run`` says it has not the memory), so they are taken at their bottom ends.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_trust_extremes import BOUNDS

from shoal.engine.core.recorder import metric_table
from shoal.presets.build import build
from shoal.presets.io import PresetError, list_presets, read_raw, set_dotted, validate
from shoal.presets.kinds import sections

PRESETS = sorted(list_presets())
SIZES = {"sim.robots", "sim.runs", "sim.steps"}
OPTIONAL = set(sections())  # the sections that ask for a scene kind (the kinds' registry)
STEPS = 3


def fields_of(preset: str) -> list[str]:
    """The bounded fields that apply to ``preset`` (list items: the preset's first)."""
    raw = read_raw(preset)
    out = []
    for path in sorted(BOUNDS):
        section = path.split(".")[0]
        if section in OPTIONAL and section not in raw:
            continue
        if path.startswith("controller.schedule."):
            if not raw.get("controller", {}).get("schedule"):
                continue
            path = path.replace("schedule.", "schedule.0.")
        out.append(path)
    return out


def _bounds(path: str) -> tuple[float, float]:
    ends = BOUNDS[path.replace("schedule.0.", "schedule.")]
    return min(ends), max(ends)


@st.composite
def edge_case(draw: st.DrawFn) -> tuple[str, str, Any]:
    preset = draw(st.sampled_from(PRESETS))
    path = draw(st.sampled_from(fields_of(preset)))
    lo, hi = _bounds(path)
    top = path not in SIZES and draw(st.booleans())
    end, inward = (hi, -1) if top else (lo, 1)
    how = draw(st.sampled_from(["at", "next", "near"]))
    if isinstance(lo, int) and isinstance(hi, int):
        value = end + inward * {"at": 0, "next": 1, "near": max(1, (hi - lo) // 1000)}[how]
    else:
        value = {"at": end, "next": math.nextafter(end, end + inward), "near": end + inward * 1e-3 * (hi - lo)}[how]
    return preset, path, value


def _outputs(sim: Any, info: Any) -> dict[str, np.ndarray]:
    out = {"x": np.asarray(sim.state.x, float), "u": np.asarray(sim.state.u, float)}
    out.update({f"metric {k}": np.asarray(v, float) for k, v in metric_table(sim.state, info, sim.t).items()})
    return out


def _run(scenario: Any) -> dict[str, np.ndarray]:
    sim = build(scenario)
    info = None
    for _ in range(STEPS):
        info = sim.step()
    return _outputs(sim, info)


@functools.lru_cache(maxsize=None)
def finite_as_shipped(preset: str) -> frozenset[str]:
    """The outputs that are finite after a few steps of ``preset`` as shipped."""
    return frozenset(k for k, v in _run(validate(read_raw(preset))).items() if np.isfinite(v).all())


def named(err: PresetError, path: str) -> bool:
    parts = path.split(".")
    heads = {path, parts[0], parts[-1], ".".join(parts[:2])}
    return any(h in m for m in err.messages for h in heads)


@settings(max_examples=200, suppress_health_check=[HealthCheck.too_slow])
@given(edge_case())
def test_any_preset_at_the_edge_of_any_field_runs_finite_or_is_refused_by_name(case):
    preset, path, value = case
    data = read_raw(preset)
    set_dotted(data, path, value)
    try:
        outputs = _run(validate(data))
    except PresetError as err:
        assert named(err, path), (preset, path, value, err.messages)
        return
    by_design = {"metric round_trip"} if path == "sim.robots" and value < 3 else set()  # no triangle to close
    bad = [k for k in finite_as_shipped(preset) - by_design if not np.isfinite(outputs[k]).all()]
    assert not bad, f"{preset} with {path} = {value!r}: {bad} not finite"


def test_every_preset_and_field_is_drawn_from():
    """The strategy reaches all 27 presets and every kind of section (a guard on the lists above)."""
    assert len(PRESETS) >= 27
    drawn = {p.split(".")[0] for preset in PRESETS for p in fields_of(preset)}
    assert {"sim", "controller", "objective", "world", "acoustics", "slo", "robot", "sensing"} <= drawn


def test_a_world_the_generator_cannot_lay_out_is_refused_by_field():
    """(found by the property above) The model allows a course as narrow as its start square."""
    data = read_raw("course-dvc")
    set_dotted(data, "world.width", 5.5)
    try:
        build(validate(data))
    except PresetError as err:
        assert err.messages == ["world.width: must exceed start_size"]
    else:
        raise AssertionError("a 5.5 m wide course was built")


def test_a_tiny_objective_scale_is_refused_by_the_model():
    """(found by the property above) 5e-324 m per unit made Rastrigin's landscape overflow (NaN)."""
    data = read_raw("rastrigin")
    set_dotted(data, "objective.scale", 1e-300)
    try:
        validate(data)
    except PresetError as err:
        assert err.messages[0].startswith("objective.scale: Input should be greater than or equal to 0.000001")
    else:
        raise AssertionError("objective.scale = 1e-300 was accepted")


def test_a_sweep_cell_whose_world_cannot_be_laid_out_is_refused_before_anything_runs(tmp_path):
    from shoal.studies.sweep import SweepError, run_sweep

    try:
        run_sweep("course-dvc", ["world.width=5.5,30"], tmp_path / "s", runs=1, steps=2, progress=False)
    except SweepError as err:
        assert any("world.width=5.5" in m and "world.width: must exceed start_size" in m for m in err.messages)
    else:
        raise AssertionError("a sweep with a 5.5 m wide course ran")
    assert not (tmp_path / "s").exists()
