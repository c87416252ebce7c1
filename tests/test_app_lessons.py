"""The Lessons tab without a browser: its handles are driven by assigning ``.value`` (their
callbacks run in the test thread) on a real viser server, as in ``test_app_session.py``."""

from __future__ import annotations

import pytest

from shoal.app.lessons import parse_lesson, readings
from shoal.app.lessons.chooser import paths
from shoal.app.lessons.panel import NAV, LessonProgress, LessonsPanel
from shoal.app.lessons.verify import run_metrics

APP_PRESET = "default"


def _label(panel, word: str) -> str:
    return next(label for label in panel.lesson_menu.options if word in label)


def _open(tab, word: str):
    lessons = tab.panels.lessons
    lessons.lesson_menu.value = _label(lessons, word)
    return lessons


def test_every_kind_of_panel_has_a_lessons_tab(tab):
    labels = [t._label for t in tab.panels.tabs._tab_handles]
    assert labels[labels.index("Controller") + 2:] == ["Lessons", "Sweep"]  # the chapter's notes are in Lessons
    assert tab.panels.notes.content.startswith("#")
    lessons = tab.panels.lessons
    assert lessons.progress is tab.lesson_progress
    assert len(lessons.lesson_menu.options) >= 8
    assert lessons.step_text.content.startswith("#### Step 1 of ")
    assert lessons.answer.visible is False


def test_set_up_loads_the_steps_scene_through_the_model_and_pauses(tab):
    tab.session.play()
    lessons = _open(tab, "blow up")
    lessons.nav.value = NAV[1]
    lessons.nav.value = NAV[1]  # step 3: ω = 1.1 with the standard law
    assert lessons.progress.step == 2 and "An inertia weight above 1" in lessons.step_text.content
    assert "controller.omega = 1.1" in lessons.setup_text.content
    lessons.setup_button.value = True
    s = tab.session
    c = s.scenario.controller
    assert (s.scenario.name, c.law, c.omega) == ("standard-pso", "standard", 1.1)
    assert s.sim.policy.omega == 1.1 and s.sim.state.k == 0 and not s.playing
    assert tab.panels.handles["controller.omega"].value == 1.1  # the panel follows
    title, body, color = tab.messages[-1]
    assert (title, color) == ("Set up step 3: An inertia weight above 1", "green") and "Press Play" in body
    s.play()
    for _ in range(60):
        s.step(1)
    assert s.readout()["outside"] == 20  # what the step says: every robot leaves the arena


def test_the_answer_is_revealed_on_demand(tab):
    lessons = tab.panels.lessons
    assert not lessons.answer.visible and lessons.answer_button.label == "Show answer"
    lessons.answer_button.value = True
    assert lessons.answer.visible and lessons.answer.content.startswith("**Answer:** ")
    assert lessons.answer_button.label == "Hide answer"
    lessons.nav.value = NAV[1]  # a new step starts hidden
    assert not lessons.answer.visible and not lessons.progress.revealed


def test_the_last_page_lists_the_ideas_and_back_returns(tab):
    lessons = _open(tab, "Designing from the robot")
    n = len(lessons.lesson.steps)
    for _ in range(n + 3):  # past the end stays on the last page
        lessons.nav.value = NAV[1]
    assert lessons.progress.step == n and lessons.step_text.content.startswith("#### Try it yourself")
    assert not any(h.visible for h in (lessons.setup_button, lessons.question, lessons.answer_button))
    lessons.nav.value = NAV[0]
    assert lessons.progress.step == n - 1 and lessons.question.visible and lessons.setup_button.visible


def test_a_set_up_of_another_kind_rebuilds_the_panels_and_keeps_the_place(tab):
    old = _open(tab, "obstacles")
    old.nav.value = NAV[1]
    old.answer_button.value = True
    old.setup_button.value = True  # Adapted RPSO on the obstacle course: a fleet
    assert tab.panels.name == "fleet" and tab.session.scenario.name == "course-adapted-c3-equal"
    assert old.closed and not tab.lesson_progress.focus
    new = tab.panels.lessons
    assert new is not old and new.progress.lesson == "04-dvc" and new.progress.step == 1
    assert new.answer.visible and "Adapted RPSO, little avoidance" in new.step_text.content
    labels = [t._label for t in tab.panels.tabs._tab_handles]
    assert labels[0] == "Lessons"  # the rebuilt tab group opens on its first tab: the lesson stays in view
    assert tab.session.scenario.controller.c3 == pytest.approx(0.5728) and not tab.session.playing
    old._handle(old._move, 1)  # a click on the old panel still in flight when it went changes nothing
    assert new.progress.step == 1



def test_a_swapped_out_panel_is_hidden_at_once_and_removed_a_moment_later(tab):
    """The page applies a batch's GUI updates after its removals: the old panel gets no update
    once it is swapped out, and its handles go only when its last updates have landed."""
    old = tab.panels
    lessons = _open(tab, "obstacles")
    lessons.setup_button.value = True  # a fleet: the panels are swapped
    assert tab.panels is not old and old.removed
    status = old.status
    assert all(not h.visible for h in old.top) and not status._impl.removed
    tab.tick(5.0)  # not yet: their last updates may still be on their way
    assert not status._impl.removed and old.top
    tab._retired[0] = (0.0, old)  # (as RETIRE_SECONDS later)
    tab.tick(6.0)
    assert status._impl.removed and not old.top and not tab._retired


