"""One run lifecycle for every scene kind: a scene opens playing, Reset starts again with the
current values and keeps playing, the last step stops, loops or runs on (the header's *at the
end*), a finished run starts again on Play, Step or a changed control, and the status never
shows a step beyond the last one over it. Driven through the real panels of a hand-ticked tab.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from shoal.app.kinds.registry import session_for
from shoal.app.session.lifecycle import LOOP, RUN_ON, STOP, Lifecycle, at_end_choice, at_end_label
from shoal.presets import io as presets_io
from shoal.presets.kinds import kind_for
from shoal.testing import live_change, variant_presets

# one preset of every kind of scene a tab tells apart (each robot cap of each registered kind), with
# a change of a live field it takes without a rebuild (shoal.testing)
KINDS = {name: live_change(kind_for(sc), sc) for name, sc in ((p, presets_io.load(p)) for p in variant_presets())}
OPENED_PAUSED = ("standard-pso", "course-nonomni", "course-physics", "slo-pso-sphere")


def _short(tab, steps: int = 6) -> None:
    """Make the tab's run ``steps`` long (through the model, as any change)."""
    assert tab.panels.apply({"sim.steps": steps}, "steps")


def _status(tab) -> str:
    tab.panels.refresh_status()
    return tab.panels.status.content


@pytest.mark.parametrize("preset", OPENED_PAUSED + ("default", "sonar-gt-pso", "slo-walk"))
def test_every_preset_opens_playing_from_the_dropdown_even_after_a_finished_run(tab, preset):
    _short(tab)
    tab.session.play()
    tab.session.step(10)
    assert tab.session.finished and not tab.session.playing
    assert tab.panels.load_preset(preset)
    assert tab.session.scenario.name == preset and tab.session.playing


def test_a_paused_scene_switched_to_another_kind_opens_playing(tab):
    tab.session.pause()
    tab.panels.load_preset("course-physics")
    assert tab.session.engine_name == "Fleet" and tab.session.playing
    tab.session.pause()
    tab.panels.load_preset("slo-pso-sphere")
    assert tab.session.engine_name == "SLOSwarm" and tab.session.playing


def test_a_lessons_set_up_keeps_its_scene_paused_at_step_0(tab):
    s = tab.session
    s.play()
    load = s.load_scenario
    seen: list[bool] = []

    def spy(scenario, **kw):  # the ticker could step the moment the scene is in: is it playing then?
        load(scenario, **kw)
        seen.append(s.playing)
    s.load_scenario = spy
    assert tab.panels.set_up_lesson("standard-pso", {}) == []
    assert seen == [False]  # loaded paused, not paused afterwards
    assert tab.session is s and not s.playing and s.k == 0
    assert tab.panels.set_up_lesson("course-dvc", {}) == []  # another kind: a new session, paused too
    assert tab.session is not s and not tab.session.playing and tab.session.k == 0


@pytest.mark.parametrize("preset", list(KINDS))
def test_reset_starts_again_with_the_current_values_and_keeps_playing(tab, preset):
    tab.panels.load_preset(preset)
    s = tab.session
    s.step(12)
    assert tab.panels.apply(KINDS[preset], "a live change")
    s.step(3)
    tab.panels.press("Reset")
    s = tab.session
    assert s.k == 0 and s.playing
    fresh = session_for(s.scenario)  # a new engine of the values in force
    s.step(8)
    fresh.step(8)
    assert np.allclose(s.sim.state.x, fresh.sim.state.x, equal_nan=True)


def test_reset_of_a_paused_run_stays_paused_and_of_a_finished_run_plays(tab):
    s = tab.session
    s.step(3)
    s.pause()
    tab.panels.press("Reset")
    assert s.k == 0 and not s.playing
    _short(tab)
    s.play()
    s.step(20)
    assert s.finished
    tab.panels.press("Reset")
    assert s.k == 0 and s.playing and not s.finished


@pytest.mark.parametrize("preset", list(KINDS))
def test_stop_at_the_last_step_finishes_and_play_starts_again(tab, preset):
    tab.panels.load_preset(preset)
    _short(tab)
    s = tab.session
    tab.tick(0.0)
    for i in range(1, 40):  # the ticker plays it out at 20 steps/s
        tab.tick(i * 0.1)
    assert s.k == 6 and s.finished and not s.playing
    status = _status(tab)
    assert "6/6" in status and "finished" in status and "7/6" not in status
    tab.panels.press("Step")  # never step 7/6: a finished run starts again
    assert s.k == 1 and not s.playing
    s.step(10)
    tab.panels.press("Play")
    assert s.playing and s.k == 0


def test_a_changed_control_starts_a_finished_run_again_with_its_value(tab):
    s = tab.session
    _short(tab)
    s.play()
    s.step(10)
    assert s.finished
    tab.panels.handles["controller.mode"].value = "raw"
    assert s.k == 0 and s.playing and s.scenario.controller.mode == "raw"
    s.step(10)
    tab.panels.handles["controller.omega"].value = 0.55  # a change the running engine takes
    assert s.k == 0 and s.playing and s.sim.policy.omega == pytest.approx(0.55)
    s.step(10)
    tab.panels.handles["view.steps_per_second"].value = 40.0  # the view alone: still finished
    assert s.finished and not s.playing


