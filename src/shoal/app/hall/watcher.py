"""One watcher's own controls: what a class tab may do besides watching.

A watcher sees the broadcast (:mod:`.broadcast`) and has, on its own ``client.gui``, the
*Take over* button and, while a round is open, the answer controls of that round
(:mod:`.rounds`): a button per choice (A, B, …), or a number box and *Answer*; under them the
answer it gave, which it may change until the round closes. Its values are checked by
:func:`~shoal.app.input_guard.guard_inputs` (the type, a finite number, one of the buttons) and
then by :meth:`.rounds.Rounds.answer` (the round open, the range, the pace); a refusal is a red
message naming why. Nothing else a watcher sends reaches a handler.
"""

from __future__ import annotations

import threading
from typing import Any, Callable

from ..input_guard import guard_inputs
from ..markdown import escape
from .broadcast import ORDER_ANSWER, ORDER_OWN
from .rounds import CHOICE, MAX_NUMBER, OPEN, REVEALED, Refused, Round, Rounds


def notify(client: Any, title: str, body: str, color: str = "blue") -> None:
    """A toast on ``client``'s page (red ones stay longer)."""
    client.add_notification(title, body, color=color, auto_close_seconds=10.0 if color == "red" else 4.0)


TAKE_OVER = "Take over"
TAKE_OVER_HINT = "a private copy of the lecture's run, from this very step, that you drive yourself"


class Watcher:
    """The own controls of the watcher on ``client`` (a viser ``ClientHandle``)."""

    def __init__(self, client: Any, take_over: Callable[["Watcher"], object], rounds: Rounds | None = None) -> None:
        self.client = client
        self.key = int(client.client_id)
        self.rounds = rounds
        self._lock = threading.Lock()
        self._shown: tuple[int, str] | None = None  # (round, state) the controls show
        self._controls: list[Any] = []
        self.mine: Any = None  # the markdown that says this tab's answer
        self.taken: str | None = None  # the id of this tab's last take-over
        self.taken_at = -1e9  # (time.monotonic) when
        guard_inputs(client.gui, self.refuse)
        self.take_over_button = client.gui.add_button(TAKE_OVER, color="green", hint=TAKE_OVER_HINT,
                                                      order=ORDER_OWN)

        @self.take_over_button.on_click
        def _(event: Any) -> None:
            take_over(self)

    def notify(self, title: str, body: str, color: str = "blue") -> None:
        notify(self.client, title, body, color)

    def refuse(self, title: str, body: str) -> None:
        self.notify(title, body, "red")

    # ------------------------------------------------------------------ rounds
    def show(self, r: Round | None) -> None:
        """The answer controls for round ``r`` as it stands (open: controls; closed or revealed:
        this tab's answer only)."""
        with self._lock:
            shown = (r.number, r.state) if r is not None else None
            if shown == self._shown:
                return
            self._shown = shown
            gui = self.client.gui
            for h in self._controls:
                h.remove()
            self._controls = []
            if r is None:
                return
            if r.state == OPEN:
                self._build(gui, r)
            self.mine = gui.add_markdown(self._said(r), order=ORDER_ANSWER + 0.5)
            self._controls.append(self.mine)

    def _build(self, gui: Any, r: Round) -> None:
        q = r.question
        if q.kind == CHOICE:
            buttons = gui.add_button_group("your answer", q.letters, order=ORDER_ANSWER,
                                           hint="pick one; you may change it until the round closes")
            self._controls.append(buttons)

            @buttons.on_click
            def _(event: Any) -> None:
                self.answer(r.number, event.target.value)
        else:
            unit = f" [{q.unit}]" if q.unit else ""
            box = gui.add_number(f"your answer{unit}", initial_value=0.0, min=-MAX_NUMBER, max=MAX_NUMBER, step=0.001,
                                 order=ORDER_ANSWER, hint="a number; press Answer (you may change it until the "
                                                          "round closes)")
            send = gui.add_button("Answer", color="blue", order=ORDER_ANSWER + 0.1)
            self._controls += [box, send]

            @send.on_click
            def _(event: Any) -> None:
                self.answer(r.number, box.value)

    def _said(self, r: Round) -> str:
        mine = self.rounds.mine(self.key) if self.rounds is not None else None
        if mine is None:
            return "*No answer from this tab yet.*" if r.state == OPEN else "*This tab gave no answer.*"
        text = f"**Your answer:** {escape(mine)}"
        right = r.question.answer
        if r.state == REVEALED and right is not None:
            text += " ✓" if mine == r.question.label(right) else " (not the answer)"
        elif r.state == OPEN:
            text += " (you may change it until the round closes)"
        return text

    def answer(self, number: int, value: object) -> bool:
        """This tab's answer ``value`` to round ``number``; a refusal is said in red. True if taken."""
        if self.rounds is None:
            return False
        try:
            self.rounds.answer(self.key, value, number)
        except Refused as err:
            self.refuse("Refused: your answer", str(err))
            return False
        r = self.rounds.current
        if r is not None and self.mine is not None:
            self.mine.content = self._said(r)
        return True
