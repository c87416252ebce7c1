"""The browser app's Chapter 4–5 scenes without a browser: fleet session, panels, clicks, scene.

As in ``test_app_session.py``, GUI handles are driven by assigning ``.value`` (their
callbacks run in the test thread) on a real viser server; clicks are fed to the tab as
scene click events with a ray, as the browser sends them.
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

from shoal.app.kinds import fleet as fleet_kind
from shoal.app.kinds import swarm
from shoal.app.kinds.fleet import CONTROLLERS, EditRefused
from shoal.app.kinds.registry import app_presets
from shoal.app.session.session import Session
from shoal.engine.core.recorder import TRAJECTORY_COLUMNS
from shoal.engine.kinds.fleet import Fleet
from shoal.engine.robots.sensing import sense
from shoal.presets import io as presets_io

from app_helpers import HAND_TAB


@dataclass
class Click:
    """What viser's ``SceneClickEvent`` carries that the app reads."""

    ray_origin: tuple[float, float, float]
    ray_direction: tuple[float, float, float]
    modifier: str | None = None


APP_PRESET = "course-dvc"  # the shared ``server`` fixture (conftest.py) shows this scene


def _last(tab):
    assert tab.messages, "expected a notification"
    return tab.messages[-1]


def click_at(tab, x: float, y: float, modifier: str | None = None) -> None:
    """A slanted ray from above through world (x, y), as a browser click sends it."""
    sx, sy = tab.arena.to_scene(np.array([x, y]))
    origin = np.array([sx + 1.5, sy - 2.0, 60.0])
    d = np.array([sx, sy, 0.0]) - origin
    tab.scene_click(Click(tuple(origin), tuple(d / np.linalg.norm(d)), modifier))


def free_spot(session: Session, robot: int, distance: float) -> np.ndarray:
    """A point ``distance`` m from the robot's surface (centre to centre, one default obstacle's
    radius more) that is clear of every obstacle and robot."""
    fleet, obstacle_radius = session.sim, fleet_kind.driver(session).obstacle_radius
    x = fleet.state.x[0, robot]
    r = fleet.params.robot_radius + distance + obstacle_radius
    for a in np.linspace(0, 2 * math.pi, 72, endpoint=False):
        p = x + r * np.array([math.cos(a), math.sin(a)])
        clear_obstacles = fleet.world.obstacle_distance(*p).min(initial=np.inf) > obstacle_radius + 0.3
        others = np.hypot(*(fleet.state.x[0] - p).T) - fleet.params.robot_radius - obstacle_radius
        if clear_obstacles and others.min() > 0.3:
            return p
    raise AssertionError("no free spot near the robot")


# ---------------------------------------------------------------------------- loading and drawing
def test_course_preset_builds_a_fleet_and_draws_its_obstacles(tab):
    s = tab.session
    assert s.kind is fleet_kind.KIND and isinstance(s.sim, Fleet)
    assert isinstance(tab.panels, type(tab.panels)) and tab.arena.name == "fleet"
    assert "course-dvc" in app_presets() and "default" in app_presets()
    tab.tick(1.0)
    world = s.sim.world
    node = tab.arena.nodes["obstacles"]
    circles = world.circles
    assert len(circles) > 10
    np.testing.assert_allclose(np.asarray(node.batched_positions)[:, :2],
                               tab.arena.to_view(circles[:, :2])[:, :2], rtol=1e-6, atol=1e-5)
    np.testing.assert_allclose(node.batched_scales, circles[:, 2] * tab.arena.scale, rtol=1e-6)
    walls = np.asarray(tab.arena.nodes["walls"].points)
    assert walls.shape == (len(world.walls), 2, 3)
    robots = np.asarray(tab.arena.nodes["robots"].points)
    np.testing.assert_allclose(robots[:, :2], tab.arena.to_view(s.sim.state.x[0])[:, :2], atol=1e-5)
    layers = np.asarray(tab.arena.nodes["layers"].points)[:, :, 0]
    assert set(np.round(layers.ravel() / tab.arena.scale + tab.arena.centre[0], 3)) == set(
        np.round(world.layer_x, 3))  # dotted lines at the layer positions


