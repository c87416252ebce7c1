"""Turn a validated :class:`Scenario` into its engine: :func:`build` asks the kinds' registry
(:mod:`.kinds`) for the scenario's kind and calls that kind's builder (one module per kind in
:mod:`.builders`, imported on first use, so building a Chapter 3 swarm imports no fleet, sonar
or SLO code).

The builders' helpers (``build_fleet``, ``world_for``, ``sonar_params_for``, …) were once all
here; they are still offered under these names, each loaded from its kind's module when first
asked for."""

from __future__ import annotations

import importlib
from typing import Any

from shoal.engine.core.contract import Engine

from .kinds import Builder, kind_for, kind_of
from .models import Scenario, required

__all__ = ["Builder", "build", "build_slo", "kind_of"]


def build(scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Engine:
    """The engine of whatever the scenario describes (:func:`kind_of`), for runs ``first_run …
    first_run + runs − 1`` of the seed (default: the preset's)."""
    return kind_for(scenario).build(scenario, runs=runs, seed=seed, first_run=first_run)


def build_slo(scenario: Scenario, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Engine:
    """An ``[slo]`` scene: Mai's SLO swarm, or the scene's own swarm (``swarm = "host"``) on
    SLO-estimated (or, with ``positions = "oracle"``, true) positions with the same seed."""
    required(scenario.slo, "slo")
    return build(scenario, runs=runs, seed=seed, first_run=first_run)


_MOVED = {  # name → the builder module that has it now
    **dict.fromkeys(("build_simulation", "policy_for", "law_for", "objective_for", "swarm_keywords"), "swarm"),
    **dict.fromkeys(("build_fleet", "fleet_params_for", "fleet_keywords"), "fleet"),
    **dict.fromkeys(("build_sonar", "sonar_params_for", "sonar_keywords"), "sonar"),
    **dict.fromkeys(("build_slo_swarm", "slo_errors_for", "slo_unit", "slo_localiser_for", "slo_live_changes"), "slo"),
    **dict.fromkeys(("world_for", "world_error", "with_obstacles", "check_world"), "world"),
    "positions_for": "positions",
}


def __getattr__(name: str) -> Any:
    module = _MOVED.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__package__}.builders.{module}"), name)
