"""Control feedback comes first (app/tab.py): after a control event the scene waits a moment
while the control's answer is already there, and a big swarm redraws less often so that a
slow page keeps up. Driven by hand ticks (the tick's own clock, never wall-clock time)."""

from __future__ import annotations

from shoal.app.tab import TabApp, scene_points


def _count_draws(tab) -> list[int]:
    draws = [0]
    draw = tab.arena.draw

    def counted(snap):
        draws[0] += 1
        return draw(snap)
    tab.arena.draw = counted
    return draws


def test_after_a_control_event_the_scene_waits_and_the_answer_is_there_first(tab):
    s = tab.session
    s.play()
    tab.tick(1.0)
    tab.tick(1.2)
    assert tab.arena.drawn_revision == s.revision
    tab.panels.press("Pause")
    tab.panels.press("Step")  # the robots move...
    assert "paused" in tab.panels.status.content  # ...and the status answered at once
    tab.tick(1.25)
    tab.tick(1.25 + 0.9 * TabApp.CONTROL_HOLD)
    assert tab.arena.drawn_revision != s.revision  # the scene waits while controls move
    tab.panels.handles["view.trail_seconds"].value = 3.0  # a dragged slider: the wait starts again
    tab.tick(1.25 + 1.5 * TabApp.CONTROL_HOLD)
    assert tab.arena.drawn_revision != s.revision
    tab.tick(1.25 + 3.0 * TabApp.CONTROL_HOLD)
    assert tab.arena.drawn_revision == s.revision  # then the scene follows


def test_a_big_swarm_redraws_less_often_than_a_small_one(tab):
    counts = {}
    for robots in (20, 1000):
        tab.session.apply({"sim.robots": robots, "view.steps_per_second": 30.0})
        tab.session.play()
        tab.tick(10.0)
        draws = _count_draws(tab)
        for i in range(1, 121):  # 2 s of ticks at 60 Hz, one step each
            tab.tick(10.0 + i / 60.0)
        counts[robots] = draws[0]
        snap = tab.session.snapshot()
        assert scene_points(snap) >= robots
    assert counts[20] >= 50  # ~30 redraws a second
    assert counts[1000] <= 25  # ~10: 1000 robots and their trails are ~4,000 points a redraw
