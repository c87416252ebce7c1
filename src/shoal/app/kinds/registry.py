"""The scene kinds the app shows, one for each engine kind: a scenario is shown by the app kind
of the engine kind it describes (:func:`shoal.presets.kinds.kind_for`, the one rule that tells
them apart). Each kind's registry entry (:data:`shoal.presets.kinds.KINDS`) names the module
whose ``KIND`` shows it: the built-in ones here, a plug-in's in its own package."""

from __future__ import annotations

import functools
import importlib
import sys

from shoal.presets import io as presets_io
from shoal.presets import kinds as scene_kinds
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.session import Session
from .base import AppKind


def _app_kind(module: str) -> AppKind:
    """The ``KIND`` of an app module a kind's registry entry names (code the owner installed)."""
    kind = getattr(importlib.import_module(module), "KIND", None)
    if not isinstance(kind, AppKind):
        raise TypeError(f"{module}.KIND is not an AppKind")
    return kind


@functools.cache
def app_kinds() -> dict[str, AppKind]:
    """Engine kind → the app kind that shows it, for every registered kind with an app module.
    A kind whose module does not import or has no ``KIND`` (a plug-in's) is left out with one
    line on stderr: the app shows every other kind."""
    out: dict[str, AppKind] = {}
    for k in scene_kinds.KINDS.values():
        if k.app is None:
            continue
        try:
            out[k.name] = _app_kind(k.app)
        except (Exception, SystemExit) as err:  # noqa: BLE001 - one broken module must not take the others down
            why = f"{type(err).__name__}: {str(err)[:200]}"
            print(f"shoal: the app cannot show {k.label} (kind {k.name!r}): its module {k.app!r} did not load: "
                  f"{why}; SHOAL_PLUGINS=off runs without plug-ins", file=sys.stderr, flush=True)
    return out


def kinds() -> tuple[AppKind, ...]:
    return tuple(app_kinds().values())


def kind_for(scenario: Scenario) -> AppKind:
    """The kind that shows ``scenario`` (:class:`PresetError` if none does)."""
    kind = app_kinds().get(scene_kinds.kind_for(scenario).name)
    if kind is None:
        raise PresetError([f"{scenario.name}: no view for this kind of scene"])
    return kind


def app_kind(session: Session) -> AppKind:
    """The plug-in behind ``session``."""
    return next(k for k in kinds() if k.name == session.kind.name)


def check_supported(scenario: Scenario) -> Scenario:
    """``scenario`` if the browser app can show it, else :class:`PresetError` saying why."""
    return kind_for(scenario).check(scenario)


def session_for(scenario: Scenario) -> Session:
    """A new session of the kind ``scenario`` needs."""
    return kind_for(scenario).session(scenario)


@functools.lru_cache(maxsize=1)
def app_presets() -> dict[str, str]:
    """Shipped presets the browser app can run, name → one-line description."""
    out = {}
    for name, description in presets_io.list_presets().items():
        try:
            check_supported(presets_io.load(name))
        except PresetError:
            continue
        out[name] = description
    return out
