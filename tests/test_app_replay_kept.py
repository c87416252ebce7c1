"""A replay keeps what the arena showed while the run went on: swarm B of Compare, the obstacles
a user added or removed in a fleet's world, a source dragged or moving. Recorded in sessions,
exported, loaded back through the panel's *Load replay* into a hand-ticked tab and drawn; the
JSON export's preset is the edited one, as *Download preset* writes it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from shoal.app import replay
from shoal.app.kinds import fleet, sonar
from shoal.app.kinds.registry import session_for
from shoal.presets import io as presets_io

APP_PRESET = "course-dvc"  # the shared ``server`` fixture (conftest.py); loads swap the scene kind


def session(name: str, *overrides: str):
    return session_for(presets_io.load(name, list(overrides)))


def loaded(tab, src, name: str = "run.npz"):
    """``src``'s replay file, loaded into ``tab`` through the panel (refused: the test fails)."""
    assert tab.panels.replay_gui.load(name, src.export_replay()), tab.messages[-1]
    assert tab.session.replaying is not None
    return tab.session


def drawn(tab, key: str, prop: str = "points") -> np.ndarray:
    """World positions (x, y) of the ``key`` node's points as the arena shows them now."""
    pts = np.asarray(getattr(tab.arena.nodes[key], prop), dtype=float).reshape(-1, 3)
    return tab.arena.to_world(pts[:, :2]) if len(pts) else np.zeros((0, 2))


def edited_course():
    """course-dvc run 12 steps: an obstacle added after step 4, another removed after step 8."""
    src = session("course-dvc")
    d = fleet.driver(src)
    src.step(4)
    generated = src.sim.world.circles.copy()
    d.add_obstacle(src.sim.world.bounds[2] - 4.0, 1.5, 1.25)
    src.step(4)
    added = src.sim.world.circles.copy()
    d.remove_obstacle_near(*generated[2, :2], tol=0.0)
    src.step(4)
    return src, (generated, added, src.sim.world.circles.copy())


def test_a_replay_draws_the_obstacles_as_they_were_at_each_step(tab):
    src, (generated, added, removed) = edited_course()
    rec = replay.from_bytes(src.export_replay())
    assert rec.scene["obstacles"].i.tolist() == [0, 5, 9]  # three versions, not one a frame
    s = loaded(tab, src)
    for n, (k, circles) in enumerate(((2, generated), (6, added), (11, removed), (3, generated))):
        s.scrub(k)
        tab.tick(1.0 + n)  # (the tab's clock only goes on)
        np.testing.assert_allclose(drawn(tab, "obstacles", "batched_positions"), circles[:, :2], atol=1e-5)
        np.testing.assert_allclose(np.asarray(tab.arena.nodes["obstacles"].batched_scales) / tab.arena.scale,
                                   circles[:, 2], rtol=1e-6)
    assert "obstacle" in [e.label for e in tab.arena.legend()]
    s.leave_replay()  # Run live: a live run of the preset, its own world again
    tab.tick(20.0)
    np.testing.assert_allclose(drawn(tab, "obstacles", "batched_positions"), generated[:, :2], atol=1e-5)


def test_scrubbing_a_live_run_back_shows_the_obstacles_of_that_step(tab):
    s = tab.session
    d = fleet.driver(s)
    s.step(3)
    before = s.sim.world.circles.copy()
    d.add_obstacle(s.sim.world.bounds[2] - 4.0, -1.5, 1.0)
    s.step(3)
    s.scrub(2)
    tab.tick(1.0)
    np.testing.assert_allclose(drawn(tab, "obstacles", "batched_positions"), before[:, :2], atol=1e-5)
    s.step(1)  # on from the live end: the obstacle is there
    tab.tick(2.0)
    assert len(drawn(tab, "obstacles", "batched_positions")) == len(before) + 1


def test_a_replay_draws_a_dragged_source_where_it_was(tab):
    src = session("sonar-xb-pso")
    start = src.sim.state.source[0].copy()
    src.step(3)
    sonar.driver(src).move_source(12.5, -30.25)
    src.step(3)
    rec = replay.from_bytes(src.export_replay())
    assert rec.scene["source"].i.tolist() == [0, 4]  # the drag, not a copy a frame
    s = loaded(tab, src)
    for n, (k, where) in enumerate(((2, start), (5, (12.5, -30.25)), (0, start))):
        s.scrub(k)
        tab.tick(1.0 + n)
        np.testing.assert_allclose(drawn(tab, "source", "batched_positions"), [where], atol=1e-4)
        np.testing.assert_allclose(s.shown_snapshot().extras["source"], where)


