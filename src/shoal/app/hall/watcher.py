"""One watcher's own controls: what a class tab may do besides watching.

A watcher sees the broadcast (:mod:`.broadcast`) and has, on its own ``client.gui``, the
*Take over* button and, while a round is open, the answer controls of that round
(:mod:`.rounds`). Its values are checked by :func:`~shoal.app.input_guard.guard_inputs` before
anything reads them; nothing else a watcher sends reaches a handler.
"""

from __future__ import annotations

from typing import Any, Callable

from ..input_guard import guard_inputs
from .broadcast import ORDER_OWN

TAKE_OVER = "Take over"
TAKE_OVER_HINT = "a private copy of the lecture's run, from this very step, that you drive yourself"


class Watcher:
    """The own controls of the watcher on ``client`` (a viser ``ClientHandle``)."""

    def __init__(self, client: Any, take_over: Callable[["Watcher"], object]) -> None:
        self.client = client
        self.key = int(client.client_id)
        guard_inputs(client.gui, self.refuse)
        self.take_over_button = client.gui.add_button(TAKE_OVER, color="green", hint=TAKE_OVER_HINT,
                                                      order=ORDER_OWN)

        @self.take_over_button.on_click
        def _(event: Any) -> None:
            take_over(self)

    def notify(self, title: str, body: str, color: str = "blue") -> None:
        self.client.add_notification(title, body, color=color, auto_close_seconds=10.0 if color == "red" else 4.0)

    def refuse(self, title: str, body: str) -> None:
        self.notify(title, body, "red")
