"""``shoal/<preset>-v0`` for every preset whose kind is an environment (:data:`~shoal.rl.spec.SPECS`).

Each id's entry point is :class:`~shoal.rl.env.ShoalEnv` and its vector entry point
:class:`~shoal.rl.vector.ShoalVectorEnv` (``gymnasium.make_vec(..., vectorization_mode=
"vector_entry_point")``: one batched scene). A plug-in's presets count once its kind's spec is
registered; :func:`register_presets` is run again by ``import shoal.rl`` and by hand after that.
"""

from __future__ import annotations

import warnings
from importlib.metadata import entry_points
from types import ModuleType

import gymnasium

from shoal.api.scene import scenario_of
from shoal.engine.core.plugins import disabled
from shoal.presets.io import PresetError, shipped_names
from shoal.presets.kinds import kind_for

from .spec import SPECS

NAMESPACE = "shoal"
GROUP = "shoal.rl"  # entry points: a function of no arguments that registers a plug-in kind's RLSpec


def load_rl_plugins() -> list[str]:
    """Call every installed entry point of :data:`GROUP` (none with ``SHOAL_PLUGINS=off``), as
    ``shoal.plugins`` are called: only names from the installed packages' metadata, and one that
    fails is reported (a warning), not fatal. The names of those that loaded."""
    loaded = []
    for ep in [] if disabled() else sorted(entry_points(group=GROUP), key=lambda e: e.name):
        try:
            obj = ep.load()
            if callable(obj) and not isinstance(obj, ModuleType):
                obj()
        except Exception as err:  # noqa: BLE001 - a broken plug-in must not take the environments down
            warnings.warn(f"shoal.rl plug-in {ep.name!r} ({ep.value}) did not load: {type(err).__name__}: {err}",
                          stacklevel=2)
        else:
            loaded.append(ep.name)
    return loaded


def env_id(preset: str) -> str:
    return f"{NAMESPACE}/{preset}-v0"


def environment_presets() -> list[str]:
    """The presets whose kind has an RL spec (its robots can be steered), in name order."""
    out = []
    for name in shipped_names():
        try:
            kind = kind_for(scenario_of(name))
        except (PresetError, ValueError):
            continue
        if kind.name in SPECS:  # (the spec declares it; Batch checks the engine takes a steering)
            out.append(name)
    return out


def register_presets() -> list[str]:
    """Register ``shoal/<preset>-v0`` for each of :func:`environment_presets` not registered yet; every id."""
    ids = []
    for name in environment_presets():
        i = env_id(name)
        if i not in gymnasium.registry:
            gymnasium.register(id=i, entry_point="shoal.rl.env:ShoalEnv",
                               vector_entry_point="shoal.rl.vector:ShoalVectorEnv", kwargs={"preset": name})
        ids.append(i)
    return ids
