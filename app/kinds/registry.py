"""The scene kinds the app shows, in the order they are asked: from the highest ``priority``
down, the first kind that accepts a scenario shows it. (Mai's SLO swarm before the acoustic
swarm, both before the Chapter 3 swarm, which would accept any scene without a world.)

A new kind is one more module in :mod:`shoal.app.kinds` and one more entry in ``KINDS``."""

from __future__ import annotations

import functools

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..session.session import Session
from . import fleet, mai, sonar, swarm
from .base import AppKind

KINDS: tuple[AppKind, ...] = tuple(sorted((swarm.KIND, fleet.KIND, sonar.KIND, mai.KIND),
                                          key=lambda kind: -kind.priority))
BY_NAME = {kind.name: kind for kind in KINDS}


def kind_for(scenario: Scenario) -> AppKind:
    """The kind that shows ``scenario`` (:class:`PresetError` if none does)."""
    for kind in KINDS:
        if kind.accepts(scenario):
            return kind
    raise PresetError([f"{scenario.name}: no view for this kind of scene"])


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
