"""A/B comparison (swarm B), the timeline and replays in the browser app, without a browser.

Sessions are driven directly; the panels and the arena through a real viser server's GUI
(``server.gui``: assigning ``.value`` runs the callbacks in the test thread), as in
``test_app_session.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app import replay
from shoal.app.kinds import fleet, sonar
from shoal.app.kinds.fleet import PROBE_NODES
from shoal.app.kinds.registry import session_for
from shoal.app.session.timeline import verify_replay
from shoal.app.session.twin import parse_overrides, twin_scenario
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.testing import example_presets

from app_helpers import shown

KINDS = tuple(example_presets().values())  # one preset of every registered kind (shoal.testing)


def session(name: str = "default", **overrides):
    sc = presets_io.load(name, [f"{k}={v}" for k, v in overrides.items()])
    return session_for(sc)


def positions(s) -> dict[int, np.ndarray]:
    return {f.k: f.x for f in s.frames}


# ---------------------------------------------------------------------------- overrides
def test_override_lines_are_read_like_set():
    text = "controller.law = standard  # the other law\n\n sim.robots=12; view.trail_seconds=2.5\nx.flag=true"
    assert parse_overrides(text) == {"controller.law": "standard", "sim.robots": 12, "view.trail_seconds": 2.5,
                                     "x.flag": True}
    with pytest.raises(PresetError, match="not dotted.key=value"):
        parse_overrides("controller.omega 0.5")


def test_b_differs_from_a_only_by_its_overrides():
    s = session("default")
    s.enable_compare({"controller.law": "adapted-tanh", "sim.robots": 12})
    a, b = s.scenario.model_dump(), s.twin.scenario.model_dump()
    assert b["controller"].pop("law") == "adapted-tanh" and b["sim"].pop("robots") == 12
    a["controller"].pop("law"), a["sim"].pop("robots")
    assert a == b
    assert s.twin.scenario == twin_scenario(s.scenario, s.overrides)


# ---------------------------------------------------------------------------- lock-step
@pytest.mark.parametrize("name", KINDS)
def test_without_overrides_b_is_a_step_by_step(name):
    s = session(name)
    s.step(3)
    s.enable_compare({})  # A restarts with B from step 0
    assert s.sim.state.k == s.twin.sim.state.k == 0
    s.step(15)
    pa, pb = positions(s), positions(s.twin)
    assert sorted(pa) == sorted(pb) == list(range(16))
    for k in pa:
        np.testing.assert_array_equal(pa[k], pb[k])


def test_b_shows_only_once_a_has_restarted(monkeypatch):
    """A reader that does not take the session's lock (a page poll, a test) never finds the new B
    beside A's old step: B is published after A's restart, both at step 0."""
    s = session("default")
    s.step(5)
    seen = []
    reset = s.sim.reset

    def watched_reset(seed):  # A's restart begins: what does a lock-free reader see now?
        seen.append((s.twin is not None, int(s.sim.state.k)))
        reset(seed)

    monkeypatch.setattr(s.sim, "reset", watched_reset)
    s.enable_compare({"controller.law": "adapted-tanh"})
    assert seen == [(False, 5)]  # no B yet while A still stood at step 5
    assert s.sim.state.k == s.twin.sim.state.k == 0


def test_another_law_takes_b_elsewhere_from_the_same_start():
    s = session("default")
    choices = {"controller.law": "standard", "controller.mode": "raw", "controller.omega": 0.5,
               "controller.c1": 1.06066, "controller.c2": 1.06066}
    s.enable_compare(choices)
    s.step(30)
    pa, pb = positions(s), positions(s.twin)
    np.testing.assert_array_equal(pa[0], pb[0])  # same seed: same start
    assert np.abs(pa[30] - pb[30]).max() > 0.1


def test_changes_to_a_reach_b_and_keep_it_in_step():
    s = session("default")
    s.enable_compare({"controller.law": "adapted-tanh"})
    s.step(5)
    s.apply({"controller.U": 4.0})
    assert s.twin.scenario.controller.U == 4.0 and s.twin.scenario.controller.law == "adapted-tanh"
    s.step(5)
    assert s.sim.state.k == s.twin.sim.state.k == 10
    s.reset(seed=7)
    assert s.twin.scenario.sim.seed == 7 and s.twin.sim.state.k == 0
    s.step(4)
    s.reset()
    assert s.sim.state.k == s.twin.sim.state.k == 0


def test_a_bad_override_is_refused_by_name_and_changes_nothing():
    s = session("default")
    s.step(7)
    with pytest.raises(PresetError) as err:
        s.enable_compare({"controller.omega": 3.0})
    assert any(m.startswith("B: controller.omega") for m in err.value.messages)
    assert s.twin is None and s.sim.state.k == 7


def test_a_change_that_b_cannot_take_is_refused_for_both():
    s = session("course-dvc")
    s.enable_compare({"controller.alpha": 0.9})
    s.step(3)
    with pytest.raises(PresetError) as err:
        s.apply({"sim.robots": 0})
    assert err.value.messages
    with pytest.raises(PresetError, match="B: "):
        s.enable_compare({"world.kind": "nowhere"})
    assert s.twin.scenario.controller.alpha == 0.9 and s.sim.state.k == s.twin.sim.state.k == 3


# ---------------------------------------------------------------------------- timeline
def test_scrubbing_shows_the_recorded_frame_and_play_returns_live():
    s = session("default")
    s.enable_compare({"controller.law": "adapted-tanh"})
    s.play()
    s.step(20)
    assert s.scrub(8) == 8 and not s.playing
    snap = s.shown_snapshot()
    np.testing.assert_array_equal(snap.x, s.frames[8].x)
    assert not snap.live and snap.k == 8
    assert snap.trails.shape[1] >= 2 and np.allclose(snap.trails[:, -1], s.frames[8].x[: len(snap.trails)])
    np.testing.assert_array_equal(s.twin_view()[0], s.twin.frames[8].x)
    m, span = s.shown_metrics(1000)
    assert m["t"][-1] == pytest.approx(s.frames[8].t) and span[1] == pytest.approx(s.frames[-1].t)
    s.apply({"view.trail_seconds": 2.0})  # a view setting keeps the step shown...
    assert s.cursor == 8
    s.apply({"controller.U": 5.0})  # ...a change to the run shows the live run
    assert s.cursor is None
    s.scrub(3)
    s.play()
    assert s.cursor is None and s.shown_snapshot().live


# ---------------------------------------------------------------------------- replays
@pytest.mark.parametrize("name", KINDS)
def test_a_replay_re_simulates_to_the_same_positions(name):
    s = session(name)
    s.step(25)
    rec = replay.from_bytes(s.export_replay(), "run.npz")
    assert rec.frames == 26 and rec.name == name and rec.metric_names == s.history.names
    verified, text = verify_replay(session_for(presets_io.validate(rec.meta["preset"])), rec)
    assert verified is True and "steps 0–20 match" in text


def test_a_run_changed_while_it_ran_is_shown_but_not_verified():
    s = session("default")
    s.step(5)
    s.apply({"controller.U": 4.0})
    s.step(10)
    rec = replay.from_bytes(s.export_replay())
    assert rec.meta["live_edits"] == 1
    verified, text = verify_replay(session_for(presets_io.validate(rec.meta["preset"])), rec)
    assert verified is False and "not reproduced" in text


def test_a_replay_opens_at_its_start_plays_through_and_reset_rewinds_it():
    src = session("default")
    src.step(12)
    rec = replay.from_bytes(src.export_replay())
    s = session("default")
    s.enter_replay(rec, (True, "verified"))
    assert s.replaying.name == "default" and s.cursor == 0 and not s.playing  # at its first step, paused
    s.play()
    assert s.step(5) == 5 and s.cursor == 5 and s.sim.state.k == 0  # the engine does not advance
    np.testing.assert_array_equal(s.shown_snapshot().x, src.frames[5].x)
    assert s.step(100) == 7 and s.cursor == 12 and not s.playing  # its end: paused there
    s.play()  # at the end: from the start again
    assert s.cursor == 0 and s.playing
    s.step(4)
    s.apply({"view.trail_seconds": 3.0})  # a view change keeps the replay
    assert s.replaying is not None
    s.reset()  # back to the replay's first step, playing on
    assert s.replaying is not None and s.cursor == 0 and s.playing
    s.leave_replay()  # a live run of its preset (so does a changed control)
    assert s.replaying is None and s.cursor is None and len(s.frames) == 1
    s.enter_replay(rec, (True, "verified"))
    s.reset(seed=5)  # a new seed: a live run with it
    assert s.replaying is None and s.scenario.sim.seed == 5


# ---------------------------------------------------------------------------- panels
def test_compare_tab_switches_b_on_and_the_arena_and_plot_show_it(tab):
    p = tab.panels
    assert p.compare_gui.quick.value.startswith("standard PSO law")
    assert "controller.law=standard" in p.compare_gui.text.value
    p.compare_gui.enabled.value = True
    s = tab.session
    assert s.twin is not None and tab.messages[-1][2] == "green"
    s.step(10)
    tab.tick(1.0)
    node = tab.arena.nodes["twin"]
    assert node.visible
    np.testing.assert_allclose(np.asarray(node.points)[:, :2], tab.arena.to_view(s.twin.sim.state.x[0])[:, :2],
                               atol=1e-5)
    assert p.handles["speed"].series[-1]["label"] == "B: max |u|"
    assert len(p.handles["speed"].data) == len(p.handles["speed"].series)
    p.compare_gui.enabled.value = False
    tab.tick(2.0)
    assert s.twin is None and not tab.arena.nodes["twin"].visible
    assert all(not x.get("label", "").startswith("B:") for x in p.handles["speed"].series)


def test_a_bad_override_typed_in_the_compare_tab_is_a_red_toast(tab):
    p = tab.panels
    p.compare_gui.text.value = "controller.omega=7"
    p.compare_gui.enabled.value = True
    title, body, color = tab.messages[-1]
    assert color == "red" and "B: controller.omega" in body
    assert tab.session.twin is None and p.compare_gui.enabled.value is False


def test_the_timeline_slider_scrubs_and_the_arena_shows_that_step(tab):
    s = tab.session
    s.step(30)
    tab.tick(1.0)
    timeline = tab.panels.replay_gui.timeline
    assert (timeline.min, timeline.max, timeline.value) == (0, 30, 30)
    timeline.value = 12
    assert s.cursor == 12 and not s.playing
    tab.tick(2.0)
    robots = np.asarray(tab.arena.nodes["robots"].points)[:, :2]
    np.testing.assert_allclose(robots, tab.arena.to_view(s.frames[12].x)[:, :2], atol=1e-5)
    assert not tab.arena.nodes["gbest"].visible  # bests are not recorded
    assert tab.panels.handles["speed"].data[0][-1] == pytest.approx(s.frames[12].t)
    assert "step 12" in shown(tab.panels.replay_gui.where.content)


def test_load_replay_swaps_the_scene_kind_and_shows_the_badge(tab):
    src = session("course-dvc")
    src.step(15)
    data = src.export_replay()
    assert tab.panels.replay_gui.load("course.npz", data)
    s = tab.session
    assert s.kind is fleet.KIND and s.replaying is not None and s.scenario.name == "course-dvc"
    assert tab.messages[-1][2] == "green" and "verified" in tab.messages[-1][1]
    tab.tick(1.0)
    badge, live = tab.panels.replay_gui.badge, tab.panels.replay_gui.live
    assert badge.visible and "Replay of course-dvc, seed" in shown(badge.content) and live.visible
    assert "Reset goes back to its first step" in shown(badge.content)
    s.scrub(9)
    tab.tick(2.0)
    pts = np.asarray(tab.arena.nodes["robots"].points)[:, :2]
    np.testing.assert_allclose(pts, tab.arena.to_view(src.frames[9].x)[:, :2], atol=1e-5)
    nodes = tab.arena.nodes
    assert not nodes["gbest"].visible and not any(nodes[k].visible for k in PROBE_NODES if k in nodes)
    tab.panels.press("Reset")  # the replay's first step
    assert s.replaying is not None and s.cursor == 0
    live.value = True  # Run live: a live run of the preset, playing; the sensing view is back
    tab.tick(3.0)
    assert s.replaying is None and s.playing and not badge.visible and not live.visible
    assert nodes["sectors"].visible and nodes["gbest"].visible


def test_a_bad_replay_is_refused_and_nothing_changes(tab):
    s = tab.session
    s.step(4)
    good = session("default")
    good.step(3)
    data = good.export_replay()
    for name, content, words in (("big.npz", b"\0" * (replay.MAX_REPLAY_BYTES + 1), "20 MiB"),
                                 ("cut.npz", data[:-200], "truncated"),
                                 ("text.npz", b"hello", "not a replay")):
        assert not tab.panels.replay_gui.load(name, content)
        title, body, color = tab.messages[-1]
        assert color == "red" and name in title and words in body
    assert tab.session is s and s.replaying is None and s.sim.state.k == 4
    assert s.kind.name == "swarm"


@pytest.mark.parametrize("name", KINDS)
def test_every_kind_draws_b_and_a_scrubbed_frame(tab, name):
    s = tab.replace(presets_io.load(name))
    choice = next(iter(tab.panels.compare_choices().values()))
    tab.panels.compare_gui.quick.value = next(iter(tab.panels.compare_choices()))
    assert parse_overrides(tab.panels.compare_gui.text.value) == choice
    tab.panels.compare_gui.enabled.value = True
    assert s.twin is not None, tab.messages[-1]
    s.step(12)
    tab.tick(1.0)
    twin = tab.arena.nodes["twin"]
    assert twin.visible
    np.testing.assert_allclose(np.asarray(twin.points)[:, :2], tab.arena.to_view(s.twin.sim.state.x[0, :, :2])[:, :2],
                               atol=1e-5)
    plot_labels = [x["label"] for key in ("speed", "com", "dist", "error") if key in tab.panels.handles
                   for x in tab.panels.handles[key].series]
    assert any(label.startswith("B: ") for label in plot_labels)
    s.scrub(5)
    tab.tick(2.0)
    np.testing.assert_allclose(np.asarray(tab.arena.nodes["robots"].points)[:, :2],
                               tab.arena.to_view(s.frames[5].x[:, :2])[:, :2], atol=1e-5)
    np.testing.assert_allclose(np.asarray(twin.points)[:, :2], tab.arena.to_view(s.twin.frames[5].x[:, :2])[:, :2],
                               atol=1e-5)


def test_hand_edits_reach_b_too():
    """An obstacle dropped in A's world, or a dragged source, is where B meets it as well."""
    s = session("course-dvc")
    s.enable_compare({"controller.alpha": 0.9})
    s.step(3)
    x = s.sim.world.bounds[2] - 5.0
    fleet.driver(s).add_obstacle(x, 0.0, 1.0)
    np.testing.assert_array_equal(s.twin.sim.world.circles, s.sim.world.circles)
    fleet.driver(s).restore_world()
    np.testing.assert_array_equal(s.twin.sim.world.circles, s.sim.world.circles)
    acoustic = session("sonar-xb-pso")
    acoustic.enable_compare({"acoustics.algorithm": "x-pso"})
    sonar.driver(acoustic).move_source(12.0, -30.0)
    np.testing.assert_array_equal(acoustic.twin.sim.state.source[0], [12.0, -30.0])
