"""The *Positions* folder of the Chapter 3, fleet and acoustic panels: the switch between true
(oracle) and SLO-estimated positions, the error set, and a readout of the selected robot's
beliefs (what the switch changes in the scenario: :mod:`shoal.app.session.positions`).
"""

from __future__ import annotations

from typing import Any

from shoal.presets.models import Scenario

from ..session.beliefs import Ghosts
from ..session.positions import NEW_SLO, POSITIONS, positions_of, switch_changes
from ..session.session import Session
from ..session.snapshot import Snapshot
from .spec import Dropdown, Folder, Text, Visible

ERROR_SETS = {"None": "none", "Low": "low", "High": "high"}  # Tab. 4.3 (label → preset value)


def label_of(mapping: dict[str, str], value: str) -> str:
    """The label of ``value`` in a label → value ``mapping`` (the value itself if it has none)."""
    return next((k for k, v in mapping.items() if v == value), value)


def ghost_text(ghosts: Ghosts | None) -> str:
    """One line on the selected robot's beliefs."""
    if ghosts is None:
        return "True positions: every robot knows where everyone is (the oracle)."
    if not len(ghosts.of):
        return f"robot {ghosts.observer:d} localised nobody at its last step"
    text = (f"robot {ghosts.observer:d} localises {len(ghosts.of)} robots · mean error "
            f"{ghosts.mean_error:.2f} m · worst {ghosts.error.max():.2f} m")
    if ghosts.best is not None and ghosts.true_best is not None:
        off = float(((ghosts.best - ghosts.true_best) ** 2).sum() ** 0.5)
        text += f" · believes the global best {off:.2f} m off"
    return text


def _positions(s: Session) -> str:
    return label_of(POSITIONS, positions_of(s.scenario))


def _switch(s: Session, label: str) -> dict[str, Any] | None:
    value = POSITIONS.get(label)
    return switch_changes(s.scenario, value) if value is not None and value != positions_of(s.scenario) else None


def _errors(s: Session) -> str:
    slo = s.scenario.slo
    return label_of(ERROR_SETS, slo.errors if slo is not None else NEW_SLO["slo.errors"])


def _set_errors(s: Session, label: str) -> dict[str, Any] | None:
    value, slo = ERROR_SETS.get(label), s.scenario.slo
    return {"slo.errors": value, "slo.error_values": {}} if value is not None and slo is not None \
        and value != slo.errors else None


def _on_slo(s: Session) -> bool:
    return positions_of(s.scenario) == "slo"


def _readout(s: Session, snap: Snapshot) -> str:
    return ghost_text(snap.ghosts) if snap.live else "A recorded frame: beliefs are not recorded."


def positions_folder(observer: str = "", visible: Visible | None = None) -> Folder:
    """The folder; ``observer``: words on how to pick the robot whose ghosts are drawn."""
    return Folder("Positions", key="Positions", expand=False, visible=visible, items=(
        Dropdown("positions", "positions", tuple(POSITIONS), read=_positions, write=_switch,
                 hint="the robots act on true (oracle) or SLO-estimated positions; same seed (rebuilds)"),
        Dropdown("positions.errors", "error set", tuple(ERROR_SETS), read=_errors, write=_set_errors,
                 visible=_on_slo,
                 hint="sensor errors of Tab. 4.3 (range and odometry); applies at once"),
        Text("positions.readout", on_snapshot=_readout),
        Text(text="*Ghosts (blue diamonds): where the selected robot believes the others are; segments join "
                  "them to the truth, green to red. The large one: where it believes the global best is."
                  f"{observer}*"),
    ))


def positions_choices(sc: Scenario) -> dict[str, dict[str, Any]]:
    """B on the other positions (the same seed, so A and B differ only by localisation)."""
    if positions_of(sc) == "slo":
        return {"positions: oracle (true)": switch_changes(sc, "oracle")}
    return {"positions: SLO (estimated)": switch_changes(sc, "slo")}
