"""One registry per kind of variant (velocity laws, robot laws, acoustic strategies, SLO
selections): the engine dispatches on it and the preset models take their choices and rules
from it, so the layers cannot disagree about what a variant is."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.acoustics.strategies import STRATEGIES, make_strategy
from shoal.engine.kinds.fleet import Fleet, FleetParams
from shoal.engine.kinds.sonar import AcousticSwarm, SonarParams
from shoal.engine.pso.laws import LAWS, Law
from shoal.engine.robots.laws import ROBOT_LAWS
from shoal.engine.robots.world import empty_arena
from shoal.engine.slo.beliefs import LocaliserParams
from shoal.engine.slo.selection import SELECTIONS
from shoal.presets.io import PresetError, load

REGISTRIES = (LAWS, ROBOT_LAWS, STRATEGIES, SELECTIONS)


@pytest.mark.parametrize("registry", REGISTRIES, ids=lambda r: r.what)
def test_every_entry_has_a_unique_name_and_label(registry):
    assert all(name == entry.name for name, entry in registry.items())
    labels = registry.labels()
    assert len(labels) == len(registry) and set(labels.values()) == set(registry)
    with pytest.raises(ValueError, match=rf"^{registry.what}: unknown 'nope', choose from"):
        registry.pick("nope")


def test_the_engine_refuses_a_name_no_registry_holds():
    with pytest.raises(ValueError, match="^law: unknown 'adapted-sin'"):
        Law("adapted-sin")
    with pytest.raises(ValueError, match="^law: unknown 'rpso2'"):
        FleetParams(law="rpso2")
    with pytest.raises(ValueError, match="^strategy: unknown 'c-pso'"):
        make_strategy("c-pso")
    with pytest.raises(ValueError, match="^selection: unknown 'nearest'"):
        LocaliserParams(selection="nearest")
    assert LocaliserParams(selection="perfect").selection == "perfect"  # the oracle baseline


def test_the_presets_offer_exactly_the_registered_variants():
    for law in LAWS:
        assert load("default", [f"controller.law={law}", "controller.mode=raw"]).controller.law == law
    for law in ROBOT_LAWS:
        sets = [f"controller.law={law}", "controller.mode=raw", "robot.drive=differential"]
        assert load("course-dvc", sets).controller.law == law
    with pytest.raises(PresetError, match="controller.law"):
        load("default", ["controller.law=adapted-sin"])
    for name in STRATEGIES:
        assert load("sonar-xb-pso", [f"acoustics.algorithm={name}"]).acoustics.algorithm == name
    for name in SELECTIONS:
        assert load("slo-walk", [f"slo.selection={name}"]).slo.selection == name
    with pytest.raises(PresetError, match="slo.selection"):
        load("slo-walk", ["slo.selection=perfect"])  # an engine baseline, not a preset choice


def test_dvc_belongs_to_the_laws_with_a_dvc_form():
    with_dvc = [name for name, law in ROBOT_LAWS.items() if law.dvc is not None]
    assert with_dvc == ["adapted-rpso", "nonomni"]
    for name, law in ROBOT_LAWS.items():
        sets = [f"controller.law={name}", "controller.mode=dvc"]
        if law.body_frame:
            sets.append("robot.drive=differential")
        if law.dvc is None:
            with pytest.raises(PresetError, match="mode 'dvc' needs law 'adapted-rpso' or 'nonomni'"):
                load("course-dvc", sets)
            with pytest.raises(ValueError, match=f"^dvc: law '{name}' has no DVC form"):
                FleetParams(law=name, dvc=True)
        else:
            assert load("course-dvc", sets).controller.mode == "dvc"


def test_body_frame_laws_need_a_differential_drive():
    for name, law in ROBOT_LAWS.items():
        sets = [f"controller.law={name}", "controller.mode=raw", "robot.drive=holonomic"]
        if law.body_frame:
            with pytest.raises(PresetError, match="needs robot.drive = 'differential'"):
                load("course-dvc", sets)
        else:
            load("course-dvc", sets)


@pytest.mark.parametrize("name", list(STRATEGIES))
def test_minimum_robots_come_from_the_strategy(name):
    need = STRATEGIES[name].min_robots
    assert load("sonar-xb-pso", [f"acoustics.algorithm={name}", f"sim.robots={need}"]).sim.robots == need
    AcousticSwarm(SonarParams(algorithm=name, mode="surrogate"), robots=need)
    if need > 1:
        with pytest.raises(PresetError, match=f"needs at least {need}"):
            load("sonar-xb-pso", [f"acoustics.algorithm={name}", f"sim.robots={need - 1}"])
        with pytest.raises(ValueError, match=f"^{name} needs at least {need} robots"):
            AcousticSwarm(SonarParams(algorithm=name, mode="surrogate"), robots=need - 1)


def test_the_fleet_draws_and_weighs_as_its_law_says():
    for name, law in ROBOT_LAWS.items():
        drive = "differential" if law.body_frame else "holonomic"
        params = FleetParams(law=name, dvc=False, drive=drive, c=(0.1, 0.2, 0.3))
        assert params.body_frame == law.body_frame
        fleet = Fleet(world=empty_arena(), robots=3, runs=2, params=params)
        r = fleet._draws()
        assert r.shape == (law.terms, 2, 3) + ((2,) if law.draws == "component" else ())
        _, c = fleet._coefficients(np.full((2, 3, 6), 3.0))  # six open sectors
        assert c.shape == (law.terms, 2, 3) and np.all(c[:, 0, 0] == (0.1, 0.2, 0.3, 0.0, 0.0)[: law.terms])
