"""A take-over's state: the lecture's run as bytes a private session starts from.

(Waits for the engine's snapshot: until then a take-over is refused with a message.)
"""

from __future__ import annotations

from ..session.session import Session


class CannotTakeOver(Exception):
    """The run cannot be handed over now; the message says why."""


def capture(session: Session) -> bytes:
    raise CannotTakeOver("taking over needs the engine's snapshot, which this build does not have yet")


def restore(state: bytes) -> tuple[Session, bool]:
    raise CannotTakeOver("taking over needs the engine's snapshot, which this build does not have yet")