def test_a_replay_draws_a_moving_source_where_it_was_at_each_step(tab):
    src = session("escort-moving", "sim.steps=20")
    src.step(12)
    path = {f.k: f.scene["source"][0] for f in src.frames}
    assert np.hypot(*(path[12] - path[0])) > 0.5  # it really moves
    s = loaded(tab, src)
    for n, k in enumerate((1, 12, 7)):
        s.scrub(k)
        tab.tick(1.0 + n)
        np.testing.assert_allclose(drawn(tab, "source", "batched_positions"), [path[k]], atol=1e-4)
    rec = replay.from_bytes(s.export_replay())  # a replay shown exports the same path again
    np.testing.assert_array_equal(rec.scene_at(7)["source"][0], path[7])


def test_a_replay_keeps_swarm_b_and_draws_it_in_teal(tab):
    src = session("default", "sim.robots=8")
    src.enable_compare({"controller.law": "standard", "controller.mode": "raw"})
    src.step(20)
    b = {f.k: f.x.copy() for f in src.twin.frames}
    assert np.abs(b[20] - src.frames[20].x).max() > 0.1  # B really went elsewhere
    s = loaded(tab, src)
    assert s.twin is None  # nothing runs: B is drawn from the file
    for n, k in enumerate((15, 4)):
        s.scrub(k)
        tab.tick(1.0 + n)
        assert tab.arena.nodes["twin"].visible
        np.testing.assert_allclose(drawn(tab, "twin"), b[k], atol=1e-5)
        np.testing.assert_allclose(drawn(tab, "robots"), src.frames[k].x, atol=1e-5)
    assert {"swarm B", "swarm B's trail"} <= {e.label for e in tab.arena.legend()}
    assert "swarm B" in tab.panels.replay_gui.badge.content
    again = replay.from_bytes(s.export_replay())  # exported again from the replay: B kept
    assert again.twin_overrides == {"controller.law": "standard", "controller.mode": "raw"}
    np.testing.assert_array_equal(again.twin(15)[0], b[15])
    s.leave_replay()  # Run live: a live run of the preset, without B
    tab.tick(40.0)
    assert not tab.arena.nodes["twin"].visible


def test_a_swarm_b_in_another_dimension_is_kept_in_its_own():
    src = session("default", "sim.robots=6")
    src.enable_compare({"sim.d": 3})
    src.step(8)
    rec = replay.from_bytes(src.export_replay())
    assert rec.x.shape[1] == 2 and rec.b_x.shape[1] == 3
    np.testing.assert_array_equal(rec.twin(8)[0], src.twin.frames[8].x)
    s = session("default", "sim.robots=6")
    s.enter_replay(rec, (None, "not checked"))
    s.scrub(8)
    x, trails = s.shown_snapshot().twin
    np.testing.assert_array_equal(x, src.twin.frames[8].x)
    assert trails.shape[-1] == 3


def test_a_replay_with_b_overrides_the_preset_cannot_take_is_refused(tab):
    src = session("default")
    src.enable_compare({"sim.robots": 3})
    src.step(3)
    rec = src.recording()
    bad = replay.Recording(**{**{f: getattr(rec, f) for f in ("k", "t", "n", "x", "heading", "status", "metrics",
                                                             "b_n", "b_x", "b_status")},
                              "meta": {**rec.meta, "twin": {"overrides": {"sim.robots": -4}}}})
    s = tab.session
    assert not tab.panels.replay_gui.load("bad.npz", replay.to_bytes(bad))
    title, body, colour = tab.messages[-1]
    assert colour == "red" and "B: sim.robots" in body
    assert tab.session is s and s.replaying is None


def test_a_version_1_replay_still_loads_and_plays(tab):
    from test_replay import v1_bytes

    src, (generated, _, _) = edited_course()
    assert tab.panels.replay_gui.load("old.npz", v1_bytes(src.recording()))
    s = tab.session
    s.scrub(6)
    tab.tick(1.0)
    np.testing.assert_allclose(drawn(tab, "robots"), src.frames[6].x, atol=1e-5)
    # version 1 kept no obstacles: the preset's world is drawn, as before
    np.testing.assert_allclose(drawn(tab, "obstacles", "batched_positions"), generated[:, :2], atol=1e-5)


