"""Oracle or SLO-estimated positions for a Chapter 3 swarm, a fleet or an acoustic scene: the
scenario side of the *Positions* folder, no GUI here.

The switch goes through the model like any control: SLO positions are ``[slo] swarm =
"host"``, ``positions = "slo"`` (a scene without ``[slo]`` gets one: Low errors, CSS, every
robot localising every other); oracle is ``positions = "oracle"``, the very run of the scene
without SLO. Switching rebuilds the swarm with the same seed; the error set and the other
localisation settings retune the running swarm (beliefs kept). The view draws the selected
robot's ghosts (:mod:`.beliefs`); the folder reads out how wrong they are.
"""

from __future__ import annotations

from typing import Any

from shoal.presets.build import slo_live_changes
from shoal.presets.models import Scenario

POSITIONS = {"SLO (estimated)": "slo", "oracle (true)": "oracle"}  # the switch's labels
NEW_SLO = {"slo.errors": "low", "slo.selection": "css", "slo.neighbourhood": "full"}  # a scene without [slo]
ENGINE_ONLY = ("objective", "walk_speed", "quality_threshold")  # SLO_LIVE fields of Mai's swarm only


def positions_of(sc: Scenario) -> str:
    """"slo" when the scene's own swarm acts on SLO-estimated positions, else "oracle"."""
    slo = sc.slo
    return "slo" if slo is not None and slo.swarm == "host" and slo.positions == "slo" else "oracle"


def switch_changes(sc: Scenario, positions: str) -> dict[str, Any]:
    """The preset fields that put ``sc``'s own swarm on ``positions`` ("slo" or "oracle")."""
    if positions == "oracle":
        return {"slo.positions": "oracle"} if sc.slo is not None else {}
    changes: dict[str, Any] = {"slo.swarm": "host", "slo.positions": "slo"}
    return changes if sc.slo is not None else {**changes, **NEW_SLO}


def slo_retune(old: Scenario, new: Scenario) -> dict[str, Any] | None:
    """``retune(slo=...)`` keywords taking a running host swarm from ``old``'s ``[slo]`` to
    ``new``'s: {} when the engine has nothing to change (no change, or oracle positions
    both), None when the change needs a rebuild (the switch, the unit, or a setting that
    cannot change mid-run)."""
    a, b = old.slo, new.slo
    if a == b:
        return {}
    if positions_of(old) != positions_of(new):
        return None
    if positions_of(new) == "oracle":
        return {}  # nothing localises: the run is the scene's without SLO
    if a is None or b is None or a.unit != b.unit:  # (both have an [slo] here: both on SLO positions)
        return None
    changes = slo_live_changes(old, old.model_copy(update={"slo": b}))
    return None if changes is None else {k: v for k, v in changes.items() if k not in ENGINE_ONLY}
