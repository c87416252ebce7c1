"""Prediction rounds (issue 31 §4): the lecturer asks, every class tab answers once (and may change
its answer until the round closes), the lecturer sees the count and the distribution live and
reveals them; every tab then sees the distribution and the answer, and the run plays.

The rules of :class:`Rounds` in process; then the whole round over viser's raw websocket,
hostile answers included (refused by name), and answers from tabs that are not watchers (not
taken); the CSV is a download in the lecturer's tab and nothing is written on the server.
"""

from __future__ import annotations

import csv
import io
import math
import os
import time

import pytest
from viser import _messages

from shoal.app.hall import round_view
from shoal.app.hall.class_panel import KINDS, lesson_question
from shoal.app.hall.command import start_lecture
from shoal.app.hall.rounds import MAX_NUMBER, MIN_SECONDS_BETWEEN, Question, Refused, Rounds
from shoal.app.lessons import library

from browser.browser_helpers import wait_until
from hall_helpers import lecturer, watcher
from viser_wire import WireClient


def test_a_watcher_answers_once_and_may_change_it_until_the_round_closes():
    rounds = Rounds()
    rounds.open(Question.choice("Inside or outside?", ["inside", "outside"], "inside"))
    assert rounds.answer("a", "A") == "inside"
    time.sleep(MIN_SECONDS_BETWEEN)
    assert rounds.answer("a", "B") == "outside"  # changed: counted once, the last one
    rounds.answer("b", "B")
    r = rounds.current
    assert r is not None and r.counts() == [("A. inside", 0), ("B. outside", 2)]
    rounds.close()
    with pytest.raises(Refused, match="closed"):
        rounds.answer("c", "A")
    rounds.reveal()
    assert r.state == "revealed"
    rows = list(csv.reader(io.StringIO(rounds.csv().decode())))
    assert rows[0] == ["round", "question", "answer", "time"]
    assert [row[:3] for row in rows[1:]] == [["1", "Inside or outside?", "outside"]] * 2
    assert all("a" not in row[3:] and "b" not in row[3:] for row in rows[1:])  # no key of who answered


@pytest.mark.parametrize("value, why", [
    (math.nan, "finite"), (math.inf, "finite"), (-math.inf, "finite"), (MAX_NUMBER * 10, "beyond"),
    ("12", "expected a number"), (True, "expected a number"), (None, "expected a number"), ([1], "expected a number"),
])
def test_a_number_round_refuses_what_no_page_sends_by_name(value, why):
    rounds = Rounds()
    rounds.open(Question.number("How many steps?", "steps", 300))
    with pytest.raises(Refused, match=why):
        rounds.answer("a", value)
    assert rounds.current is not None and rounds.current.answers == {}


def test_repeated_answers_are_paced_and_a_choice_must_be_one_of_the_buttons():
    rounds = Rounds()
    rounds.open(Question.choice("Which?", ["x", "y", "z"]))
    for bad in ("D", "a", "", "A" * 10_000, 0, None):
        with pytest.raises(Refused, match="not one of A, B, C"):
            rounds.answer("a", bad)
    rounds.answer("a", "C")
    with pytest.raises(Refused, match="too many answers"):
        rounds.answer("a", "A")
    assert rounds.mine("a") == "z"


@pytest.mark.parametrize("make, why", [
    (lambda: Question.choice("", ["a", "b"]), "question: missing"),
    (lambda: Question.choice("q", ["a"]), "2 to 6"),
    (lambda: Question.choice("q", ["a", "a"]), "the same"),
    (lambda: Question.choice("q", ["a", "b"], "c"), "not one of the choices"),
    (lambda: Question.choice("q" * 601, ["a", "b"]), "at most 600"),
    (lambda: Question.number("q", "s", math.nan), "finite"),
])
def test_a_bad_question_is_refused_naming_the_field(make, why):
    with pytest.raises(Refused, match=why):
        make()