def test_collided_robots_get_their_own_colour(tab):
    tab.panels.preset.value = "course-rpso"  # original RPSO loses robots quickly
    s = tab.session
    while s.sim.state.status[0].sum() == 0 and s.sim.state.k < 200:
        s.step(1)
    tab.tick(2.0)
    colors = np.asarray(tab.arena.nodes["robots"].colors)
    status = s.sim.state.status[0]
    assert status.any() and not status.all()
    assert {tuple(c) for c in colors[status == 1]} != {tuple(c) for c in colors[status == 0]}


def test_stalled_robots_are_ringed_counted_in_the_status_and_plotted(tab):
    from shoal.engine.kinds.fleet import STALL_STEPS

    s = tab.session
    s.step(2)
    with s.lock:
        s.sim.state.slow[0, :3] = STALL_STEPS  # three robots held still for a while
        s.sim.state.status[0, :3] = 0
    s.revision += 1
    tab.tick(3.0)
    rings = np.asarray(tab.arena.nodes["stalled"].points, dtype=float)[:, :, :2].reshape(-1, 2)
    centres = tab.arena.to_view(s.sim.state.x[0, :3])[:, :2]
    n = fleet_kind.STALLED_RING_SEGMENTS
    assert tab.arena.nodes["stalled"].visible and len(rings) == 3 * n * 2
    for c in centres:  # each ring goes round its robot
        near = rings[np.hypot(*(rings - c).T) < 2.0 * s.sim.params.robot_radius * tab.arena.scale]
        assert len(near) >= 2 * n
    assert "&nbsp;stalled" in tab.panels.view_gui.legend.content
    assert f"{int(s.sim.info().stalled[0])} stalled" in tab.panels.status.content
    s.sim.state.slow[0] = 0
    s.step(1)
    tab.panels.refresh_plots()
    m = s.metric_arrays()
    np.testing.assert_allclose(tab.panels.handles["robots"].data[3], m["stalled"])
    tab.tick(4.0)
    assert not tab.arena.nodes["stalled"].visible


# ---------------------------------------------------------------------------- panels → engine
def test_sliders_reach_the_fleet_params_without_restart(tab):
    s, p = tab.session, tab.panels
    s.step(4)
    fleet, x = s.sim, s.sim.state.x.copy()
    p.handles["controller.alpha"].value = 0.6
    p.handles["controller.beta"].value = 0.7
    p.handles["sensing.range"].value = 4.5
    p.handles["controller.guard"].value = True
    p.handles["controller.update"].value = "simultaneous"
    assert (fleet.params.alpha, fleet.params.beta, fleet.params.sensing_range) == (0.6, 0.7, 4.5)
    assert fleet.params.guard and fleet.params.update == "simultaneous"
    assert s.sim is fleet and fleet.state.k == 4 and np.array_equal(fleet.state.x, x)  # not restarted
    s.step(1)
    assert fleet.state.omega[0] == pytest.approx(np.full(s.sim.robots, 1 - 0.7))  # in force at the next step
    assert s.scenario.controller.alpha == 0.6 and s.scenario.sensing.range == 4.5  # export/download agree


def test_constant_controller_budget_and_ratio_sliders(tab):
    p, s = tab.panels, tab.session
    p.handles["controller"].value = "Adapted RPSO (constant)"
    assert (s.sim.params.law, s.sim.params.dvc) == ("adapted-rpso", False)
    p.handles["c_hat"].value = 1.8
    p.handles["ratio"].value = 2.0
    c1, c2, c3 = s.sim.params.c
    assert c1 + c2 + c3 == pytest.approx(1.8, rel=1e-4) and c3 / (c1 + c2) == pytest.approx(2.0, rel=1e-4)
    assert c1 == pytest.approx(c2)
    assert p.handles["ratio"].visible and not p.handles["controller.alpha"].visible
    p.handles["controller"].value = "Original RPSO"
    assert s.sim.params.law == "rpso" and s.sim.params.c == pytest.approx((c1, c2, c3))


def test_non_omni_controller_switches_drive_and_rebuilds(tab):
    p = tab.panels
    p.handles["controller"].value = "Non-omni + DVC"
    s = tab.session
    assert s.sim.params.law == "nonomni" and s.sim.params.drive == "differential" and s.sim.state.k == 0
    assert _last(tab)[0] == "Fleet rebuilt"
    assert tuple(p.handles["robot.drive"].options) == ("differential",)
    s.step(3)
    assert s.sim.state.c.shape[0] == 5  # the five non-omni budgets


