"""Where a scene's own swarm gets its positions: the truth, or SLO estimates with ``[slo] swarm =
"host"`` and ``positions = "slo"`` (the localiser's modules are imported only then)."""

from __future__ import annotations

from typing import Any

from shoal.engine.core.positions import Oracle, PositionSource

from ..models import Scenario, on_slo_positions


def positions_for(scenario: Scenario, world: Any = None) -> PositionSource:
    """The scene's :class:`~shoal.engine.core.positions.PositionSource` (``world``: a fleet's laid-out
    world, which sets the SLO length unit)."""
    if not on_slo_positions(scenario):
        return Oracle()
    from .slo import estimated_for  # (an SLO scene only: a run on true positions never loads the localiser)

    return estimated_for(scenario, world)
