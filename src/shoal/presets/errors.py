"""How a preset's faults are told: :class:`PresetError` (one message per bad field) and the
short, dotted form of a pydantic error. The bottom of :mod:`shoal.presets`: every other module
of it may raise these, and this one imports none of them."""

from __future__ import annotations

import re
import reprlib
import typing
from typing import Any, Callable

from pydantic import BaseModel, ValidationError

from shoal.engine.core.suggest import did_you_mean


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


FieldsAt = Callable[[tuple[Any, ...]], list[str]]  # a place in the model validated → the field names there


def format_errors(err: ValidationError, fields_at: FieldsAt = lambda loc: []) -> list[str]:
    """One line per error: ``dotted.field: message (got value)``, the value and names shortened,
    and for a mistyped field, section or name the closest ones it could have been
    (``fields_at(loc)``: the field names at a place of the model validated)."""
    lines = []
    for e in err.errors(include_url=False):
        loc = ".".join(_short_name(p) for p in e["loc"])
        msg = e["msg"].removeprefix("Value error, ")
        quiet = e["type"] in ("missing",) or isinstance(e.get("input"), dict)
        got = "" if quiet else f" (got {_SHORT.repr(e.get('input'))})"
        line = f"{loc}: {msg}{got}" if loc else f"{msg}{got}"
        lines.append(line + _suggestion(e, msg, fields_at))
    return lines


def _suggestion(e: Any, msg: str, fields_at: FieldsAt) -> str:
    """" (did you mean …?)" for an unknown field or section (the model's fields at its place) or a
    value outside its choices (the names the message lists)."""
    loc = tuple(e["loc"])
    if e["type"] == "extra_forbidden" and loc and isinstance(loc[-1], str):
        return did_you_mean(loc[-1], fields_at(loc[:-1]))
    section = re.search(r"no scene kind has a \[([^\]]+)\] section", msg)
    if section:
        return did_you_mean(section.group(1), fields_at(()))
    if msg.startswith("Input should be") and isinstance(e.get("input"), str):
        return did_you_mean(e["input"], re.findall(r"'([^']*)'", msg))
    return ""


def fields_in(model: Any, loc: tuple[Any, ...]) -> list[str]:
    """The field names of the pydantic model at ``loc`` inside ``model`` ([] where there is none;
    list indices are passed over)."""
    for part in loc:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part) if isinstance(model, type) and issubclass(model, BaseModel) else None
        model = None if field is None else model_in(field.annotation)
        if model is None:
            return []
    return list(model.model_fields) if isinstance(model, type) and issubclass(model, BaseModel) else []


def model_in(annotation: Any) -> Any:
    """The pydantic model an annotation holds (``Model``, ``Model | None``, ``list[Model]``), or None."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = model_in(arg)
        if found is not None:
            return found
    return None
