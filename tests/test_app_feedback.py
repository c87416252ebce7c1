"""Control feedback comes first (app/tab.py): after a control event the scene waits a moment
while the control's answer is already there. Driven by hand ticks (the tick's own clock,
never wall-clock time)."""

from __future__ import annotations

from shoal.app.tab import TabApp


def test_after_a_control_event_the_scene_waits_and_the_answer_is_there_first(tab):
    s = tab.session
    tab.control_hold = TabApp.CONTROL_HOLD  # (hand-ticked tabs have none)
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

