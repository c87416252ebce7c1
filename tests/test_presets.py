"""Preset models, files and ``--set`` overrides."""

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shoal.presets.io import (
    PresetError,
    apply_overrides,
    list_presets,
    load,
    parse_text,
    parse_value,
    read_raw,
    to_json,
    to_toml,
    validate,
)
from shoal.presets.models import Scenario


def test_every_shipped_preset_validates_and_round_trips():
    names = list_presets()
    assert {"default", "fig3-4a", "fig3-5c", "standard-pso"} <= set(names)
    for name in names:
        s = load(name)
        assert validate(parse_text(to_toml(s))) == s
        assert validate(parse_text(to_json(s), "json")) == s


def _messages(data):
    with pytest.raises(PresetError) as e:
        validate(data)
    return e.value.messages


@pytest.mark.parametrize(
    "patch, field",
    [
        ({"controller": {"omega": 1.7}}, "controller.omega"),
        ({"sim": {"robots": 0}}, "sim.robots"),
        ({"sim": {"robots": "many"}}, "sim.robots"),
        ({"controller": {"law": "pso"}}, "controller.law"),
        ({"objective": {"kind": "moon"}}, "objective.kind"),
        ({"controller": {"omeg": 0.5}}, "controller.omeg"),
        ({"controller": {"schedule": [{"t_start": 5, "U": -1, "A_plus": 1}]}}, "controller.schedule.0.U"),
    ],
)
def test_bad_fields_are_named(patch, field):
    msgs = _messages(patch)
    assert any(m.startswith(field + ":") for m in msgs), msgs


def test_inconsistent_controller_says_why():
    msgs = _messages({"controller": {"mode": "physical", "dt": 1.0, "U": 2.0, "A_plus": 5.0}})
    assert any("controller" in m and "A_plus" in m and "faster" in m for m in msgs)
    msgs = _messages({"controller": {"mode": "raw", "law": "adapted-sgn", "omega": 1.0}})
    assert any("omega" in m and "[3.14]" in m for m in msgs)
    # standard PSO may use ω ≥ 1 (to show divergence) in raw mode
    assert validate({"controller": {"mode": "raw", "law": "standard", "omega": 1.1}}).controller.omega == 1.1


def test_syntax_errors_are_reported():
    with pytest.raises(PresetError, match="TOML syntax"):
        parse_text("[sim\nrobots = 3")
    with pytest.raises(PresetError, match="JSON syntax"):
        parse_text('{"sim": {"robots": 3},}', "json")


def test_unknown_preset_lists_the_shipped_ones():
    with pytest.raises(PresetError, match="default"):
        read_raw("no-such-preset")


def test_overrides_are_typed_and_validated():
    s = load("default", ["controller.U=4", "controller.law=adapted-tanh", "objective.source=[1.5, 2]", "sim.seed=9"])
    assert s.controller.U == 4.0 and s.controller.law == "adapted-tanh"
    assert s.objective.source == (1.5, 2.0) and s.sim.seed == 9
    with pytest.raises(PresetError, match="controller.omega"):
        load("default", ["controller.omega=abc"])
    with pytest.raises(PresetError, match="sim.nope"):
        load("default", ["sim.nope=1"])
    with pytest.raises(PresetError, match="sim.robots"):
        load("default", ["sim.robots.x=1"])
    with pytest.raises(PresetError, match="dotted.key=value"):
        load("default", ["controller.omega"])


def test_overrides_reach_schedule_items():
    s = load("fig3-5a", ["controller.schedule.0.U=5"])
    assert s.controller.schedule[0].U == 5.0
    with pytest.raises(PresetError, match="no such list item"):
        load("fig3-5a", ["controller.schedule.7.U=5"])


def test_overrides_do_not_touch_the_input():
    raw = read_raw("default")
    before = json.dumps(raw, sort_keys=True)
    apply_overrides(raw, ["controller.U=5"])
    assert json.dumps(raw, sort_keys=True) == before


@given(st.text(max_size=30))
def test_parse_value_never_crashes(text):
    parse_value(text)


@given(key=st.text(min_size=0, max_size=20), value=st.text(max_size=10))
def test_any_override_is_accepted_or_refused_with_a_message(key, value):
    try:
        load("default", [f"{key}={value}"])
    except PresetError as e:
        assert e.messages and all(m.strip() for m in e.messages)


def test_schema_is_exportable():
    schema = Scenario.model_json_schema()
    assert "controller" in schema["properties"]
