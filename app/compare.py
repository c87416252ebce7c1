"""Same-seed A/B comparison: a second swarm B that runs A's preset and seed with a few fields
overridden, in lock-step with A.

B is a whole session of A's kind, built from A's scenario with ``overrides`` (dotted path →
value) applied and validated by the same pydantic model. It steps, resets and takes A's later
changes together with A, so that (same seed, same result) B differs from A only by its
overrides: with no overrides B is A, step for step.

:class:`CompareMixin` is part of :class:`~shoal.app.base_session.BaseSession`; the helpers
here are pure functions of text and scenarios.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

import numpy as np

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

if TYPE_CHECKING:
    from .base_session import BaseSession

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


class CompareMixin:
    """Swarm B of a session (``twin``): built, changed, stepped and reset with A."""

    twin: BaseSession | None
    overrides: dict[str, Any]

    def enable_compare(self: Any, overrides: dict[str, Any]) -> None:
        """Build B from A's scenario with ``overrides`` and restart A and B from step 0 together.
        Raises :class:`PresetError` (nothing changed) when B's scenario is refused."""
        with self.lock:
            if self.replaying is not None:
                raise PresetError(["compare: a replay is shown; press Reset for a live run first"])
            twin = type(self)(twin_scenario(self.scenario, overrides))  # may refuse: nothing changed
            self.twin, self.overrides = twin, dict(overrides)
            self._reset_locked(self.scenario.sim.seed)
            self.revision += 1

    def disable_compare(self: Any) -> None:
        with self.lock:
            self.twin = None
            self.revision += 1

    def _twin_propose(self: Any, new: Scenario) -> Scenario | None:
        """B's scenario after A goes to ``new`` (None without B); refuses what B cannot take."""
        if self.twin is None:
            return None
        new_b = twin_scenario(new, self.overrides)
        try:
            self.twin.check(new_b)
        except PresetError as err:
            raise PresetError([f"B: {m}" for m in err.messages]) from None
        return new_b

    def _twin_adopt(self: Any, new_b: Scenario | None) -> Scenario | None:
        """B takes its side of A's change first (its old scenario is returned, to undo it)."""
        if self.twin is None or new_b is None:
            return None
        old = self.twin.scenario
        with self.twin.lock:
            self.twin._adopt(new_b)
        return old

    def twin_metric(self: Any, name: str, t: np.ndarray) -> np.ndarray | None:
        """B's metric ``name`` at A's times ``t`` (None without B)."""
        twin = self.twin
        if twin is None:
            return None
        m = twin.metric_arrays()
        if name not in m or not len(m["t"]):
            return None
        return np.interp(np.asarray(t, float), m["t"], m[name])
