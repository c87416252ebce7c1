"""The run's lifecycle, the same for every scene kind: playing or paused, and what happens at
the preset's last step (``sim.steps``).

At the last step a run *stops* (it is then finished: Play, Step or a changed control start it
again from step 0 with the current values), *loops* (starts again from step 0 and plays on)
or *runs on* past it. The choice belongs to the browser tab, not to the preset: it outlives a
preset switch and is never written into a preset file.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..markdown import escape

STOP, LOOP, RUN_ON = "stop", "loop", "run on"
AT_END = (STOP, LOOP, RUN_ON)


def at_end_label(choice: str, steps: int) -> str:
    """The header's words for ``choice`` (``stop`` names the last step)."""
    return f"stop at step {steps}" if choice == STOP else choice


def at_end_choice(label: str, steps: int) -> str | None:
    """The choice a label of :func:`at_end_label` stands for (None: not one of them)."""
    return next((c for c in AT_END if at_end_label(c, steps) == label), None)


@dataclass
class Lifecycle:
    """Playing or not, and the end rule (``at_end``: one of :data:`AT_END`)."""

    playing: bool = False
    at_end: str = STOP

    def choose(self, choice: str) -> None:
        if choice not in AT_END:
            raise ValueError(f"at the end: {choice!r} is not one of {', '.join(AT_END)}")
        self.at_end = choice

    def finished(self, k: int, steps: int) -> bool:
        """Has a run that stops at its last step reached it?"""
        return self.at_end == STOP and k >= steps

    def at_last(self, k: int, steps: int) -> str:
        """What a run at step ``k`` does before its next step: ``"go"`` on, ``"stop"`` or ``"restart"``."""
        if k < steps or self.at_end == RUN_ON:
            return "go"
        return "stop" if self.at_end == STOP else "restart"

    def progress(self, k: int, steps: int, unit: str = "step") -> str:
        """``step 12/600``; past the last step (run on) ``step 612 (on past 600)``."""
        return f"{escape(unit)} {k:d}/{steps:d}" if k <= steps else f"{escape(unit)} {k:d} (on past {steps:d})"
