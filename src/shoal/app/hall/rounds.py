"""Prediction rounds: the lecturer asks, every class tab answers, then the answer is revealed.

A :class:`Question` is multiple choice (2 to :data:`MAX_CHOICES` choices, shown as A, B, …) or a
number with a unit, with the right answer if there is one. The lecturer opens a :class:`Round`
of it; each watcher answers once and may change its answer until the round closes (its last
answer counts, once); the lecturer sees the count and the distribution as they come, closes the
round and reveals it, and every tab then sees the distribution and the answer.

Answers are anonymous: a round keeps one answer per watcher under a key that means nothing
outside the process (the connection's number), and the CSV the lecturer may download
(:meth:`Rounds.csv`: round, question, answer, time) has no key at all. Nothing is written to
disk: the CSV is a download in the lecturer's tab, made when asked.

:meth:`Rounds.answer` refuses, naming why, anything a watcher's page could not have sent: a value
of the wrong type, not one of the choices, not a finite number, beyond :data:`MAX_NUMBER`, for a
round that is not open, or faster than :data:`MIN_SECONDS_BETWEEN` after the last one.
"""

from __future__ import annotations

import csv
import io
import math
import threading
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Hashable, Sequence

CHOICE, NUMBER = "choice", "number"
OPEN, CLOSED, REVEALED = "open", "closed", "revealed"
MAX_CHOICES = 6
LETTERS = "ABCDEF"
MAX_QUESTION = 600  # characters
MAX_CHOICE = 120
MAX_UNIT = 24
MAX_NUMBER = 1e12  # |answer| of a number round
MAX_ROUNDS = 500  # kept for the CSV in one lecture (the oldest go first)
MIN_SECONDS_BETWEEN = 0.2  # between two answers of one watcher
BINS = 8  # of a number round's distribution


class Refused(ValueError):
    """An answer or a question that is not taken; the message says why."""


def _text(value: object, what: str, most: int, least: int = 1) -> str:
    if not isinstance(value, str):
        raise Refused(f"{what}: expected text")
    text = " ".join(value.split())
    if len(text) < least:
        raise Refused(f"{what}: missing")
    if len(text) > most:
        raise Refused(f"{what}: {len(text)} characters, at most {most}")
    return text


def finite(value: object, what: str = "answer") -> float:
    """``value`` as a float within ±:data:`MAX_NUMBER`, or :class:`Refused` naming the problem."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise Refused(f"{what}: expected a number, got {type(value).__name__}")
    x = float(value)
    if not math.isfinite(x):
        raise Refused(f"{what}: expected a finite number, got {value!r}")
    if abs(x) > MAX_NUMBER:
        raise Refused(f"{what}: {x:g} is beyond ±{MAX_NUMBER:g}")
    return x


def shown_number(x: float) -> str:
    return f"{x:.6g}"


@dataclass(frozen=True)
class Question:
    """What a round asks: ``text``, and ``choices`` (multiple choice) or a ``unit`` (a number);
    ``answer`` is the right choice or number (None: none is right)."""

    text: str
    kind: str
    choices: tuple[str, ...] = ()
    unit: str = ""
    answer: str | float | None = None
    source: str = ""  # where it comes from (a lesson's step), said with the results

    @classmethod
    def choice(cls, text: object, choices: Sequence[object], answer: object = None, source: str = "") -> Question:
        t = _text(text, "question", MAX_QUESTION)
        if not isinstance(choices, (list, tuple)):
            raise Refused("choices: expected a list")
        cs = tuple(_text(c, f"choice {i + 1}", MAX_CHOICE) for i, c in enumerate(choices))
        if not 2 <= len(cs) <= MAX_CHOICES:
            raise Refused(f"choices: {len(cs)} given, a round has 2 to {MAX_CHOICES}")
        if len(set(cs)) != len(cs):
            raise Refused("choices: two are the same")
        if answer is not None and answer not in cs:
            raise Refused(f"answer: {answer!r} is not one of the choices")
        return cls(t, CHOICE, cs, "", answer if isinstance(answer, str) else None, source)

    @classmethod
    def number(cls, text: object, unit: object = "", answer: object = None, source: str = "") -> Question:
        t = _text(text, "question", MAX_QUESTION)
        u = _text(unit, "unit", MAX_UNIT, least=0) if unit is not None else ""
        a = finite(answer, "answer") if answer is not None else None
        return cls(t, NUMBER, (), u, a, source)

    @property
    def letters(self) -> tuple[str, ...]:
        """The labels the class picks from: A, B, … (one per choice)."""
        return tuple(LETTERS[: len(self.choices)])

    def label(self, value: str | float) -> str:
        """An answer as the results and the CSV say it: a choice's text, or the number with its unit."""
        if self.kind == CHOICE:
            return str(value)
        return f"{shown_number(float(value))} {self.unit}".rstrip()


@dataclass
class Answer:
    value: str | float  # a choice's text, or a number
    at: float  # time.time() of the answer