def test_bad_values_are_refused_and_the_fleet_is_untouched(tab):
    s, p = tab.session, tab.panels
    s.step(3)
    fleet, scenario = s.sim, s.scenario
    p.handles["controller.alpha"].value = 1.0  # the model wants α < 1
    title, body, color = _last(tab)
    assert color == "red" and "controller.alpha" in body
    assert p.handles["controller.alpha"].value == pytest.approx(0.9)  # handle restored
    assert fleet.params.alpha == 0.9 and s.scenario is scenario and s.sim is fleet
    p.handles["world.length"].value = 20.0  # allowed by the model, too short for the course generator
    title, body, color = _last(tab)
    assert color == "red" and "world.length" in body
    assert p.handles["world.length"].value == pytest.approx(60.0)
    assert s.sim is fleet and s.sim.state.k == 3


def test_world_and_robot_count_changes_rebuild_the_fleet(tab):
    s, p = tab.session, tab.panels
    s.step(5)
    old = s.sim
    p.handles["sim.robots"].value = 9
    assert s.sim is not old and s.sim.robots == 9 and s.sim.state.k == 0
    assert _last(tab)[:1] == ("Fleet rebuilt",)
    circles = s.sim.world.circles.copy()
    p.handles["world.seed"].value = 5
    assert not np.array_equal(s.sim.world.circles, circles)
    p.handles["world.kind"].value = "forest"
    assert s.sim.world.name == "forest" and p.handles["world.density"].visible
    assert not p.handles["world.layers"].visible


# ---------------------------------------------------------------------------- editing the world
def test_click_adds_an_obstacle_that_the_next_step_senses(tab):
    s, p = tab.session, tab.panels
    p.handles["controller.update"].value = "simultaneous"  # robot 2 senses before anyone moves
    tab.tick(1.0)
    spot = free_spot(s, 2, 1.0)
    n = len(s.sim.world.circles)
    click_at(tab, *spot)
    circles = s.sim.world.circles
    assert len(circles) == n + 1
    np.testing.assert_allclose(circles[-1, :2], spot, atol=1e-6)
    assert circles[-1, 2] == pytest.approx(0.7)
    assert fleet_kind.driver(s).edits == 1
    s.step(1)
    reading = s.sim.state.reading
    seen = reading.hit[0, 2] & np.all(np.isclose(reading.centre[0, 2], spot), axis=-1)
    assert seen.any(), "the robot next to the new obstacle did not sense it"
    tab.tick(2.0)
    assert len(tab.arena.nodes["obstacles"].batched_positions) == n + 1  # and it is drawn


def test_shift_click_removes_the_nearest_obstacle_and_drag_moves_one(tab):
    s = tab.session
    circles = s.sim.world.circles.copy()
    target = circles[3]
    click_at(tab, target[0] + target[2] + 0.3, target[1], "shift")
    after = s.sim.world.circles
    assert len(after) == len(circles) - 1
    assert not np.any(np.all(np.isclose(after, target), axis=1))
    tab.tick(1.0)
    assert len(tab.arena.nodes["obstacles"].batched_positions) == len(after)
    # drag obstacle 0 somewhere free: the view reports scene coordinates of the pointer
    dest = np.array([30.0, 0.5]) if s.sim.world.obstacle_distance(30.0, 0.5).min() > 1.0 else np.array([33.0, 9.0])
    event = type("Drag", (), dict(instance_index=0, phase="update", end_position=(*tab.arena.to_scene(dest), 0.0)))
    tab.arena.layer("obstacles").dragged(event)
    np.testing.assert_allclose(s.sim.world.circles[0, :2], dest, atol=1e-6)
    assert len(s.sim.world.circles) == len(after)


def test_move_mode_picks_then_places(tab):
    s, p = tab.session, tab.panels
    p.handles["click"].value = "move obstacle"
    c = s.sim.world.circles[5].copy()
    click_at(tab, c[0], c[1] + c[2] + 0.2)
    assert p.part.state.picked == 5
    dest = (c[0] + 1.5, c[1])
    click_at(tab, *dest)
    np.testing.assert_allclose(s.sim.world.circles[5, :2], dest, atol=1e-6)


