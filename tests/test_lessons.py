"""Lesson files: the format, the loader's messages for bad files, and that every shipped lesson
reads, names only scenes the preset model and the app accept, and passes its checks."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from shoal.app.kinds.registry import kind_for
from shoal.app.lessons import LessonError, library, parse_lesson, quotes, readings
from shoal.app.lessons.library import read_lesson, shipped
from shoal.app.lessons.model import Check
from shoal.app.lessons.readings import Run, format_value
from shoal.app.lessons.scenes import describe, load_scene, overrides, scene_errors, toml_literal
from shoal.app.lessons.verify import check_failures, lesson_check_failures, run_metrics
from shoal.app.panel.lesson_run import NOT_THIS_SCENE, LessonRun
from shoal.presets.io import PresetError, parse_value

GOOD = '''+++
title = "A small lesson"
chapter = "3"
summary = "Two steps."
+++

An introduction.

## First

```setup
preset = "standard-pso"
controller.omega = 0.6
sim = { robots = 12 }

[check]
steps = 20
final.omega = [0.6, 0.6]
```

Some sentences.

**Do:** press Play.

**Question:** what happens?

**Answer:** it settles.

Over two paragraphs.

## Second

```setup
controller.c2 = 1.3
```

More sentences.

**Do:** look.

**Question:** and now?

**Answer:** the same.

## Third, on the scene as it is

Text.

**Do:** drag ω.

**Question:** why?

**Answer:** because.

## Try it yourself

- one idea
  over two lines
- another idea
'''


def _messages(text: str, lesson_id: str = "bad") -> list[str]:
    with pytest.raises(LessonError) as err:
        parse_lesson(text, lesson_id)
    return err.value.messages


# ---------------------------------------------------------------------------- the format
def test_a_lesson_file_reads_into_steps_scenes_and_ideas():
    lesson = parse_lesson(GOOD, "small")
    assert (lesson.id, lesson.title, lesson.chapter, lesson.intro) == ("small", "A small lesson", "3",
                                                                      "An introduction.")
    assert [s.title for s in lesson.steps] == ["First", "Second", "Third, on the scene as it is"]
    first = lesson.steps[0]
    assert first.text == "Some sentences."
    assert (first.instruction, first.question) == ("press Play.", "what happens?")
    assert first.answer == "it settles.\n\nOver two paragraphs."
    assert first.setup.values == {"controller.omega": 0.6, "sim.robots": 12}  # dotted keys and tables
    assert first.setup.check.steps == 20 and first.setup.check.final == {"omega": (0.6, 0.6)}
    assert lesson.try_it == ["one idea over two lines", "another idea"]
    assert lesson.label == "Ch. 3 · A small lesson"


def test_a_step_builds_on_the_scene_of_the_step_before():
    lesson = parse_lesson(GOOD, "small")
    assert lesson.scene(0) == ("standard-pso", {"controller.omega": 0.6, "sim.robots": 12})
    assert lesson.scene(1) == ("standard-pso", {"controller.omega": 0.6, "sim.robots": 12, "controller.c2": 1.3})
    assert lesson.scene(2) is None  # no setup: the step works on the scene as it is
    fresh = parse_lesson(GOOD.replace("controller.c2 = 1.3", 'preset = "default"\ncontroller.c2 = 1.3'), "small")
    assert fresh.scene(1) == ("default", {"controller.c2": 1.3})  # naming a preset starts afresh


@pytest.mark.parametrize(
    "change, expected",
    [
        (("+++\ntitle", "title"), "bad.md: must start with a +++ line"),
        (('summary = "Two steps."\n+++', 'summary = "Two steps."'), "bad.md: the header has no closing +++ line"),
        (('chapter = "3"', 'chapter = 3'), "bad.md, chapter: Input should be a valid string"),
        (('title = "A small lesson"\n', ''), "bad.md, title: Field required"),
        (("**Question:** what happens?", ""),
         "bad.md, step 1 'First', question: missing (a paragraph that starts with **Question:**)"),
        (("**Answer:** the same.", "**Answer:** the same.\n\n**Answer:** twice"),
         "bad.md, step 2 'Second': answer: given twice"),
        (("controller.omega = 0.6", "controller.omega = = 0.6"), "bad.md, step 1 'First': setup: TOML syntax"),
        (("controller.c2 = 1.3", "Controller.C2 = 1.3"), "bad.md, step 2 'Second', setup.values.Controller.C2"),
        (('preset = "standard-pso"', 'preset = "../etc/passwd"'),
         "bad.md, step 1 'First', setup.preset: String should match pattern"),
        (("final.omega = [0.6, 0.6]", "final.omega = [0.7, 0.6]"), "final.omega: bounds [0.7, 0.6] are empty"),
        (("final.omega = [0.6, 0.6]", ""), "step 1 'First', setup.check: names no metric"),
        (("steps = 20", "steps = 20\nafter = 30"), "after = 30 is beyond steps = 20"),
        (("## Try it yourself\n\n- one idea\n  over two lines\n- another idea\n", ""),
         "bad.md, try_it: missing (end the lesson with a '## Try it yourself' list)"),
        (('preset = "standard-pso"\n', ''), "step 1 'First': setup names no preset, and no earlier step does"),
    ],
)
def test_a_bad_lesson_file_names_the_lesson_step_and_field(change, expected):
    old, new = change
    assert old in GOOD
    messages = _messages(GOOD.replace(old, new, 1))
    assert any(expected in m for m in messages), messages


def test_two_setup_blocks_in_one_step_are_refused():
    block = '```setup\ncontroller.c2 = 1.3\n```'
    messages = _messages(GOOD.replace(block, block + "\n\n" + block))
    assert messages == ["bad.md, step 2 'Second': has 2 setup blocks; a step sets up one scene"]


def test_a_huge_file_is_refused_before_it_is_parsed():
    assert "characters; a lesson has at most" in _messages(GOOD + "x" * 50_000)[0]


def test_a_bad_shipped_file_is_left_out_and_reported(tmp_path, monkeypatch):
    (tmp_path / "01-good.md").write_text(GOOD, encoding="utf-8")
    (tmp_path / "02-bad.md").write_text(GOOD.replace("+++\n", "", 1), encoding="utf-8")
    (tmp_path / "03-binary.md").write_bytes(b"\xff\xfe+++")
    monkeypatch.setattr(library, "_folder", lambda: tmp_path)
    library.shipped.cache_clear()
    try:
        lessons, problems = library.shipped()
    finally:
        library.shipped.cache_clear()
    assert list(lessons) == ["01-good"]
    assert problems[0].startswith("02-bad.md: must start with a +++ line")
    assert problems[1].startswith("03-binary.md: cannot read")


def test_read_lesson_names_an_unreadable_file(tmp_path):
    with pytest.raises(LessonError, match="missing.md: cannot read"):
        read_lesson(tmp_path / "missing.md")
    path = tmp_path / "mine.md"
    path.write_text(GOOD, encoding="utf-8")
    assert read_lesson(path).id == "mine"


# ---------------------------------------------------------------------------- scenes
@given(st.recursive(
    st.one_of(st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=False),
              st.text(max_size=12)),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=2),
    max_leaves=6))
def test_a_field_value_survives_the_override_string(value):
    back = parse_value(toml_literal(value))
    assert back == value or (isinstance(value, float) and math.isclose(back, value))


def test_a_scene_goes_through_the_preset_model():
    sc = load_scene("standard-pso", {"controller.omega": 1.1, "controller.law": "standard"})
    assert sc.controller.omega == 1.1
    assert overrides({"controller.law": "adapted-sgn", "sim.robots": 5}) == [
        'controller.law="adapted-sgn"', "sim.robots=5"]
    with pytest.raises(PresetError) as err:
        load_scene("standard-pso", {"controller.law": "adapted-sgn", "controller.omega": 1.1})
    assert any(m.startswith("controller:") and "[3.14]" in m for m in err.value.messages)


def test_scene_errors_name_the_lesson_step_and_field():
    bad = GOOD.replace("controller.c2 = 1.3", "controller.c2 = 1000.0\nsim.robots = 100000")
    errors = scene_errors(parse_lesson(bad, "bad"))
    assert any(e.startswith("bad.md, step 2 'Second': standard-pso with") and "controller.c2: Input should be "
               "less than or equal to 100" in e for e in errors), errors


def test_the_app_limits_count_as_refusals():
    bad = GOOD.replace("controller.c2 = 1.3", "sim.robots = 5000")
    errors = scene_errors(parse_lesson(bad, "bad"))
    assert len(errors) == 1 and "sim.robots = 5000: the browser app runs at most" in errors[0]


def test_a_check_reports_what_does_not_hold():
    lesson = parse_lesson(GOOD.replace("final.omega = [0.6, 0.6]", "final.omega = [0.9, 1.0]\n"
                                       "max.max_speed = [0, 1e-9]\nmean.no_such = [0, 1]"), "bad")
    failures = lesson_check_failures(lesson)
    where = "bad.md, step 1 'First' (standard-pso with controller.omega = 0.6, sim.robots = 12)"
    assert any(f.startswith(f"{where}: final.omega should lie in [0.9, 1] at step 20; run 0: 0.6") for f in failures)
    assert any("max.max_speed should lie in [0, 1e-09] over steps 1-20; run 0:" in f for f in failures)
    assert any("mean.no_such: no such metric (this scene has: " in f and "max_speed" in f for f in failures)


def test_run_metrics_counts_robots_outside_the_arena():
    m = run_metrics("standard-pso", {"controller.omega": 1.1}, 60)
    assert m["outside"].shape == (60, 1) and m["outside"][0, 0] == 0 and m["outside"][-1, 0] == 20


# ---------------------------------------------------------------------------- shipped lessons
LESSONS, PROBLEMS = shipped()


def test_every_shipped_lesson_reads():
    assert PROBLEMS == ()
    chapters = {lesson.chapter for lesson in LESSONS.values()}
    assert {"3", "4", "5", "6", "7", "8", "Mai SLO"} <= chapters


@pytest.mark.parametrize("lesson_id", sorted(LESSONS))
def test_every_scene_of_a_shipped_lesson_validates(lesson_id):
    lesson = LESSONS[lesson_id]
    assert scene_errors(lesson) == []
    for i in range(len(lesson.steps)):
        scene = lesson.scene(i)
        if scene is not None:
            kind_for(load_scene(*scene))  # the app has a view for it


CHECKED = [(lid, i) for lid in sorted(LESSONS) for i in range(len(LESSONS[lid].steps))
           if readings.step_check(LESSONS[lid], i) is not None]


@functools.cache
def _headless(lesson_id: str, index: int) -> dict[str, np.ndarray]:
    """The step's scene run headless for its check (shared by the tests below)."""
    (preset, values), check = readings.step_check(LESSONS[lesson_id], index)
    return run_metrics(preset, values, check.steps, check.runs)


