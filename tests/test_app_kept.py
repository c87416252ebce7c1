"""What a user builds by hand is kept: obstacles added, removed and moved in a fleet's world and
a source dragged in an acoustic scene go into the downloaded preset (``world.obstacles``,
``acoustics.source``), and loading that preset brings them back; bad values are refused by name."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.kinds import fleet, sonar
from shoal.app.kinds.registry import session_for
from shoal.presets import io as presets_io
from shoal.presets.build import world_for
from shoal.presets.io import PresetError

APP_PRESET = "course-dvc"  # the shared ``server`` fixture (conftest.py) shows this scene (the ``tab`` test)


def reloaded(s):
    """A new session of the preset ``s`` downloads (its TOML text, parsed and validated again)."""
    text = s.preset_toml().decode()
    return session_for(presets_io.validate(presets_io.parse_text(text))), text


def test_fleet_edits_survive_download_and_load():
    s = session_for(presets_io.load("course-dvc"))
    d = fleet.driver(s)
    s.step(2)
    generated = s.sim.world.circles.copy()
    x1 = s.sim.world.bounds[2] - 4.0
    d.add_obstacle(x1, 1.5, 1.25)
    d.remove_obstacle_near(*generated[3, :2], tol=0.0)
    d.move_obstacle(0, generated[0, 0] + 0.37, generated[0, 1] - 0.21)
    edited = s.sim.world.circles.copy()
    assert len(edited) == len(generated) and not np.array_equal(edited, generated)

    t, text = reloaded(s)
    assert "obstacles" in text
    np.testing.assert_array_equal(t.sim.world.circles, edited)  # exactly: floats round-trip through TOML
    assert t.scenario.world.obstacles is not None
    fleet.driver(t).restore_world()  # "restore" goes back to the world the preset describes: the edited one
    np.testing.assert_array_equal(t.sim.world.circles, edited)
    t.step(3)  # and it runs
    assert t.sim.state.k == 3


def test_a_new_world_setting_in_the_app_generates_the_world_afresh():
    s = session_for(presets_io.load("course-dvc", ["world.obstacles=[[10.0, 0.0, 1.0]]"]))
    assert len(s.sim.world.circles) == 1
    s.apply({"world.layers": 3})
    assert s.scenario.world.obstacles is None
    np.testing.assert_array_equal(s.sim.world.circles, world_for(s.scenario.world).circles)
    assert len(s.sim.world.circles) > 1


def test_a_preset_without_edits_downloads_as_before():
    s = session_for(presets_io.load("course-dvc"))
    assert s.preset_toml().decode() == presets_io.to_toml(s.scenario)
    assert "obstacles" not in s.preset_toml().decode()
    a = session_for(presets_io.load("sonar-xb-pso"))
    assert "source" not in presets_io.parse_text(a.preset_toml().decode())["acoustics"]


def test_restore_drops_the_edits_from_the_download():
    s = session_for(presets_io.load("course-dvc"))
    d = fleet.driver(s)
    d.add_obstacle(s.sim.world.bounds[2] - 4.0, 1.5, 1.0)
    d.restore_world()
    assert "obstacles" not in s.preset_toml().decode()


def test_dragged_source_survives_download_and_load():
    s = session_for(presets_io.load("sonar-xb-pso"))
    s.step(2)
    sonar.driver(s).move_source(12.5, -30.25)
    t, text = reloaded(s)
    assert t.scenario.acoustics.source == (12.5, -30.25)
    np.testing.assert_array_equal(t.sim.state.source[0], [12.5, -30.25])
    assert "source starts at (12.5, -30.2) m (acoustics.source)" in sonar._readout(t)
    # the swarm itself starts as the preset's did: only the source moved
    fresh = session_for(presets_io.load("sonar-xb-pso"))
    np.testing.assert_array_equal(t.sim.state.x, fresh.sim.state.x)


def test_a_moving_source_dragged_keeps_its_path():
    sc = presets_io.validate(presets_io.apply_overrides(presets_io.read_raw("sonar-xb-pso"), ["acoustics.v_n=0.5"]))
    s = session_for(sc)
    s.step(4)
    sonar.driver(s).move_source(10.0, 20.0)
    s.step(3)
    t, _ = reloaded(s)
    t.step(7)
    np.testing.assert_allclose(t.sim.state.source[0], s.sim.state.source[0], atol=1e-9)


BASE = "course-dvc"


def refused(*overrides: str) -> str:
    with pytest.raises(PresetError) as err:
        presets_io.load(BASE if overrides[0].startswith("world") else "sonar-xb-pso", list(overrides))
    return str(err.value)


@pytest.mark.parametrize("override, field", [
    ("world.obstacles=[[10.0, 0.0, -1.0]]", "world.obstacles.0.2"),
    ("world.obstacles=[[10.0, nan, 1.0]]", "world.obstacles.0.1"),
    ("world.obstacles=[[10.0, inf, 1.0]]", "world.obstacles.0.1"),
    ("world.obstacles=[[10.0, 1.0]]", "world.obstacles.0.2"),
    ("world.obstacles=[[1e300, 0.0, 1.0]]", "world.obstacles.0.0"),
    ("acoustics.source=[nan, 1.0]", "acoustics.source.0"),
    ("acoustics.source=[1.0, 1e9]", "acoustics.source.1"),
    ("acoustics.source=[1.0]", "acoustics.source.1"),
])
def test_bad_values_are_refused_naming_the_field(override, field):
    assert refused(override).startswith(field + ":")


def test_a_million_obstacles_are_refused_naming_the_field():
    data = presets_io.read_raw(BASE)
    data["world"]["obstacles"] = [[10.0, 0.0, 1.0]] * 10**6
    with pytest.raises(PresetError) as err:
        presets_io.validate(data)
    assert str(err.value).startswith("world.obstacles:") and "2000" in str(err.value)


def test_an_obstacle_outside_the_world_is_refused_naming_it():
    sc = presets_io.load(BASE, ["world.obstacles=[[10.0, 0.0, 1.0], [5000.0, 0.0, 1.0]]"])
    with pytest.raises(PresetError, match=r"^world\.obstacles\.1: .*outside the world"):
        world_for(sc.world)
    with pytest.raises(PresetError, match=r"world\.obstacles\.1"):
        session_for(sc)


def test_an_obstacle_on_the_start_box_is_refused_naming_it():
    sc = presets_io.load(BASE, ["world.obstacles=[[30.0, 0.0, 1.0], [3.0, 0.0, 5.0]]"])
    with pytest.raises(PresetError, match=r"^world\.obstacles\.1: .*start box"):
        world_for(sc.world)


def test_an_edit_a_preset_cannot_hold_is_refused_at_download_naming_it():
    """An obstacle dropped in the start box (allowed while the robots run) cannot be kept: robots
    start there. The download says which obstacle, and the session is untouched."""
    s = session_for(presets_io.load(BASE))
    sx0, sy0, sx1, sy1 = s.sim.world.start_box
    s.sim.state.x[0] += (sx1 - sx0) + 3.0  # the robots have left the start box
    fleet.driver(s).add_obstacle((sx0 + sx1) / 2, (sy0 + sy1) / 2, 0.5)
    n = len(s.sim.world.circles)
    with pytest.raises(PresetError, match=rf"world\.obstacles\.{n - 1}: .*start box"):
        s.preset_toml()
    assert len(s.sim.world.circles) == n and s.scenario.world.obstacles is None


def test_an_empty_list_means_no_obstacles_and_unset_means_generated():
    empty = presets_io.load(BASE, ["world.obstacles=[]"])
    assert len(world_for(empty.world).circles) == 0
    assert len(world_for(presets_io.load(BASE).world).circles) > 0


def test_the_download_button_writes_the_edits_or_says_why_not(tab):
    s = tab.session
    d = fleet.driver(s)
    d.add_obstacle(s.sim.world.bounds[2] - 4.0, 1.5, 1.0)
    tab.panels.download.value = True  # fires on_click
    name, content = tab.downloads[-1]
    again = presets_io.validate(presets_io.parse_text(content.decode()))
    np.testing.assert_array_equal(np.asarray(again.world.obstacles), s.sim.world.circles)
    sx0, sy0, sx1, sy1 = s.sim.world.start_box
    s.sim.state.x[0] += (sx1 - sx0) + 3.0
    d.add_obstacle((sx0 + sx1) / 2, (sy0 + sy1) / 2, 0.5)
    before = len(tab.downloads)
    tab.panels.download.value = True
    assert len(tab.downloads) == before  # nothing half-written
    title, body, colour = tab.messages[-1][:3]
    assert title == "Refused: download preset" and "start box" in body and colour == "red"