def test_every_lesson_question_can_be_asked_of_a_class():
    """Each step of every shipped lesson has a round, and it makes a valid question."""
    lessons, problems = library.shipped()
    assert not problems
    asked = 0
    for lesson in lessons.values():
        for i, step in enumerate(lesson.steps):
            assert step.round is not None, f"{lesson.id} step {i + 1} '{step.title}' has no round"
            q = lesson_question(lesson, i)
            assert q.answer is not None, f"{lesson.id} step {i + 1}: a lesson's round says its answer"
            asked += 1
    assert asked >= 40


def test_the_class_sees_only_the_count_until_the_round_is_revealed():
    rounds = Rounds()
    rounds.open(Question.choice("Which <b>one</b>?", ["inside", "outside"], "outside"))
    rounds.answer("a", "B")
    rounds.answer("b", "A")
    r = rounds.current
    open_html = round_view.class_html(r)
    assert "2 answers so far" in open_html and "%" not in open_html and "&lt;b&gt;one&lt;/b&gt;" in open_html
    rounds.close()
    rounds.reveal()
    shown = round_view.class_html(r)
    assert "50 %" in shown and "Answer: outside" in shown and "✓" in shown
    assert all(f"font-size:{px}px" not in shown for px in range(1, 16))  # nothing smaller than 16 px


def _answer(c: WireClient, label: str, value) -> None:
    c.send(_messages.GuiUpdateMessage(c.wait_uuid(label), {"value": value}))


def _html_of(c: WireClient) -> list[str]:
    """Every content given to an HTML element of the page, in order."""
    ids = {m["uuid"] for m in c.gui if m.get("type") == "GuiHtmlMessage"}
    out = []
    for m in c.gui:
        fields = m.get("props") if m.get("type") == "GuiHtmlMessage" else (
            m.get("updates") if m.get("type") == "GuiUpdateMessage" and m.get("uuid") in ids else None)
        out += [str(v) for k, v in (fields or {}).items() if k == "content" and v]
    return out