@pytest.mark.parametrize("lesson_id, index", CHECKED)
def test_every_check_of_a_shipped_lesson_holds(lesson_id, index):
    """What each step says the student will see, run headless on the step's scene."""
    (preset, values), check = readings.step_check(LESSONS[lesson_id], index)
    where = f"{lesson_id}.md, step {index + 1} ({describe(preset, values)})"
    assert [f"{where}: {m}" for m in check_failures(preset, values, check, _headless(lesson_id, index))] == []


@pytest.mark.parametrize("lesson_id, index", CHECKED)
def test_the_screen_reads_what_the_check_computes(lesson_id, index):
    """Every number a step's check names is read out on the screen the step sets up (the
    Lessons tab's readings of the app's session, run 0) and equals the headless run's."""
    (preset, values), check = readings.step_check(LESSONS[lesson_id], index)
    scenario = load_scene(preset, values)
    session = kind_for(scenario).session(scenario)
    measure = LessonRun(session)
    session.advance(check.steps)
    run = measure(preset, values, readings.names(check))
    assert isinstance(run, Run) and run.k == check.steps
    shown = readings.read(check, run)
    headless = readings.headless(check, _headless(lesson_id, index))
    assert [(r.label, r.span, r.shown) for r in shown] == [(r.label, r.span, r.shown) for r in headless]
    assert all(r.complete and r.value is not None for r in shown)
    session.apply({"sim.seed": scenario.sim.seed + 1})  # another scene than the step's: no numbers
    assert measure(preset, values, readings.names(check)) == NOT_THIS_SCENE


