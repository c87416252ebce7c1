"""The Compare folder of every panel (closed at first): switch swarm B on, say how it differs from A.

B = A with the overrides typed as ``dotted.key=value`` lines, validated by the preset model
(a bad line or value is refused with a red notification naming the field, nothing changes).
A quick choice fills them in: each kind offers its own (the law for a Chapter 3 swarm, the
controller for a fleet, the algorithm for an acoustic swarm, positions or selection for SLO).
Switching B on, or applying new overrides, restarts A and B together from step 0 with the
same seed.
"""

from __future__ import annotations

from typing import Any

from shoal.presets.io import PresetError

from ..markdown import escape
from ..session.twin import override_text, parse_overrides
from .spec import Host

CUSTOM = "custom (type below)"
INTRO = ("**Swarm B** runs the same preset and seed as A with the overrides below, in lock-step with "
         "the playback. In the arena B is drawn as blue squares under A; in the main plot its curve is blue and "
         "dashed.")


class CompareFolder:
    """The handles of the Compare folder, wired to ``panel.session``."""

    def __init__(self, panel: Host) -> None:
        self.panel = panel
        gui = panel.gui
        choices = panel.compare_choices()
        first = next(iter(choices), CUSTOM)
        with gui.add_folder("Compare with swarm B", expand_by_default=False) as self.folder:
            gui.add_markdown(INTRO)
            self.enabled = gui.add_checkbox("compare with swarm B", False,
                                            hint="run B beside A; both restart from step 0 with the same seed")
            self.quick = gui.add_dropdown("B differs by", tuple(choices) + (CUSTOM,), initial_value=first,
                                          hint="fills in the overrides below")
            self.text = gui.add_text(
                "B overrides", override_text(choices.get(first, {})), multiline=True,
                hint="one dotted.key=value a line, as shoal run --set; checked by the preset model")
            self.apply_button = gui.add_button("Apply to B", hint="rebuild B with these overrides (A and B restart)")
            self.info = gui.add_markdown("")
        self._wire()

    @property
    def session(self) -> Any:
        return self.panel.session

    def _wire(self) -> None:
        @self.enabled.on_update
        def _(event: Any) -> None:
            if self.panel.syncing:
                return
            if self.enabled.value:
                self.enable()
            else:
                self.session.disable_compare()
                self.sync()

        @self.quick.on_update
        def _(event: Any) -> None:
            if self.panel.syncing or self.quick.value == CUSTOM:
                return
            choice = self.panel.compare_choices().get(self.quick.value)
            if choice is not None:
                self.panel.set_quietly(self.text, override_text(choice))
                if self.session.twin is not None:
                    self.enable()

        @self.apply_button.on_click
        def _(event: Any) -> None:
            self.enable()

    def enable(self) -> bool:
        """Build B from the typed overrides; refused (red notification, nothing changed) if bad."""
        try:
            overrides = parse_overrides(self.text.value)
            self.session.enable_compare(overrides)
        except PresetError as err:
            self.panel.refuse(err, "swarm B")
            self.sync()
            return False
        what = ", ".join(f"{k} = {v}" for k, v in overrides.items()) or "no overrides (B is A)"
        self.panel.notify("Comparing A and B", f"B: {what}; both restart from step 0", "green")
        self.sync()
        return True

    def sync(self) -> None:
        """Checkbox, quick choices and info from the session."""
        p = self.panel
        if p.removed:
            return
        s = self.session
        on = s.twin is not None
        choices = p.compare_choices()
        options = tuple(choices) + (CUSTOM,)
        with p.quietly():
            p.set_quietly(self.enabled, on)
            if tuple(self.quick.options) != options:
                self.quick.options = options
            if self.quick.value not in options:
                p.set_quietly(self.quick, options[0])
            if not on and self.quick.value in choices:  # follow A while B is off
                p.set_quietly(self.text, override_text(choices[self.quick.value]))
        if on:
            lines = ("\n".join(f"- <code>{escape(f'{k} = {v}')}</code>" for k, v in s.overrides.items())
                     or "- nothing: B is A")
            self.info.content = f"B = A with:\n{lines}"
        else:
            self.info.content = "B is off."