def test_a_round_on_the_wire_from_the_lesson_to_the_reveal(tmp_path):
    cwd = os.getcwd()
    os.chdir(tmp_path)  # (nothing may be written here: the CSV is a download)
    srv = start_lecture("default", port=0)
    try:
        boss = lecturer(srv)
        a, b, hostile = watcher(srv), watcher(srv), watcher(srv)
        wait_until(lambda: boss.uuid_of("Ask the class") and boss.uuid_of("lesson"), what="the Lessons tab")
        s = srv.lecture.session
        s.pause()
        boss.send(_messages.GuiUpdateMessage(boss.wait_uuid("Ask the class"), {"value": True}))  # step 1's question
        wait_until(lambda: a.uuid_of("your answer") and b.uuid_of("your answer"), what="the answer buttons")
        r = srv.rounds.current
        assert r is not None and r.question.kind == "choice" and r.question.source.startswith("Ch. 3")
        _answer(a, "your answer", "A")
        _answer(b, "your answer", "B")
        time.sleep(MIN_SECONDS_BETWEEN + 0.05)
        _answer(b, "your answer", "A")  # changed its mind
        # hostile answers, each refused by name, none counted
        for value, why in (("Z", "not one of the choices"), (float("nan"), "expected text"),
                           (2 ** 63, "expected text"), ("A" * 50_000, "not one of the choices"),
                           (True, "expected text"), ([1, 2], "expected text")):
            _answer(hostile, "your answer", value)
            wait_until(lambda why=why: any(why in body for _, body, _ in hostile.notifications()), what=why)
        wait_until(lambda: len(r.answers) == 2, what="two answers")
        assert [c for _, c in r.counts()][:2] == [2, 0]
        # a tab that is not a watcher sends an answer with a watcher's button id: not taken
        solo = WireClient(srv.port, decode=True, path=f"/p/{srv.desk.issue_plain()}")
        wait_until(lambda: solo.uuid_of("playback"), what="a private tab")
        solo.send(_messages.GuiUpdateMessage(a.wait_uuid("your answer"), {"value": "B"}))
        boss.send(_messages.GuiUpdateMessage(a.wait_uuid("your answer"), {"value": "B"}))
        time.sleep(0.5)
        assert len(r.answers) == 2 and [c for _, c in r.counts()][:2] == [2, 0]
        # the lecturer sees count and distribution live; the class only the count
        wait_until(lambda: any("2 answers" in h and "100 %" in h for h in _html_of(boss)), what="the live results")
        assert not any("%" in h for h in _html_of(a))
        assert any("2 answers so far" in h for h in _html_of(a))
        boss.send(_messages.GuiUpdateMessage(boss.wait_uuid("round"), {"value": "Reveal and play"}))
        for c in (a, b, hostile):
            wait_until(lambda c=c: any("Answer: " in h and "100 %" in h for h in _html_of(c)), what="the reveal")
        assert s.playing  # the run plays out on every screen
        wait_until(lambda: a.saw("✓") or a.saw("not the answer"), what="a watcher told how it did")
        # a number round from the lecturer's own question, then the CSV as a download
        boss.set_value("question", "How many seconds until the swarm settles?")
        boss.set_value("answer with", KINDS[1])
        boss.set_value("unit", "s")
        boss.set_value("right answer", "12.5")
        time.sleep(0.3)
        boss.send(_messages.GuiUpdateMessage(boss.wait_uuid("Open round"), {"value": True}))
        wait_until(lambda: srv.rounds.current is not r, what="the number round")
        wait_until(lambda: a.uuid_of("your answer [s]"), what="the number box")
        a.set_value("your answer [s]", 11.0)
        time.sleep(0.2)
        _answer(a, "Answer", True)
        hostile.set_value("your answer [s]", 1e300)
        time.sleep(0.2)
        _answer(hostile, "Answer", True)
        wait_until(lambda: any("more than its largest value" in body for _, body, _ in hostile.notifications()),
                   what="a huge number refused by the box's range")
        # (the box kept the value in force, 0, and Answer sends what it shows)
        wait_until(lambda: len(srv.rounds.current.answers) == 2, what="the number answers")
        boss.send(_messages.GuiUpdateMessage(boss.wait_uuid("Download answers (CSV)"), {"value": True}))
        wait_until(lambda: any(n.startswith("shoal-rounds-") and n.endswith(".csv") for n in boss.downloads),
                   what="the CSV download")
        rows = list(csv.reader(io.StringIO(srv.rounds.csv().decode())))
        assert [row[2] for row in rows[1:]] == ["Inside", "Inside", "11 s", "0 s"], rows
        assert os.listdir(tmp_path) == []
        for c in (boss, a, b, hostile, solo):
            c.close()
    finally:
        srv.stop()
        os.chdir(cwd)


@pytest.mark.parametrize("hostile", ['<img src=x onerror=alert(1)>', "<script>alert(1)</script>",
                                     '"><iframe srcdoc="<script>parent.x=1</script>">', "</div><div onclick=x>"])
def test_a_hostile_question_shows_as_text_in_every_view_of_a_round(hostile):
    """A question, its choices and its unit are the lecturer's typing (or a lesson's): on every
    screen they are text, never markup."""
    rounds = Rounds()
    rounds.open(Question.choice(hostile, [hostile, "b" + hostile], hostile))
    rounds.answer("a", "A")
    views = [round_view.class_html(rounds.current), round_view.lecturer_html(rounds.current)]
    rounds.close()
    rounds.reveal()
    views += [round_view.class_html(rounds.current), round_view.lecturer_html(rounds.current)]
    rounds.open(Question.number(hostile, hostile[:24], 3.0))
    rounds.answer("a", 2.0)
    rounds.reveal()
    views += [round_view.class_html(rounds.current), round_view.lecturer_html(rounds.current)]
    for v in views:
        assert hostile not in v and "<script" not in v and "<img" not in v and "<iframe" not in v, v