@pytest.mark.parametrize("lesson_id, index", CHECKED)
def test_every_number_an_answer_quotes_agrees_with_the_reading(lesson_id, index):
    """The words of an answer that quote a reading (its check's ``quote``) are in the answer and
    borne out by the reading the step's scene gives, headless (what the screen reads: the test
    above): "about 4 units" is not said of 4.2 as "about 6"."""
    step = LESSONS[lesson_id].steps[index]
    (preset, values), check = readings.step_check(LESSONS[lesson_id], index)
    got = {f"{r.kind}.{r.metric}": r for r in readings.headless(check, _headless(lesson_id, index))}
    answer = " ".join(step.answer.split())
    where = f"{lesson_id}.md, step {index + 1} '{step.title}'"
    for key, words in check.quote.items():
        assert words in answer, f"{where}: the answer does not say {words!r}"
        r = got[key]
        assert quotes.holds(quotes.claim(words), r.value), f"{where}: {words!r} but the screen reads {r.shown}"


PLAY_SECONDS = 60.0  # a step's run reaches its check's last step within this at the speed its Set up sets


@pytest.mark.parametrize("lesson_id, index", CHECKED)
def test_set_up_sets_a_speed_at_which_the_step_is_played_in_a_minute(lesson_id, index):
    (preset, values), check = readings.step_check(LESSONS[lesson_id], index)
    speed = load_scene(preset, values).view.steps_per_second
    seconds = check.steps / speed
    assert seconds <= PLAY_SECONDS, (f"{lesson_id}.md, step {index + 1}: {check.steps} steps at {speed:g} steps/s "
                                     f"take {seconds:.0f} s: set view.steps_per_second")


