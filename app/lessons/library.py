"""The shipped lessons (``shoal.static``'s ``lessons/*.md``), in file-name order."""

from __future__ import annotations

import functools
from importlib import resources
from pathlib import Path
from typing import Any

from .model import Lesson
from .parse import LessonError, parse_lesson

FOLDER = "lessons"


def _folder() -> Any:
    return resources.files("shoal.static").joinpath(FOLDER)


def read_lesson(path: str | Path) -> Lesson:
    """A lesson file anywhere (for authors and tests), validated; :class:`LessonError` if bad."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise LessonError([f"{path.name}: cannot read: {err}"]) from None
    return parse_lesson(text, path.stem)


@functools.lru_cache(maxsize=1)
def shipped() -> tuple[dict[str, Lesson], tuple[str, ...]]:
    """(lesson id → lesson, problems): a bad file is left out and reported, never fatal."""
    lessons: dict[str, Lesson] = {}
    problems: list[str] = []
    try:
        files = sorted((f for f in _folder().iterdir() if f.name.endswith(".md")), key=lambda f: f.name)
    except (FileNotFoundError, OSError):
        return {}, (f"the {FOLDER} folder is not installed",)
    for f in files:
        try:
            lesson = parse_lesson(f.read_text(encoding="utf-8"), f.name.removesuffix(".md"))
        except LessonError as err:
            problems += err.messages
        except (OSError, UnicodeDecodeError) as err:
            problems.append(f"{f.name}: cannot read: {err}")
        else:
            lessons[lesson.id] = lesson
    return lessons, tuple(problems)