def test_edits_on_a_robot_are_refused_and_clicks_on_robots_select(tab):
    s, p = tab.session, tab.panels
    x = s.sim.state.x[0, 4]
    n = len(s.sim.world.circles)
    with pytest.raises(EditRefused, match="robot"):
        fleet_kind.driver(s).add_obstacle(x[0] + 0.9, x[1])
    click_at(tab, x[0] + 0.2, x[1])
    assert s.selected_robot == 4 and p.handles["robot"].value == 4
    assert len(s.sim.world.circles) == n
    s.step(2)
    s.reset()
    assert s.sim.state.k == 0 and len(s.sim.world.circles) == n  # reset keeps the world
    click_at(tab, *free_spot(s, 0, 2.0))
    p.handles["restore"].value = True
    assert len(s.sim.world.circles) == n and fleet_kind.driver(s).edits == 0


# ---------------------------------------------------------------------------- the selected robot
@pytest.mark.parametrize("preset", ["course-dvc", "course-nonomni"])
def test_selected_robot_sectors_are_its_reading(tab, preset):
    tab.panels.preset.value = preset
    s, p = tab.session, tab.panels
    s.step(12)
    p.handles["robot"].value = 3
    tab.tick(5.0)
    fleet = s.sim
    params = fleet.params
    reading = sense(fleet.spaces, fleet.state.x, fleet.state.heading, sensing_range=params.sensing_range,
                    robot_frame=params.body_frame)
    i, view = 3, tab.arena
    sectors = view.nodes["sectors"]
    centre = view.to_view(fleet.state.x[0, i])
    np.testing.assert_allclose(np.asarray(sectors.batched_positions)[:, :2], np.repeat(centre[None, :2], 6, 0),
                               atol=1e-5)  # the six wedges sit on the robot
    np.testing.assert_allclose(np.asarray(sectors.batched_scales),
                               (params.robot_radius + reading.gap[0, i]) * view.scale, rtol=1e-5)
    w, z = np.asarray(sectors.batched_wxyzs)[:, 0], np.asarray(sectors.batched_wxyzs)[:, 3]
    start = 2 * np.arctan2(z, w)  # each wedge's first edge
    frame = fleet.state.heading[0, i] if params.body_frame else 0.0
    expected = frame - math.pi + np.arange(6) * math.pi / 3
    np.testing.assert_allclose(np.angle(np.exp(1j * (start - expected))), 0.0, atol=1e-5)
    hits = np.asarray(view.nodes["hits"].points)[:, :2]
    np.testing.assert_allclose(hits, view.to_view(reading.point[0, i][reading.hit[0, i]])[:, :2], atol=1e-5)
    assert f"robot {i}" in p.handles["budget"].content


def test_the_budget_shown_is_the_budget_the_next_step_uses(tab):
    s, p = tab.session, tab.panels
    p.handles["controller.update"].value = "simultaneous"
    s.step(15)
    p.handles["robot"].value = 1
    tab.tick(3.0)
    shown = fleet_kind.driver(s).view()
    budget = p.handles["budget"].content
    assert f"{shown.c[0] + shown.c[1]:.3f}" in budget and f"{shown.c[2]:.3f}" in budget
    s.step(1)
    np.testing.assert_allclose(s.sim.state.reading.gap[0, 1], shown.gap)
    np.testing.assert_allclose(s.sim.state.c[:, 0, 1], shown.c)
    np.testing.assert_allclose(s.sim.state.force[0, 1], shown.force)


def test_follow_views_keep_the_robot_in_the_middle_and_clicks_still_land(tab):
    s, p = tab.session, tab.panels
    s.step(20)
    p.handles["robot"].value = 2
    p.handles["view"].value = "follow the robot"
    tab.tick(4.0)
    view = tab.arena
    assert view.camera.zoom == pytest.approx(2.5)
    x = s.sim.state.x[0, 2]
    np.testing.assert_allclose(view.to_scene(x), 0.0, atol=1e-6)  # on the camera's axis
    root = np.asarray(view.nodes["root"].position)[:2]
    np.testing.assert_allclose(view.to_view(x)[:2] + root, 0.0, atol=1e-5)
    spot = free_spot(s, 2, 1.5)
    n = len(s.sim.world.circles)
    click_at(tab, *spot)
    np.testing.assert_allclose(s.sim.world.circles[n, :2], spot, atol=1e-6)


