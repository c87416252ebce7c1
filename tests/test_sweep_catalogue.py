"""What the Experiment tab offers to vary and to measure, for every shipped preset: fields the
scene's kind reads, with the model's ranges and only the choices the model accepts there;
outcomes that are exactly the columns a sweep records, each labelled."""

from __future__ import annotations

import copy
import math

import pytest

from shoal.presets.build import kind_of
from shoal.presets.io import PresetError, list_presets, load, set_dotted, validate
from shoal.studies.sweep import catalogue
from shoal.studies.sweep.outcomes import CellJob, simulate_cell

PRESETS = list(list_presets())
NEVER = ("name", "description", "schema_version", "sim.seed", "sim.runs", "world.seed", "slo.swarm")
NEVER_SECTIONS = ("view.", "arena.")


def _with(scenario, key, value):
    data = copy.deepcopy(scenario.model_dump(mode="json"))
    set_dotted(data, key, value)
    return validate(data)


@pytest.mark.parametrize("preset", PRESETS)
def test_every_offered_field_is_read_by_the_kind_and_ranged_by_the_model(preset):
    sc = load(preset)
    fields = catalogue.fields(sc)
    keys = [f.key for f in fields]
    assert len(keys) == len(set(keys)) and {"sim.robots", "sim.steps"} <= set(keys)
    assert len(keys) >= 4  # its own section's fields besides (a small plug-in kind has a handful)
    assert not set(keys) & set(NEVER) and not any(k.startswith(NEVER_SECTIONS) for k in keys)
    reads = catalogue.reads(sc)
    for f in fields:
        section, name = f.key.split(".")[:2]
        assert section in reads and (reads[section] is None or name in reads[section]), f.key
        if f.numeric:  # the model's own bounds: just outside is refused, the ends as the model says
            for end, is_open, step in ((f.lo, f.lo_open, -1), (f.hi, f.hi_open, 1)):
                if not math.isfinite(end):
                    continue
                assert f.problem(end + step * max(1.0, abs(end))) is not None
                assert (f.problem(end) is not None) == is_open, (f.key, end)
        else:  # every choice offered is one the model accepts in this scene
            assert len(f.choices) >= 2
            for c in f.choices:
                assert f.problem(c) is None
                _with(sc, f.key, c)


@pytest.mark.parametrize("preset", PRESETS)
def test_choices_the_model_refuses_in_this_scene_are_not_offered(preset):
    sc = load(preset)
    for f in catalogue.fields(sc):
        if f.numeric:
            continue
        for option in _all_options(f.key):
            if option in f.choices:
                continue
            with pytest.raises(PresetError):
                _with(sc, f.key, option)


def _all_options(key):
    import typing

    from shoal.presets.models import Scenario

    model = Scenario
    *path, name = key.split(".")
    for part in path:
        ann = model.model_fields[part].annotation
        model = next(a for a in (typing.get_args(ann) or (ann,)) if isinstance(a, type))
    ann = model.model_fields[name].annotation
    return (False, True) if ann is bool else typing.get_args(ann)


def test_controller_fields_follow_the_mode_and_kinds_do_not_mix():
    physical, raw = load("default"), load("standard-pso")
    assert {"controller.U", "controller.A_plus"} <= {f.key for f in catalogue.fields(physical)}
    assert not {"controller.omega", "controller.c1"} & {f.key for f in catalogue.fields(physical)}
    assert {"controller.omega", "controller.c1", "controller.c2"} <= {f.key for f in catalogue.fields(raw)}
    sonar = {f.key for f in catalogue.fields(load("sonar-xb-pso"))}
    assert "acoustics.Q" in sonar and not any(k.startswith(("controller.", "robot.", "world.")) for k in sonar)
    fleet = {f.key for f in catalogue.fields(load("course-dvc"))}
    assert {"controller.beta", "robot.motion", "world.layers"} <= fleet and "controller.U" not in fleet
    host = [f.key for f in catalogue.fields(load("sonar-xb-pso-slo"))]
    assert host[0] == "slo.positions" and "slo.walk_speed" not in host  # an SLO-swarm-only field


def test_field_ranges_and_suggestions():
    U = next(f for f in catalogue.fields(load("default")) if f.key == "controller.U")
    assert (U.lo, U.lo_open, U.hi, U.hi_open) == (0.0, True, 1000.0, False) and U.range_text() == "0 < U ≤ 1000"
    assert U.suggest() == (3.0, 5.25, 7.5, 9.75, 12.0)  # half to twice the preset's 6
    assert "outside" in U.problem(0.0) and "not a number" in U.problem("fast") and U.problem(True)
    alpha = next(f for f in catalogue.fields(load("course-dvc")) if f.key == "controller.alpha")
    assert alpha.hi_open and max(alpha.suggest()) < 1.0
    robots = next(f for f in catalogue.fields(load("default")) if f.key == "sim.robots")
    assert robots.kind == "integer" and all(isinstance(v, int) for v in robots.suggest())
    assert "whole number" in robots.problem(2.5)


@pytest.mark.parametrize("preset", PRESETS)
def test_outcomes_are_the_recorded_columns_each_labelled(preset):
    sc = load(preset)
    offered = catalogue.outcomes(sc)
    recorded = list(simulate_cell(CellJob(0, sc.model_dump_json(), 0, 1, 2), 0, 1).columns)
    names = [o.name for o in offered]
    assert names == [n for n in recorded if n in names]  # the sweep's columns, in its order
    hidden = set(recorded) - set(names)
    assert hidden <= catalogue.hidden() | {n for n in recorded if n.endswith(catalogue.HIDDEN_SUFFIXES)}
    labels = catalogue.labels()
    assert all(o.name in labels for o in offered), [o.name for o in offered if o.name not in labels]
    titles = [o.title for o in offered]
    assert len(titles) == len(set(titles))
    first = catalogue.first_outcome(offered).name
    assert first == {"sonar": "com_dist", "fleet": "com_fitness", "slo_swarm": "e_abs_mean"}.get(kind_of(sc),
                                                                                                 "best_fitness")


@pytest.mark.parametrize("preset, key, title", [
    ("default", "controller.U", "top speed U [m/s]"),  # "(physical mode)" left out
    ("default", "controller.dt", "controller period Δt [s]"),
    ("default", "controller.c1_share", "c1/(c1+c2) split of ĉ"),  # a formula's bracket stays
    ("course-dvc", "controller.alpha", "DVC safety factor α [4.14]"),  # an equation number is no unit
    ("course-dvc", "controller.r_min", "minimum turning radius [m]"),
    ("sonar-xb-pso", "acoustics.snr0_db", "SNR at the origin [dB]"),  # what follows a ';' left out
    ("sonar-xb-pso", "acoustics.a", "forgetting scale a [7.2]"),  # ... and after a ':' ending 3 words
    ("slo-walk", "slo.error_values.range_sigma_m", "range: stochastic multiplicative σ_m [4.2]"),
    ("default", "controller.law", "law"),
])
def test_a_field_is_titled_in_words_with_its_unit(preset, key, title):
    field = next(f for f in catalogue.fields(load(preset)) if f.key == key)
    assert field.title == title


def test_every_offered_field_has_a_short_title_with_the_unit_its_description_gives():
    for preset in ("default", "course-dvc", "sonar-xb-pso", "slo-walk", "escort-stationary"):
        for f in catalogue.fields(load(preset)):
            assert 0 < len(f.title) <= catalogue.TITLE_CHARS + 8 and " (" not in f.title  # no remark left
            if f.unit:
                assert f"[{f.unit}]" in f.title and not f.unit[0].isdigit()
