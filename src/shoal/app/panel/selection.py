"""The robot the panels and the view single out, as a number box any kind can place (the
*Selected robot* folder of the fleet and acoustic scenes, Mai's observer, the Chapter 3
particle): it shows the session's selection, follows a robot picked in the arena and selects
the robot typed."""

from __future__ import annotations

from typing import Any

from .spec import Number, PanelAPI


def _select(panel: PanelAPI, robot: Any) -> None:
    panel.select_robot(int(robot))


def robot_number(label: str = "robot", hint: str = "", key: str = "robot") -> Number:
    """A number box bound to ``session.selected_robot`` (0 … robots − 1)."""
    return Number(key, label, read=lambda s: min(s.selected_robot, s.robots - 1), act=_select,
                  high=lambda s: max(s.robots - 1, 0), hint=hint, follow=True)