# ---------------------------------------------------------------------------- the JSON export's preset
def test_the_json_export_holds_the_preset_download_preset_writes():
    src, (_, _, removed) = edited_course()
    doc = json.loads(src.export_json())
    toml = presets_io.validate(presets_io.parse_text(src.preset_toml().decode()))
    assert doc["preset"] == toml.model_dump(mode="json") == src.kept_scenario().model_dump(mode="json")
    np.testing.assert_array_equal(np.asarray(doc["preset"]["world"]["obstacles"]), removed)
    s = session("sonar-xb-pso")
    sonar.driver(s).move_source(12.5, -30.25)
    assert json.loads(s.export_json())["preset"]["acoustics"]["source"] == [12.5, -30.25]
    plain = session("default")
    assert json.loads(plain.export_json())["preset"] == plain.scenario.model_dump(mode="json")


def test_export_json_of_edits_a_preset_cannot_hold_is_refused_by_name(tab):
    s = tab.session
    sx0, sy0, sx1, sy1 = s.sim.world.start_box
    s.sim.state.x[0] += (sx1 - sx0) + 3.0  # the robots have left the start box
    fleet.driver(s).add_obstacle((sx0 + sx1) / 2, (sy0 + sy1) / 2, 0.5)
    before = len(tab.downloads)
    tab.panels.export_json.value = True
    assert len(tab.downloads) == before  # nothing half-written
    title, body, colour = tab.messages[-1][:3]
    assert title == "Refused: export JSON" and "start box" in body and colour == "red"


@pytest.mark.parametrize("name", ["slo-walk", "rastrigin"])
def test_kinds_without_b_or_scene_changes_replay_as_before(name):
    src = session(name)
    src.step(6)
    rec = replay.from_bytes(src.export_replay())
    assert rec.scene == {} and not len(rec.b_x) and rec.twin_overrides is None


# ---------------------------------------------------------------------------- hostile files on the wire
def test_hostile_version_2_replays_sent_over_the_wire_are_refused_by_name(server):
    """A page is not limited to files Export replay wrote: version-2 files with a NaN in swarm B,
    obstacle counts that overflow when added, a negative radius or a source a light-year away,
    uploaded through Load replay on a raw websocket, are each refused naming the array, and the
    tab's scene is untouched."""
    from test_replay import HUGE, arrays_of, full_recording, npz

    from browser.browser_helpers import wait_until
    from viser_wire import WireClient

    rec = full_recording()
    bad = {
        "b_x": dict(b_x=np.full((10, 2), np.nan)),
        "obstacles_n": dict(obstacles_n=np.array([HUGE, 5 - HUGE])),
        "obstacles_v": dict(obstacles_v=np.array([[5.0, 1.0, -0.5]] * 5)),
        "source_v": dict(source_v=np.full((6, 2), 9.5e15)),
        "b_n": dict(b_n=np.array([0, HUGE, HUGE, HUGE, HUGE, 10])),
    }
    client = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: client.uuid_of("Load replay") and server.tabs, what="the tab's panels")
        cid = max(server.tabs)
        session = server.tabs[cid].session
        k, scenario = session.k, session.scenario
        for name, change in bad.items():
            before = len(client.notifications())
            client.upload("Load replay", f"{name}.npz", npz(**arrays_of(rec, **change)))
            wait_until(lambda n=before: len(client.notifications()) > n, what=f"the verdict on {name}")
            title, body, colour = client.notifications()[-1][:3]
            assert colour == "red" and f"{name}.npz: {name}:" in body, (title, body)
        assert server.tabs[cid].session is session and session.replaying is None and session.scenario is scenario
        assert session.k >= k  # still its own live run
    finally:
        client.close()


def test_the_status_line_names_the_recorded_step_shown(tab):
    """Scrubbing or replaying, the status line gives the step the arena shows (not the engine's
    live step) and says the live numbers are not recorded; back at the live end it is the kind's."""
    src = session("default", "sim.steps=30")
    src.step(12)
    s = loaded(tab, src)
    s.scrub(7)
    tab.panels.refresh_status()
    text = tab.panels.status.content
    assert "replay · step 7 of 12" in text and "not recorded" in text
    live = session("default", "sim.steps=30")
    assert live.shown_step() is None
    live.step(5)
    live.scrub(2)
    assert live.shown_step()[0] == 2 and live.shown_step()[2] == 5
