"""Which algorithm suits my robots and my source? The thesis' Fig. 9-1 as a decision tree.

The questions, answers and recommendations are data (``lessons/chooser.toml`` in
``shoal.static``): every answer leads to another question or to a leaf, and every leaf
names the shipped preset that shows its algorithm. :func:`walk` follows a path of answer
numbers, :func:`trail` names its answers and :func:`paths` lists the path to every leaf.
"""

from __future__ import annotations

import functools
import tomllib
from importlib import resources
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from .model import PRESET_NAME, FieldValue
from .parse import LessonError

FILE = "lessons/chooser.toml"
MAX_ANSWERS = 4  # per question: the panel shows one button per answer
Name = Annotated[str, Field(pattern=PRESET_NAME, max_length=40)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Answer(_Model):
    label: Annotated[str, Field(min_length=1, max_length=48)]
    next: Name


class Question(_Model):
    question: Annotated[str, Field(min_length=1, max_length=200)]
    detail: Annotated[str, Field(max_length=800)] = ""
    answers: Annotated[list[Answer], Field(min_length=2, max_length=MAX_ANSWERS)]


class Leaf(_Model):
    title: Annotated[str, Field(min_length=1, max_length=80)]
    chapter: Annotated[str, Field(min_length=1, max_length=12)]
    why: Annotated[str, Field(min_length=1, max_length=1200)]
    preset: Name
    values: dict[str, FieldValue] = Field(default_factory=dict)


class Tree(_Model):
    title: Annotated[str, Field(min_length=1, max_length=80)]
    about: Annotated[str, Field(max_length=800)] = ""
    start: Name
    questions: dict[Name, Question]
    leaves: dict[Name, Leaf]

    @model_validator(mode="after")
    def _a_tree(self) -> "Tree":
        both = set(self.questions) & set(self.leaves)
        if both:
            raise ValueError(f"{', '.join(sorted(both))}: both a question and a leaf")
        if self.start not in self.questions:
            raise ValueError(f"start: no question named {self.start!r}")
        for name, q in self.questions.items():
            for i, a in enumerate(q.answers):
                if a.next not in self.questions and a.next not in self.leaves:
                    raise ValueError(f"questions.{name}.answers.{i}: next = {a.next!r} is neither a question "
                                     "nor a leaf")
        seen: set[str] = set()

        def visit(name: str, path: tuple[str, ...]) -> None:
            if name in path:
                raise ValueError(f"questions.{name}: the answers lead back to it ({' → '.join(path + (name,))})")
            seen.add(name)
            if name in self.questions:
                for a in self.questions[name].answers:
                    visit(a.next, path + (name,))

        visit(self.start, ())
        unreached = sorted((set(self.questions) | set(self.leaves)) - seen)
        if unreached:
            raise ValueError(f"{', '.join(unreached)}: no answer leads there")
        return self


def walk(tree: Tree, path: list[int]) -> Question | Leaf:
    """The question or leaf reached from the start by answer numbers ``path`` (0-based);
    :class:`IndexError` for an answer the question does not have."""
    node: Question | Leaf = tree.questions[tree.start]
    for depth, choice in enumerate(path):
        if not isinstance(node, Question):
            raise IndexError(f"answer {depth + 1}: the path already reached a leaf")
        if not 0 <= choice < len(node.answers):
            raise IndexError(f"answer {depth + 1}: the question has {len(node.answers)} answers")
        name = node.answers[choice].next
        node = tree.questions.get(name) or tree.leaves[name]
    return node


def trail(tree: Tree, path: list[int]) -> list[str]:
    """The labels of the answers along ``path`` (as :func:`walk` follows it)."""
    out = []
    for depth, choice in enumerate(path):
        node = walk(tree, path[:depth])
        if not isinstance(node, Question):
            break
        out.append(node.answers[choice].label)
    return out


def paths(tree: Tree) -> dict[str, list[list[int]]]:
    """Every leaf name → the answer paths that reach it."""
    out: dict[str, list[list[int]]] = {name: [] for name in tree.leaves}
    stack: list[tuple[str, list[int]]] = [(tree.start, [])]
    while stack:
        name, path = stack.pop()
        if name in tree.leaves:
            out[name].append(path)
            continue
        for i, a in enumerate(tree.questions[name].answers):
            stack.append((a.next, path + [i]))
    return out


def parse_tree(text: str, name: str = "chooser.toml") -> Tree:
    try:
        data: dict[str, Any] = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise LessonError([f"{name}: TOML syntax: {err}"]) from None
    try:
        return Tree.model_validate(data)
    except ValidationError as err:
        errors = err.errors(include_url=False)
        raise LessonError([f"{name}, {'.'.join(str(p) for p in e['loc']) or 'tree'}: "
                           f"{e['msg'].removeprefix('Value error, ')}" for e in errors]) from None


@functools.lru_cache(maxsize=1)
def shipped_tree() -> Tree:
    """The shipped chooser; :class:`LessonError` if it is missing or bad."""
    try:
        text = resources.files("shoal.static").joinpath(FILE).read_text(encoding="utf-8")
    except (FileNotFoundError, OSError) as err:
        raise LessonError([f"{FILE}: cannot read: {err}"]) from None
    return parse_tree(text)