# ---------------------------------------------------------------------------- plots, notes, export
def test_plots_show_com_fitness_with_layer_lines_and_operational_robots(tab):
    s, p = tab.session, tab.panels
    s.step(10)
    p.refresh_plots()
    data = p.handles["com"].data
    m = s.metric_arrays()
    np.testing.assert_allclose(data[0], m["t"])
    np.testing.assert_allclose(data[1], m["com_fitness"])
    assert m["com_fitness"][-1] == pytest.approx(s.sim.state.x[0, :, 0].mean())  # [4.17]
    layers = s.sim.world.layer_x
    assert len(data) == 2 + len(layers)
    for j, lx in enumerate(layers):
        assert np.all(np.asarray(data[2 + j]) == lx)
    assert p.handles["com"].scales["x"]["time"] is False
    ops = p.handles["robots"].data
    np.testing.assert_allclose(ops[1], m["operational"])
    assert ops[1][-1] == s.sim.robots - s.sim.state.status[0].sum()


def test_notes_follow_the_scene(tab):
    assert "Chapters 4–5" in tab.panels.notes.content and "c3 = 0" in tab.panels.notes.content
    tab.panels.preset.value = "default"
    assert "Chapter 3" in tab.panels.notes.content


def test_export_marks_collided_robots(tab):
    tab.panels.preset.value = "course-rpso"
    s = tab.session
    while s.sim.state.status[0].sum() == 0 and s.sim.state.k < 200:
        s.step(1)
    s.step(2)
    tab.panels.export_csv.value = True
    name, content = tab.downloads[-1]
    rows = list(csv.DictReader(io.StringIO(content.decode())))
    assert tuple(rows[0]) == TRAJECTORY_COLUMNS
    last = sorted((r for r in rows if int(r["step"]) == s.sim.state.k), key=lambda r: int(r["robot"]))
    assert [int(r["status"]) for r in last] == list(s.sim.state.status[0])
    np.testing.assert_allclose([[float(r["x"]), float(r["y"])] for r in last], s.sim.state.x[0], atol=1e-8)
    tab.panels.export_json.value = True
    doc = json.loads(tab.downloads[-1][1])
    assert doc["preset"]["name"] == "course-rpso" and doc["world"]["circles"]
    assert doc["trajectories"][-1]["status"] == int(s.sim.state.status[0, -1])


# ---------------------------------------------------------------------------- switching kinds
def test_switching_between_chapter_3_and_fleet_scenes_in_one_tab(tab, server):
    tab.panels.preset.value = "rastrigin"
    assert tab.session.kind is swarm.KIND and tab.panels.name == "swarm"
    assert tab.arena.name == "swarm"
    assert server.sessions[HAND_TAB] is tab.session
    tab.tick(1.0)
    assert "landscape" in tab.arena.nodes and not any(n.startswith("obstacle") for n in tab.arena.nodes)
    tab.panels.handles["controller.mode"].value = "raw"
    tab.panels.handles["controller.omega"].value = 0.61
    assert tab.session.sim.policy.omega == pytest.approx(0.61)  # Chapter 3 panels work again
    text = presets_io.to_toml(presets_io.load("forest-dvc")).encode()
    assert tab.panels.upload_preset("forest.toml", text)
    assert tab.session.kind is fleet_kind.KIND and tab.session.sim.world.name == "forest"
    tab.tick(2.0)
    assert "obstacles" in tab.arena.nodes and "landscape" not in tab.arena.nodes
    tab.panels.preset.value = "default"
    tab.tick(3.0)
    s = tab.session
    s.step(3)
    tab.tick(4.0)
    drawn = np.asarray(tab.arena.nodes["robots"].points)
    assert drawn.shape[0] == s.sim.robots and s.kind is swarm.KIND


def test_a_server_can_start_on_a_fleet_preset_and_sessions_accept_only_their_kind():
    with pytest.raises(Exception, match="world"):
        Session(presets_io.load("course-dvc"), swarm.KIND)
    with pytest.raises(Exception, match="world"):
        Session(presets_io.load("default"), fleet_kind.KIND)
    assert set(CONTROLLERS.values()) >= {("rpso", "raw"), ("adapted-rpso", "raw"), ("adapted-rpso", "dvc"),
                                         ("robot-centred", "raw"), ("nonomni", "dvc")}
