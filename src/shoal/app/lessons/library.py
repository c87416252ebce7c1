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


def _parse_file(file: Any, name: str) -> Lesson:
    """The lesson in ``file`` (a path or a package resource) named ``name``."""
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise LessonError([f"{name}: cannot read: {err}"]) from None
    return parse_lesson(text, name.removesuffix(".md"))


def read_lesson(path: str | Path) -> Lesson:
    """A lesson file anywhere (for authors and tests), validated; :class:`LessonError` if bad."""
    return _parse_file(Path(path), Path(path).name)


@functools.lru_cache(maxsize=1)
def shipped() -> tuple[dict[str, Lesson], tuple[str, ...]]:
    """(lesson id → lesson, problems): a bad file is left out and reported, never fatal."""
    lessons: dict[str, Lesson] = {}
    problems: list[str] = []
    try:
        files = sorted((f for f in _folder().iterdir() if f.name.endswith(".md")), key=lambda f: f.name)
    except OSError:
        return {}, (f"the {FOLDER} folder is not installed",)
    for f in files:
        try:
            lesson = _parse_file(f, f.name)
        except LessonError as err:
            problems += err.messages
        else:
            lessons[lesson.id] = lesson
    return lessons, tuple(problems)
