"""The "Positions" folder of the Chapter 3, fleet and acoustic panels: the switch between true
(oracle) and SLO-estimated positions, the error set, and a readout of the selected robot's
beliefs (see :mod:`.positions` for what the switch changes in the scenario).
"""

from __future__ import annotations

from typing import Any

from shoal.presets.models import Scenario

from .session.beliefs import Ghosts
from .session.positions import NEW_SLO, POSITIONS, ghost_text, positions_of, switch_changes
from .slo_panels import ERROR_SETS, _key


class PositionsGui:
    """The folder, built into ``panels`` (a :class:`~.panel_base.PanelsBase`) where it is
    created; ``sync`` inside the panels' sync guard, ``refresh`` with each snapshot."""

    def __init__(self, panels: Any, observer: str = "") -> None:
        """``observer``: words on how to pick the robot whose ghosts are drawn."""
        self.panels = panels
        gui, sc = panels.gui, panels.session.scenario
        with gui.add_folder("Positions", expand_by_default=positions_of(sc) == "slo") as folder:
            self.positions = gui.add_dropdown(
                "positions", tuple(POSITIONS), initial_value=_key(POSITIONS, positions_of(sc)),
                hint="the robots act on true (oracle) or SLO-estimated positions; same seed (rebuilds)")
            errors = sc.slo.errors if sc.slo is not None else NEW_SLO["slo.errors"]
            self.errors = gui.add_dropdown("error set", tuple(ERROR_SETS), initial_value=_key(ERROR_SETS, errors),
                                           hint="sensor errors of Tab. 4.3 (range and odometry); applies at once")
            self.readout = gui.add_markdown("")
            gui.add_markdown("*Ghosts (blue diamonds): where the selected robot believes the others are; "
                             "segments join them to the truth, green to red. The large one: where it "
                             f"believes the global best is.{observer}*")
        panels.top.append(folder)
        self.folder = folder

        @self.positions.on_update
        def _(event: Any) -> None:
            if self.panels._syncing:
                return
            value = POSITIONS.get(self.positions.value)
            here = self.panels.session.scenario
            if value is not None and value != positions_of(here):
                self.panels.apply(switch_changes(here, value), f"positions = {self.positions.value}")

        @self.errors.on_update
        def _(event: Any) -> None:
            if self.panels._syncing:
                return
            value = ERROR_SETS.get(self.errors.value)
            slo = self.panels.session.scenario.slo
            if value is not None and slo is not None and value != slo.errors:
                self.panels.apply({"slo.errors": value, "slo.error_values": {}}, f"error set = {self.errors.value}")

    def sync(self, sc: Scenario) -> None:
        """Push ``sc`` into the handles (call inside the panels' sync guard)."""
        put = self.panels._set
        put(self.positions, _key(POSITIONS, positions_of(sc)))
        if sc.slo is not None:
            put(self.errors, _key(ERROR_SETS, sc.slo.errors))
        self.errors.visible = positions_of(sc) == "slo"

    def refresh(self, ghosts: Ghosts | None, live: bool = True) -> None:
        text = ghost_text(ghosts) if live else "A recorded frame: beliefs are not recorded."
        if self.readout.content != text:
            self.readout.content = text

    def compare_choices(self, sc: Scenario) -> dict[str, dict[str, Any]]:
        """B on the other positions (the same seed, so A and B differ only by localisation)."""
        if positions_of(sc) == "slo":
            return {"positions: oracle (true)": switch_changes(sc, "oracle")}
        return {"positions: SLO (estimated)": switch_changes(sc, "slo")}