@dataclass
class Round:
    number: int
    question: Question
    opened: float
    state: str = OPEN
    answers: dict[Hashable, Answer] = field(default_factory=dict)

    def counts(self) -> list[tuple[str, int]]:
        """The distribution: (label, answers) for each choice, or for each bin of the numbers."""
        q = self.question
        values = [a.value for a in self.answers.values()]
        if q.kind == CHOICE:
            return [(f"{letter}. {c}", sum(v == c for v in values)) for letter, c in zip(q.letters, q.choices)]
        return bins([float(v) for v in values], q.unit, q.answer if isinstance(q.answer, float) else None)

    def median(self) -> float | None:
        if self.question.kind != NUMBER or not self.answers:
            return None
        xs = sorted(float(a.value) for a in self.answers.values())
        n = len(xs)
        return xs[n // 2] if n % 2 else (xs[n // 2 - 1] + xs[n // 2]) / 2


def bins(xs: list[float], unit: str, answer: float | None = None) -> list[tuple[str, int]]:
    """Up to :data:`BINS` equal bins over the answers (and the right one), as (range, count)."""
    if not xs:
        return []
    lo, hi = min(xs + ([answer] if answer is not None else [])), max(xs + ([answer] if answer is not None else []))
    if hi - lo < 1e-12 * max(1.0, abs(hi)):
        return [(f"{shown_number(lo)} {unit}".rstrip(), len(xs))]
    n = min(BINS, max(1, len(set(xs))))
    width = (hi - lo) / n
    out = [0] * n
    for x in xs:
        out[min(int((x - lo) / width), n - 1)] += 1
    return [(f"{shown_number(lo + i * width)} – {shown_number(lo + (i + 1) * width)} {unit}".rstrip(), c)
            for i, c in enumerate(out)]


class Rounds:
    """The rounds of one lecture (``revision`` bumps at every change, for the screens that show them)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.rounds: list[Round] = []
        self.revision = 0
        self._last: dict[Hashable, float] = {}  # watcher → time of its last answer

    @property
    def current(self) -> Round | None:
        """The round shown now (the last opened), None before the first."""
        return self.rounds[-1] if self.rounds else None

    def open(self, question: Question) -> Round:
        """A new round of ``question`` (the round before is closed, if it was open)."""
        with self._lock:
            last = self.current
            if last is not None and last.state == OPEN:
                last.state = CLOSED
            number = last.number + 1 if last is not None else 1
            r = Round(number, question, time.time())
            self.rounds.append(r)
            del self.rounds[:-MAX_ROUNDS]
            self._last.clear()
            self.revision += 1
            return r

    def answer(self, who: Hashable, value: object, number: int | None = None) -> str:
        """Take ``who``'s answer ``value`` (a choice's letter, or a number) for round ``number`` (the
        current one when None); returns how the results will say it. :class:`Refused` says why not."""
        with self._lock:
            r = self.current
            if r is None or (number is not None and r.number != number):
                raise Refused("this round is not open any more")
            if r.state != OPEN:
                raise Refused(f"round {r.number} is closed: answers are no longer taken")
            q = r.question
            if q.kind == CHOICE:
                if not isinstance(value, str) or value not in q.letters:
                    raise Refused(f"answer: {str(value)[:40]!r} is not one of {', '.join(q.letters)}")
                taken: str | float = q.choices[q.letters.index(value)]
            else:
                taken = finite(value)
            now = time.monotonic()
            if now - self._last.get(who, -math.inf) < MIN_SECONDS_BETWEEN:
                raise Refused("too many answers at once: wait a moment and answer again")
            self._last[who] = now
            r.answers[who] = Answer(taken, time.time())
            self.revision += 1
            return q.label(taken)

    def mine(self, who: Hashable) -> str | None:
        """``who``'s answer to the current round, as the results say it (None: none yet)."""
        with self._lock:
            r = self.current
            a = r.answers.get(who) if r is not None else None
            return r.question.label(a.value) if r is not None and a is not None else None

    def close(self) -> Round | None:
        with self._lock:
            r = self.current
            if r is not None and r.state == OPEN:
                r.state = CLOSED
                self.revision += 1
            return r

    def reveal(self) -> Round | None:
        with self._lock:
            r = self.current
            if r is not None and r.state != REVEALED:
                r.state = REVEALED
                self.revision += 1
            return r

    def forget(self, who: Hashable) -> None:
        """A watcher left: its answer stays in the round (it was given), its rate clock goes."""
        with self._lock:
            self._last.pop(who, None)

    def answered(self) -> int:
        """Answers in every round so far (what the CSV would hold)."""
        with self._lock:
            return sum(len(r.answers) for r in self.rounds)

    def csv(self) -> bytes:
        """Every answer of every round: round, question, answer, time (UTC, ISO 8601); no key of who."""
        with self._lock:
            rows = [(r.number, r.question.text, r.question.label(a.value),
                     datetime.fromtimestamp(a.at, timezone.utc).isoformat(timespec="seconds"))
                    for r in self.rounds for a in sorted(r.answers.values(), key=lambda a: a.at)]
        out = io.StringIO()
        w = csv.writer(out, lineterminator="\n")
        w.writerow(("round", "question", "answer", "time"))
        w.writerows(rows)
        return out.getvalue().encode("utf-8")