def test_the_chooser_walks_to_a_leaf_and_opens_its_scene(tab):
    lessons = tab.panels.lessons
    tree = lessons.tree
    path = paths(tree)["x-pso"][0]
    assert "Which algorithm" not in lessons.chooser_text.content and tree.about in lessons.chooser_text.content
    for choice in path:
        assert lessons.choice_buttons[choice].visible
        lessons.choice_buttons[choice].value = True
    assert lessons.progress.choices == path
    assert "#### X-PSO" in lessons.chooser_text.content and lessons.open_button.visible
    assert lessons.open_button.label == "Open sonar-x-pso"
    assert not any(b.visible for b in lessons.choice_buttons)
    lessons.chooser_nav.value = "◀ Back"
    assert lessons.progress.choices == path[:-1] and not lessons.open_button.visible
    lessons.choice_buttons[path[-1]].value = True
    lessons.open_button.value = True
    assert tab.panels.name == "sonar" and tab.session.scenario.acoustics.algorithm == "x-pso"
    again = tab.panels.lessons
    assert again.progress.choices == path and again.open_button.visible  # the rebuilt panel is where it was
    again.chooser_nav.value = "Start over"
    assert again.progress.choices == [] and tree.about in again.chooser_text.content


BAD = '''+++
title = "Bad on purpose"
chapter = "3"
summary = "Its scene is refused by the app."
+++

## Too many robots

```setup
preset = "default"
sim.robots = 5000
```

Text.

**Do:** press Set up.

**Question:** what happens?

**Answer:** a refusal.

## Try it yourself

- nothing
'''


def test_a_refused_set_up_says_why_and_changes_nothing(tab):
    before = tab.session.scenario
    gui = tab.gui
    with gui.add_folder("test lessons") as folder:
        panel = LessonsPanel(gui, tab.panels.set_up_lesson, tab.notify, LessonProgress(),
                             lessons={"bad": parse_lesson(BAD, "bad")})
    panel.setup_button.value = True
    title, body, color = tab.messages[-1]
    assert (title, color) == ("Refused: lesson set-up", "red")
    assert "sim.robots = 5000: the browser app runs at most 2000 robots" in body
    assert tab.session.scenario is before and tab.panels.name == "swarm"
    folder.remove()


def test_the_panel_needs_only_a_gui_and_two_callbacks(server):
    """Mounted on its own (the app's new layout will do that), with stand-in callbacks."""
    calls, toasts = [], []
    gui = server.viser.gui
    with gui.add_folder("standalone") as folder:
        panel = LessonsPanel(gui, lambda preset, values: calls.append((preset, values)) or [],
                             lambda *toast: toasts.append(toast))
    panel.lesson_menu.value = _label(panel, "escorting")
    panel.setup_button.value = True
    assert calls == [("escort-stationary", {"view.steps_per_second": 100.0})] and toasts[-1][2] == "green"
    panel.nav.value = NAV[1]
    panel.setup_button.value = True
    assert calls[-1] == ("escort-stationary", {"view.steps_per_second": 100.0, "sim.robots": 10})
    folder.remove()


def test_a_steps_numbers_are_read_out_under_its_question(tab):
    """Set up, Play: the numbers the step's check names follow the run shown, as the headless
    check computes them; another scene on screen says so instead of showing numbers."""
    lessons = _open(tab, "sideways")  # Ch. 5, step 1: the mean speed over steps 100–300
    assert lessons.readings.visible and "another scene than this step's" in lessons.readings.content
    lessons.setup_button.value = True
    lessons = tab.panels.lessons  # a fleet: the panels were built again
    s = tab.session
    assert s.scenario.name == "open-nonomni" and s.k == 0
    assert "(the run shown, at step 0)" in lessons.readings.content
    assert "mean over steps 100–300 (from step 100)" in lessons.readings.content
    s.advance(150)
    tab.tick(1.0)
    assert "mean robot speed [m/s], mean over steps 100–150 so far (of 100–300)" in \
        lessons.readings.content
    s.advance(150)
    tab.tick(2.0)
    (preset, values), check = readings.step_check(lessons.lesson, 0)
    want = readings.headless(check, run_metrics(preset, values, check.steps))
    for r in want:
        assert f"{r.label}, {r.span}: **{r.shown}**" in lessons.readings.content
    tab.panels.apply({"sim.robots": 12}, "robots")
    tab.tick(3.0)
    assert "another scene than this step's" in lessons.readings.content
    lessons.nav.value = NAV[1]
    lessons.nav.value = NAV[1]
    lessons.nav.value = NAV[1]
    lessons.nav.value = NAV[1]  # the last page: nothing to read
    assert not lessons.readings.visible
