"""The preset dropdown of one tab: the shipped presets the app runs, and the presets uploaded
into this tab (held in memory, never written anywhere).

A value the browser sends is only ever looked up among these choices: a path, a long string
or any other value is refused with a message and never reaches the file system.
"""

from __future__ import annotations

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError, short
from shoal.presets.models import Scenario

from .pace import paced

UPLOADED = " (uploaded)"  # an uploaded preset's choice is its name and this
MAX_UPLOADED = 8  # uploads a tab keeps to choose again (the oldest goes first)


class PresetMenu:
    """Choices (labels) of one tab's preset dropdown and the scenario each one loads."""

    def __init__(self, shipped: tuple[str, ...]) -> None:
        """``shipped``: the shipped presets the app can show."""
        self.shipped = shipped
        self._uploaded: dict[str, Scenario] = {}  # label → scenario, oldest first
        self.current: str | None = None  # the choice last loaded

    def options(self) -> tuple[str, ...]:
        return self.shipped + tuple(self._uploaded)

    def scenario(self, choice: str) -> Scenario:
        """The scenario of ``choice``; :class:`PresetError` for anything that is not a choice."""
        if isinstance(choice, str) and choice in self._uploaded:
            return self._uploaded[choice]
        if isinstance(choice, str) and choice in self.shipped:
            return paced(presets_io.load_shipped(choice))  # (opens at a speed one can watch)
        raise PresetError([f"preset {short(choice)}: not one of this tab's presets "
                           "(the shipped ones and those uploaded here)"])

    def add_upload(self, scenario: Scenario) -> str:
        """Keep ``scenario`` as a choice; returns its label (an upload of the same name replaces it)."""
        label = f"{scenario.name}{UPLOADED}"
        self._uploaded.pop(label, None)
        self._uploaded[label] = scenario
        while len(self._uploaded) > MAX_UPLOADED:
            del self._uploaded[next(iter(self._uploaded))]
        return label

    def forget(self, label: str) -> None:
        self._uploaded.pop(label, None)

    def label_for(self, scenario: Scenario) -> str | None:
        """The choice to show for ``scenario``: the one last loaded if it holds this scene,
        else the shipped preset of that name, else None (leave the dropdown as it is)."""
        current = self._uploaded.get(self.current or "")
        if self.current is not None and (current.name if current else self.current) == scenario.name:
            return self.current
        return scenario.name if scenario.name in self.shipped else None
