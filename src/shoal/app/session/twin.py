"""Swarm B (compare): a second session of A's scenario with a few fields changed, built,
changed, stepped and reset together with A, so the two differ only by those fields.

B's overrides are ``dotted.key=value`` lines, read like ``shoal run --set`` and validated by
the preset model; a message about B names B's field (``B: controller.omega …``).
"""

from __future__ import annotations

import copy
import threading
from typing import Any, Callable, Generic, Protocol, TypeVar

import numpy as np

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .history import History, Trails

MAX_OVERRIDES = 40


def parse_overrides(text: str) -> dict[str, Any]:
    """``dotted.key=value`` lines (or ``;``-separated) → {key: value}. Blank lines and ``#``
    comments are skipped; values are read like ``--set`` (TOML literals or bare strings).
    Raises :class:`PresetError` naming a line that is not ``key=value``."""
    out: dict[str, Any] = {}
    for raw in text.replace(";", "\n").splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        key, sep, value = line.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value or " " in key:
            raise PresetError([f"B overrides: {line!r} is not dotted.key=value"])
        out[key] = presets_io.parse_value(value)
    if len(out) > MAX_OVERRIDES:
        raise PresetError([f"B overrides: {len(out)} lines, at most {MAX_OVERRIDES}"])
    return out


def literal(value: Any) -> str:
    """A value as :func:`parse_overrides` reads it back."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def override_text(overrides: dict[str, Any]) -> str:
    return "\n".join(f"{k}={literal(v)}" for k, v in overrides.items())


def twin_scenario(scenario: Scenario, overrides: dict[str, Any]) -> Scenario:
    """``scenario`` with ``overrides`` applied, validated; messages name B's bad fields."""
    data = copy.deepcopy(scenario.model_dump(mode="json"))
    try:
        for key, value in overrides.items():
            presets_io.set_dotted(data, key, value)
        return presets_io.validate(data)
    except PresetError as err:
        raise PresetError([f"B: {m}" for m in err.messages]) from None


def _as_b(err: PresetError) -> PresetError:
    return PresetError([f"B: {m}" for m in err.messages])


class Side(Protocol):
    """What the twin needs of B's session."""

    lock: threading.RLock
    scenario: Scenario
    history: History

    def check(self, scenario: Scenario) -> Scenario: ...

    def advance(self, n: int = 1) -> int: ...

    def adopt(self, new: Scenario) -> None: ...

    def restart(self, seed: int) -> None: ...


S = TypeVar("S", bound=Side)


class Twin(Generic[S]):
    """Swarm B (``b``, a session of the kind of A's) and how it differs from A (``overrides``)."""

    def __init__(self, b: S, overrides: dict[str, Any]) -> None:
        self.b, self.overrides = b, dict(overrides)

    @classmethod
    def of(cls, scenario: Scenario, overrides: dict[str, Any], make: Callable[[Scenario], S]) -> Twin[S]:
        """B for A's ``scenario`` with ``overrides`` (raises :class:`PresetError` naming B's fields)."""
        return cls(make(twin_scenario(scenario, overrides)), overrides)

    def propose(self, new_a: Scenario) -> Scenario:
        """B's scenario after A goes to ``new_a``; refuses what B cannot take."""
        new_b = twin_scenario(new_a, self.overrides)
        try:
            return self.b.check(new_b)
        except PresetError as err:
            raise _as_b(err) from None

    def adopt(self, new_b: Scenario) -> Scenario:
        """B takes its side of A's change; its old scenario is returned, to undo it."""
        old = self.b.scenario
        with self.b.lock:
            self.b.adopt(new_b)
        return old

    def step(self) -> None:
        self.b.advance(1)  # A's end rule decides for both

    def restart(self) -> None:
        with self.b.lock:
            self.b.restart(self.b.scenario.sim.seed)

    def metric(self, name: str, t: np.ndarray) -> np.ndarray | None:
        """B's metric ``name`` at A's times ``t`` (None if B has no such metric yet)."""
        t = np.asarray(t, float)
        with self.b.lock:
            m = self.b.history.metric_around(float(t[0]) if len(t) else 0.0)  # (B's rows from A's first time on)
        if name not in m or not len(m["t"]):
            return None
        return np.interp(t, m["t"], m[name])

    def at(self, k: int) -> tuple[np.ndarray, Trails] | None:
        """B's robots and trails at step ``k`` (None if B has no such step)."""
        with self.b.lock:
            return self.b.history.robots_at(k, self.b.scenario.view.trail_seconds)
