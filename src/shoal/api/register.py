"""Registering your own variants from Python: :func:`register` puts an entry in the registry of
its type (an objective, a Chapter 3 law, a robot law, an acoustic strategy, an SLO selection or
a scene kind); the presets then accept its name and the app offers it. An installed package
does the same from a function named by an entry point of the group ``shoal.plugins``
(:mod:`shoal.engine.core.plugins`)."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from shoal.engine.core.objectives import OBJECTIVES, ObjectiveFunction
from shoal.engine.core.plugins import Plugin, load_plugins
from shoal.engine.core.registry import Registry
from shoal.engine.pso.laws import LAWS, VelocityLaw
from shoal.presets.kinds import KINDS, SceneKind


def registry_for(entry: Any) -> Registry[Any]:
    """The registry an entry of this type belongs in (``TypeError`` for anything else). The later
    chapters' registries are imported only for an entry that is not of an earlier type."""
    if isinstance(entry, ObjectiveFunction):
        return OBJECTIVES
    if isinstance(entry, VelocityLaw):
        return LAWS
    if isinstance(entry, SceneKind):
        return KINDS
    from shoal.engine.acoustics.strategies import STRATEGIES
    from shoal.engine.robots.laws import ROBOT_LAWS, RobotLaw
    from shoal.engine.slo.selection import SELECTIONS, SelectionRule

    if isinstance(entry, RobotLaw):
        return ROBOT_LAWS
    if isinstance(entry, SelectionRule):
        return SELECTIONS
    if isinstance(entry, type) and callable(getattr(entry, "update", None)) and hasattr(entry, "min_robots"):
        return STRATEGIES  # a Strategy class (its class attributes name it)
    raise TypeError(f"not a registry entry: {entry!r} (an ObjectiveFunction, VelocityLaw, RobotLaw, Strategy "
                    "class, SelectionRule or SceneKind)")


def register(entry: Any, *, replace: bool = False) -> Any:
    """Add ``entry`` to its registry (a taken name is refused unless ``replace``); returns it."""
    return registry_for(entry).register(entry, replace=replace)


def register_objective(name: str, f: Callable[[np.ndarray], np.ndarray], *, label: str | None = None,
                       maximise: bool = False, replace: bool = False) -> ObjectiveFunction:
    """Register ``f``, a vectorised objective of positions (..., d) → (...) (numpy, or numba-compiled),
    as ``objective.kind = name``. It is evaluated at ``(x − objective.source)/objective.scale``."""
    return OBJECTIVES.register(ObjectiveFunction(name, label or name, f, maximise=maximise), replace=replace)


def plugins() -> list[Plugin]:
    """The installed plug-ins (entry points of ``shoal.plugins``), loaded, with any load error."""
    return load_plugins()
