"""Oracle or SLO-estimated positions for a Chapter 3 swarm, a fleet or an acoustic scene: the
scenario side of the *Positions* folder, no GUI here.

The switch goes through the model like any control: SLO positions are ``[slo] swarm =
"host"``, ``positions = "slo"`` (a scene without ``[slo]`` gets one: Low errors, CSS, every
robot localising every other); oracle is ``positions = "oracle"``, the very run of the scene
without SLO. Switching rebuilds the swarm with the same seed; the error set and the other
localisation settings retune the running swarm (beliefs kept; the rule is the kind's,
``shoal.presets.builders.slo.host_slo_retune``). The view draws the selected
robot's ghosts (:mod:`.beliefs`); the folder reads out how wrong they are.
"""

from __future__ import annotations

from typing import Any

from shoal.presets.models import Scenario, on_slo_positions

POSITIONS = {"SLO (estimated)": "slo", "oracle (true)": "oracle"}  # the switch's labels
NEW_SLO = {"slo.errors": "low", "slo.selection": "css", "slo.neighbourhood": "full"}  # a scene without [slo]


def positions_of(sc: Scenario) -> str:
    """"slo" when the scene's own swarm acts on SLO-estimated positions, else "oracle"."""
    return "slo" if on_slo_positions(sc) else "oracle"


def switch_changes(sc: Scenario, positions: str) -> dict[str, Any]:
    """The preset fields that put ``sc``'s own swarm on ``positions`` ("slo" or "oracle")."""
    if positions == "oracle":
        return {"slo.positions": "oracle"} if sc.slo is not None else {}
    changes: dict[str, Any] = {"slo.swarm": "host", "slo.positions": "slo"}
    return changes if sc.slo is not None else {**changes, **NEW_SLO}

