"""How a preset's faults are told: :class:`PresetError` (one message per bad field) and the
short, dotted form of a pydantic error. The bottom of :mod:`shoal.presets`: every other module
of it may raise these, and this one imports none of them."""

from __future__ import annotations

import reprlib
from typing import Any

from pydantic import ValidationError


class PresetError(ValueError):
    """A preset could not be read or validated; ``messages`` name each bad field."""

    def __init__(self, messages: list[str]) -> None:
        self.messages = messages
        super().__init__("\n".join(messages))


_SHORT = reprlib.Repr()  # a bad value is shown short: a few items, a few levels
_SHORT.maxlevel, _SHORT.maxlist, _SHORT.maxtuple, _SHORT.maxdict = 2, 4, 4, 4
_SHORT.maxstring = _SHORT.maxother = _SHORT.maxlong = 40
MAX_NAME = 60  # characters of a field name shown in a message


def short(value: Any) -> str:
    """A value as a message shows it: a few characters, a few items, a few levels."""
    return _SHORT.repr(value)


def _short_name(part: object) -> str:
    text = str(part)
    return text if len(text) <= MAX_NAME else text[: MAX_NAME - 3] + "..."


def format_errors(err: ValidationError) -> list[str]:
    """One line per error: ``dotted.field: message (got value)``, the value and names shortened."""
    lines = []
    for e in err.errors(include_url=False):
        loc = ".".join(_short_name(p) for p in e["loc"])
        msg = e["msg"].removeprefix("Value error, ")
        quiet = e["type"] in ("missing",) or isinstance(e.get("input"), dict)
        got = "" if quiet else f" (got {_SHORT.repr(e.get('input'))})"
        lines.append(f"{loc}: {msg}{got}" if loc else f"{msg}{got}")
    return lines
