"""The built-in kinds' :class:`~shoal.rl.spec.RLSpec` s, one module each."""

from __future__ import annotations

from . import fleet, slo, sonar, swarm

BUILT_IN = (swarm.SPEC, fleet.SPEC, sonar.SPEC, slo.SPEC)
