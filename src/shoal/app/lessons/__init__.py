"""Guided lessons: short step-by-step lesson files, the Fig. 9-1 chooser, and their panel.

- :mod:`.model` and :mod:`.parse`: what a lesson is and how its file reads;
- :mod:`.library`: the shipped lessons (``shoal.static``'s ``lessons/*.md``);
- :mod:`.scenes`: a step's scene as a preset with ``--set`` overrides, through the preset model;
- :mod:`.verify`: headless runs that check what a step says the student will see;
- :mod:`.chooser`: the thesis' Fig. 9-1 as a decision tree (``lessons/chooser.toml``);
- :mod:`.panel`: the Lessons tab, built on any viser GUI handle with two callbacks.
"""

from .model import Check, Lesson, Setup, Step
from .parse import LessonError, parse_lesson

__all__ = ["Check", "Lesson", "LessonError", "Setup", "Step", "parse_lesson"]