def test_loop_starts_again_at_the_last_step_and_keeps_playing(tab):
    s = tab.session
    _short(tab)
    tab.panels.at_end.value = at_end_label(LOOP, 6)
    assert s.at_end == LOOP
    s.play()
    ks = []
    for _ in range(15):
        s.step(1)
        ks.append(s.k)
    assert ks == [1, 2, 3, 4, 5, 6, 1, 2, 3, 4, 5, 6, 1, 2, 3] and s.playing and not s.finished
    fresh = session_for(s.scenario)
    fresh.step(3)
    assert np.array_equal(s.sim.state.x, fresh.sim.state.x)  # each lap is the same run


def test_run_on_passes_the_last_step_and_says_so(tab):
    s = tab.session
    _short(tab)
    tab.panels.at_end.value = at_end_label(RUN_ON, 6)
    s.play()
    assert s.step(10) == 10 and s.k == 10 and s.playing
    status = _status(tab)
    assert "step 10 (on past 6)" in status and "/6" not in status
    tab.panels.at_end.value = at_end_label(STOP, 6)  # past the end, told to stop there: finished
    assert s.finished and not s.playing


def test_the_end_rule_outlives_a_switch_to_another_kind(tab):
    tab.panels.at_end.value = at_end_label(RUN_ON, tab.session.scenario.sim.steps)
    tab.panels.load_preset("sonar-xb-pso")
    assert tab.session.at_end == RUN_ON
    assert tab.panels.at_end.value == RUN_ON


def test_the_at_end_labels_follow_the_presets_steps(tab):
    _short(tab, 9)
    assert tuple(tab.panels.at_end.options) == ("stop at step 9", "loop", "run on")
    assert tab.panels.at_end.value == "stop at step 9"
    assert not tab.panels.choose_at_end("stop at step 10")
    assert tab.messages[-1][0].startswith("Refused") and tab.session.at_end == STOP


def test_a_pause_between_the_steps_of_a_tick_stops_the_rest(tab):
    s = tab.session
    s.apply({"view.steps_per_second": 240.0})
    s.play()
    tab.tick(10.0)
    calls = []
    before = s.driver.before_step

    def pause_after_first() -> None:  # Pause pressed while the ticker is inside its batch
        calls.append(s.k)
        if len(calls) == 1:
            tab.panels.press("Pause")
        before()

    s.driver.before_step = pause_after_first
    k0 = s.k
    tab.tick(10.1)  # 24 steps due
    assert s.k == k0 + 1 and not s.playing and len(calls) == 1


def test_a_pause_from_another_thread_does_not_wait_for_the_step_in_hand(tab):
    """The ticker holds the session's lock through a step; a Pause pressed meanwhile (viser's
    thread) takes effect at once, and the tick takes no further step."""
    s = tab.session
    s.apply({"view.steps_per_second": 240.0})
    s.play()
    tab.tick(10.0)
    in_step, paused = threading.Event(), threading.Event()
    held: list[bool] = []
    before = s.driver.before_step

    def slow_step() -> None:
        if not in_step.is_set():
            in_step.set()
            held.append(paused.wait(timeout=20.0))  # the step in hand waits for the Pause
        before()

    s.driver.before_step = slow_step
    k0 = s.k
    ticker = threading.Thread(target=tab.tick, args=(10.1,))  # 24 steps due
    ticker.start()
    assert in_step.wait(timeout=20.0)
    s.pause()
    paused.set()
    ticker.join()
    assert held == [True]  # the Pause went through while the step was in hand
    assert s.k == k0 + 1 and not s.playing


def test_swarm_b_runs_on_and_loops_with_a(tab):
    s = tab.session
    _short(tab)
    tab.panels.at_end.value = at_end_label(RUN_ON, 6)
    s.enable_compare({"controller.U": 5.0})
    s.play()
    s.step(9)
    assert s.k == 9 and s.twin.k == 9
    tab.panels.at_end.value = at_end_label(LOOP, 6)
    s.step(1)
    assert s.k == 1 and s.twin.k == 1


def test_lifecycle_rules():
    life = Lifecycle()
    assert life.at_last(5, 6) == "go" and life.at_last(6, 6) == "stop" and life.finished(6, 6)
    life.choose(LOOP)
    assert life.at_last(6, 6) == "restart" and not life.finished(6, 6)
    life.choose(RUN_ON)
    assert life.at_last(60, 6) == "go" and life.progress(60, 6) == "step 60 (on past 6)"
    assert life.progress(6, 6, "gen") == "gen 6/6"
    with pytest.raises(ValueError, match="at the end"):
        life.choose("explode")
    assert at_end_choice("stop at step 6", 6) == STOP and at_end_choice("stop at step 7", 6) is None


def test_a_shared_page_of_a_run_that_ran_on_has_every_step(tab):
    from shoal.app.share.draw import run_frames
    from shoal.app.share.frames import FramePlan

    s = session_for(presets_io.load("default", ["sim.steps=5"]))
    plan = FramePlan(first=0, last=8, stride=1, steps=(0, 3, 8))
    assert [snap.k for snap in run_frames(s, plan)] == [0, 3, 8]
