"""The lecturer's part of a lecture, at the top of the lecturer's panel: the class and its rounds.

- a line that says how many tabs watch, and the round's state;
- while there is a round, the folder *This round*: its question, the count and the
  distribution as answers come (the class sees only the count until it is revealed), *Close
  round* and *Reveal and play*, and *Download answers (CSV)* (a download in this tab; nothing is
  written on the server);
- the folder *A question of your own*: one, multiple choice (the choices separated
  by ``|``) or a number with a unit, with its answer if there is one. A lesson step's question
  is asked with one click from the Lessons tab (*Ask the class*).

It lives on the lecturer's own ``client.gui``, built before the tab's panel so that it stays on
top whatever kind of scene the panel shows; every value it reads is the lecturer's.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Protocol

from .round_view import lecturer_html
from .rounds import CLOSED, OPEN, REVEALED, Question, Refused, Round, Rounds

ROUND_BUTTONS = ("Close round", "Reveal and play")
KINDS = ("multiple choice", "a number")


class Hall(Protocol):
    """What the panel asks of the lecture."""

    rounds: Rounds

    def open_round(self, question: Question) -> Round: ...

    def close_round(self) -> None: ...

    def reveal_round(self) -> None: ...

    def watching(self) -> int: ...


class ClassPanel:
    def __init__(self, gui: Any, hall: Hall, notify: Callable[[str, str, str], None],
                 send_file: Callable[[str, bytes], None]) -> None:
        self.gui, self.hall, self.notify, self.send_file = gui, hall, notify, send_file
        self.summary = gui.add_markdown("")
        with gui.add_folder("This round", visible=False) as self.round_folder:  # (a lecturer may fold it away)
            self.live = gui.add_html("")
            self.buttons = gui.add_button_group("round", ROUND_BUTTONS, visible=False)
            self.export = gui.add_button("Download answers (CSV)", visible=False,
                                         hint="round, question, answer, time of every answer so far (no names)")
        with gui.add_folder("A question of your own", expand_by_default=False) as self.folder:
            self.question = gui.add_text("question", "", hint="what the class predicts")
            self.kind = gui.add_dropdown("answer with", KINDS)
            self.choices = gui.add_text("choices", "", hint="separated by |, e.g. inside | outside | on the line")
            self.unit = gui.add_text("unit", "", visible=False, hint="e.g. s, m/s, steps")
            self.right = gui.add_text("right answer", "", hint="one of the choices, or the number (may be left empty)")
            self.open_button = gui.add_button("Open round", color="green")
        self._shown: tuple[int, int] | None = None
        self._wire()
        self.refresh()

    def _wire(self) -> None:
        @self.kind.on_update
        def _(event: Any) -> None:
            number = self.kind.value == KINDS[1]
            self.choices.visible, self.unit.visible = not number, number

        @self.open_button.on_click
        def _(event: Any) -> None:
            self.ask()

        @self.buttons.on_click
        def _(event: Any) -> None:
            if event.target.value == ROUND_BUTTONS[0]:
                self.hall.close_round()
            else:
                self.hall.reveal_round()
            self.refresh()

        @self.export.on_click
        def _(event: Any) -> None:
            stamp = time.strftime("%Y%m%d-%H%M", time.localtime())
            self.send_file(f"shoal-rounds-{stamp}.csv", self.hall.rounds.csv())

    def ask(self) -> Round | None:
        """Open a round of the question typed in *A question of your own* (refused in red, naming the field)."""
        try:
            right: object = self.right.value.strip() or None
            if self.kind.value == KINDS[1]:
                if right is not None:
                    try:
                        right = float(str(right))
                    except ValueError:
                        raise Refused(f"right answer: {str(right)[:40]!r} is not a number") from None
                q = Question.number(self.question.value, self.unit.value, right)
            else:
                choices = [c for c in (p.strip() for p in self.choices.value.split("|")) if c]
                q = Question.choice(self.question.value, choices, right)
        except Refused as err:
            self.notify("Refused: round", str(err), "red")
            return None
        r = self.hall.open_round(q)
        self.refresh()
        return r

    def refresh(self) -> None:
        """The summary and the round's live results (the caller throttles this)."""
        rounds = self.hall.rounds
        r = rounds.current
        n = self.hall.watching()
        text = f"**Class:** {n:d} tab{'' if n == 1 else 's'} watching"
        if r is not None and r.state == OPEN:
            text += f" · round {r.number:d} open: {len(r.answers):d} answers"
        elif r is not None and r.state == CLOSED:
            text += f" · round {r.number:d} closed: {len(r.answers):d} answers"
        elif r is not None:
            text += f" · round {r.number:d} revealed"
        if self.summary.content != text:
            self.summary.content = text
        key = (rounds.revision, r.number if r is not None else 0)
        if key == self._shown:
            return
        self._shown = key
        self.live.content = lecturer_html(r)
        self.round_folder.visible = r is not None
        self.buttons.visible = r is not None and r.state != REVEALED
        self.export.visible = rounds.answered() > 0

    def remove(self) -> None:
        for h in (self.summary, self.round_folder, self.folder):
            h.remove()


def lesson_question(lesson: Any, index: int) -> Question:
    """The round of step ``index`` of ``lesson`` (its ``round`` block; :class:`Refused` if it has none)."""
    step = lesson.steps[index]
    spec = step.round
    if spec is None:
        raise Refused(f"{lesson.label}, step {index + 1}: its question has no round")
    text = spec.question or step.question
    source = f"{lesson.label}, step {index + 1}: {step.title}"
    if spec.choices is not None:
        return Question.choice(text, spec.choices, spec.answer, source)
    return Question.number(text, spec.unit or "", spec.answer, source)

