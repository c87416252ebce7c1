"""Reading a lesson file: markdown with a TOML header between ``+++`` lines.

::

    +++
    title = "When does a swarm blow up?"
    chapter = "3"
    summary = "One or two sentences for the lesson list."
    +++

    An optional introduction.

    ## A step's title

    ```setup
    preset = "standard-pso"      # optional: else build on the scene of the step before
    controller.omega = 1.1       # field values by dotted path, as in `shoal run --set`

    [check]                      # optional: what a headless run must show (see verify.py)
    steps = 100
    final.max_speed = [1e6, inf]
    ```

    A few sentences.

    **Do:** press Play; where does the ✕ sit?

    **Question:** ...

    **Answer:** ...

    ```round
    choices = ["inside", "outside"]   # or: unit = "s" (a number); asked of a class in a lecture
    answer = "inside"                 # optional; question = "..." words it for the round
    ```

    ## Try it yourself

    - one idea per item

Every problem is reported with the lesson, the step and the field it concerns.
"""

from __future__ import annotations

import re
import tomllib
from typing import Any

from pydantic import ValidationError

from .model import Lesson

FENCE = "+++"
TRY_IT = "try it yourself"
MARKERS = {"**do:**": "instruction", "**question:**": "question", "**answer:**": "answer"}
_SETUP = re.compile(r"^```setup[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
_ROUND = re.compile(r"^```round[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
_HEADING = re.compile(r"^## +(.+?)\s*$", re.M)
_ITEM = re.compile(r"^\s*[-*] +", re.M)
MAX_CHARS = 40_000  # a lesson is short; this bounds what a bad file can cost


class LessonError(ValueError):
    """A lesson file that cannot be shown; ``messages`` name the lesson, step and field."""

    def __init__(self, messages: list[str]) -> None:
        self.messages = messages
        super().__init__("\n".join(messages))


def _toml(text: str, where: str) -> dict[str, Any]:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise LessonError([f"{where}: TOML syntax: {err}"]) from None


def flatten(table: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``{"controller": {"omega": 1.1}}`` → ``{"controller.omega": 1.1}`` (lists stay values)."""
    out: dict[str, Any] = {}
    for key, value in table.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, path + "."))
        else:
            out[path] = value
    return out


def _split_header(text: str, name: str) -> tuple[dict[str, Any], str]:
    lines = text.split("\n")
    if not lines or lines[0].strip() != FENCE:
        raise LessonError([f"{name}: must start with a {FENCE} line and a TOML header (title, chapter, summary)"])
    try:
        end = next(i for i in range(1, len(lines)) if lines[i].strip() == FENCE)
    except StopIteration:
        raise LessonError([f"{name}: the header has no closing {FENCE} line"]) from None
    return _toml("\n".join(lines[1:end]), f"{name}: header"), "\n".join(lines[end + 1:])


def _step(title: str, body: str, where: str) -> dict[str, Any]:
    """One ``## title`` section as the fields of :class:`Step`."""
    step: dict[str, Any] = {"title": title}
    blocks = _SETUP.findall(body)
    if len(blocks) > 1:
        raise LessonError([f"{where}: has {len(blocks)} setup blocks; a step sets up one scene"])
    if blocks:
        table = _toml(blocks[0], f"{where}: setup")
        setup: dict[str, Any] = {}
        for key in ("preset", "check"):
            if key in table:
                setup[key] = table.pop(key)
        setup["values"] = flatten(table)
        step["setup"] = setup
        body = _SETUP.sub("", body)
    rounds = _ROUND.findall(body)
    if len(rounds) > 1:
        raise LessonError([f"{where}: has {len(rounds)} round blocks; a step asks one question"])
    if rounds:
        step["round"] = _toml(rounds[0], f"{where}: round")
        body = _ROUND.sub("", body)
    field = "text"
    parts: dict[str, list[str]] = {"text": [], "instruction": [], "question": [], "answer": []}
    for para in re.split(r"\n\s*\n", body.strip()):
        lower = para.lstrip().lower()
        marker = next((m for m in MARKERS if lower.startswith(m)), None)
        if marker is not None:
            field = MARKERS[marker]
            if parts[field]:
                raise LessonError([f"{where}: {field}: given twice"])
            para = para.lstrip()[len(marker):].strip()
        if para.strip():
            parts[field].append(para.strip())
    step.update({k: "\n\n".join(v) for k, v in parts.items() if v})
    return step


def _try_it(body: str) -> list[str]:
    items = [" ".join(item.split()) for item in _ITEM.split(body.strip())[1:]]
    return [item for item in items if item]


def _where(loc: tuple, data: dict[str, Any], name: str) -> str:
    """A pydantic error location as 'lesson, step N 'title', field'."""
    parts, out = list(loc), [name]
    if parts[:1] == ["steps"] and len(parts) > 1 and isinstance(parts[1], int):
        i = parts[1]
        title = data["steps"][i].get("title", "") if i < len(data["steps"]) else ""
        out.append(f"step {i + 1} '{title}'")
        parts = parts[2:]
    if parts:
        out.append(".".join(str(p) for p in parts))
    return ", ".join(out)


def parse_lesson(text: str, lesson_id: str) -> Lesson:
    """A validated :class:`Lesson` from the text of ``<lesson_id>.md``, or :class:`LessonError`."""
    name = f"{lesson_id}.md"
    if len(text) > MAX_CHARS:
        raise LessonError([f"{name}: {len(text)} characters; a lesson has at most {MAX_CHARS}"])
    header, body = _split_header(text.replace("\r\n", "\n"), name)
    data: dict[str, Any] = {"id": lesson_id, **header, "steps": [], "try_it": []}
    sections = _HEADING.split(body)
    data["intro"] = sections[0].strip()
    for title, section in zip(sections[1::2], sections[2::2]):
        if title.strip().lower() == TRY_IT:
            data["try_it"] = _try_it(section)
        else:
            where = f"{name}, step {len(data['steps']) + 1} '{title}'"
            data["steps"].append(_step(title, section, where))
    try:
        return Lesson.model_validate(data)
    except ValidationError as err:
        lines = []
        for e in err.errors(include_url=False):
            msg = e["msg"].removeprefix("Value error, ")
            if e["type"] == "missing" and e["loc"][-1:] in (("instruction",), ("question",), ("answer",)):
                marker = next(m for m, f in MARKERS.items() if f == e["loc"][-1])
                msg = f"missing (a paragraph that starts with {marker[:2]}{marker[2].upper()}{marker[3:]})"
            elif e["loc"] == ("try_it",) and e["type"] == "too_short":
                msg = "missing (end the lesson with a '## Try it yourself' list)"
            lines.append(f"{_where(e['loc'], data, name)}: {msg}")
        raise LessonError(lines) from None
