"""The scene kinds the app shows, one for each engine kind: a scenario is shown by the app kind
of the engine kind it describes (:func:`shoal.presets.build.kind_of`, the one rule that tells
them apart, Mai's SLO swarm before the acoustic swarm before the fleet before the Chapter 3
swarm).

A new kind is one more module in :mod:`shoal.app.kinds` and one more entry in ``KINDS``."""

from __future__ import annotations

import functools

from shoal.presets import io as presets_io
from shoal.presets.build import kind_of
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.session import Session
from . import fleet, mai, sonar, swarm
from .base import AppKind

KINDS: tuple[AppKind, ...] = (swarm.KIND, fleet.KIND, sonar.KIND, mai.KIND)
BY_NAME = {kind.name: kind for kind in KINDS}
BY_ENGINE = {kind.engine: kind for kind in KINDS}


def kind_for(scenario: Scenario) -> AppKind:
    """The kind that shows ``scenario`` (:class:`PresetError` if none does)."""
    kind = BY_ENGINE.get(kind_of(scenario))
    if kind is None:
        raise PresetError([f"{scenario.name}: no view for this kind of scene"])
    return kind


def app_kind(session: Session) -> AppKind:
    """The plug-in behind ``session``."""
    return BY_NAME[session.kind.name]


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