def test_the_answers_quote_their_readings():
    """Most steps' answers quote a number their check reads, and those numbers are tied to it."""
    quoted = [(lid, i) for lid, i in CHECKED if readings.step_check(LESSONS[lid], i)[1].quote]
    assert len(quoted) >= 30 and {lid for lid, _ in quoted} == set(LESSONS)


def test_a_quote_claims_what_its_words_say():
    c = quotes.claim
    assert quotes.holds(c("about 4 units"), 4.203) and not quotes.holds(c("about 6 units"), 4.203)
    assert quotes.holds(c("Past 10^−25"), 1.1e-30) and not quotes.holds(c("Past 10^−25"), 1e-20)
    assert quotes.holds(c("past 10⁶ m/s"), 2.1e6) and quotes.holds(c("near 10^−5"), 9.2e-6)
    assert quotes.holds(c("about 7 %"), 0.068) and not quotes.holds(c("about 7 %"), 7.0)
    assert quotes.holds(c("2.12 m/s"), 2.121) and not quotes.holds(c("2.12 m/s"), 2.13)
    assert quotes.holds(c("under 10 m/s"), 8.97) and not quotes.holds(c("over 3 m/s"), 2.9)
    with pytest.raises(ValueError):
        c("a few units")


def test_a_quote_of_no_reading_is_refused():
    with pytest.raises(LessonError, match="quote"):
        parse_lesson(GOOD.replace("[check]", '[check]\nquote."mean.nothing" = "about 3"'), "x")


def test_every_step_with_numbers_in_its_answer_is_checked():
    """A step whose scene the student sets up carries a check (the text's numbers stay true)."""
    unchecked = [f"{lid}: {s.title}" for lid, lesson in LESSONS.items() for s in lesson.steps
                 if s.setup is not None and s.setup.check is None]
    assert unchecked == []


def test_check_failures_uses_run_zero_as_the_app_shows_it():
    lesson = LESSONS["03a-stability"]
    scene = lesson.scene(0)
    assert check_failures(*scene, lesson.steps[0].setup.check) == []


# ---------------------------------------------------------------------------- readings
def test_readings_take_the_checks_aggregates_over_the_run_so_far():
    check = Check(steps=10, after=4, final={"collided": (0, 1)}, mean={"mean_speed": (0, 1)},
                  max={"frac_inside_ring": (0, 1)})
    steps = np.arange(0, 7)  # the run is at step 6 of the 10 the check needs
    run = Run(steps, {"collided": np.array([0, 0, 0, 1, 1, 2, 2.0]), "mean_speed": np.arange(7.0),
                      "frac_inside_ring": np.array([0, 0, 0, 0.5, 0.25, 0.125, 0.0])})
    final, top, mean = readings.read(check, run)
    assert (final.span, final.shown, final.complete) == ("at step 6 (of 10)", "2", False)
    assert (top.span, top.shown) == ("highest over steps 4–6 so far (of 4–10)", "25.0 %")
    assert (mean.span, mean.shown) == ("mean over steps 4–6 so far (of 4–10)", "5")
    assert top.label == "share of robots inside the escort ring" and mean.label == "mean robot speed [m/s]"
    assert final.label == "collided robots"
    assert readings.Reading("mean_dist_to_source", "mean", 1, 2, 2, 1.0).label == "mean robot–source distance [m]"
    early = readings.read(check, Run(np.arange(0, 3), {k: v[:3] for k, v in run.metrics.items()}))
    assert early[2].value is None and early[2].span == "mean over steps 4–10 (from step 4)"
    cut = readings.read(check, Run(np.arange(5, 11), {k: np.ones(6) for k in run.metrics}))
    assert cut[0].shown == "1" and cut[2].value is None  # steps 4–10 are no longer all recorded
    text = readings.text(readings.read(check, run), 6)
    assert text.startswith("**Read on screen** <small>(the run shown, at step 6)</small>")
    assert "- mean robot speed [m/s], mean over steps 4–6 so far (of 4–10): **5**" in text


@pytest.mark.parametrize("metric, value, shown", [
    ("com_dist", 223.71, "223.7"), ("frac_inside_ring", 0.0681, "6.8 %"), ("steps_to_converge", -1.0, "not yet"),
    ("steps_to_converge", 285.0, "285"), ("best_so_far", 1.65e-26, "1.65×10⁻²⁶"), ("max_speed", 2.851e7, "2.85×10⁷"),
    ("max_speed", 0.0, "0"), ("max_speed", math.inf, "∞"), ("max_speed", math.nan, "—"), ("outside", 14.0, "14"),
])
def test_a_reading_is_printed_for_a_projector(metric, value, shown):
    assert format_value(metric, value) == shown
