"""The contract between a scene kind's engine and everything that drives it: the ``shoal run``
recorder, the sweeps and the browser app.

Every kind (the Chapter 3 swarm, the Chapter 4–5 fleet, the Chapter 6–8 acoustic swarm and
Mai's SLO swarm) simulates ``runs`` independent seeded runs at once and exposes:

* ``state``: run-major arrays of every robot at step ``k`` (:class:`State`);
* ``reset(seed)``, ``step() -> Info`` (one control tick of every run) and ``info() -> Info``
  (the metrics of the current step, also before the first tick);
* ``retune(**changes) -> list[str]``: change settings of a running engine without a restart.
  The class lists the keywords it accepts in ``LIVE``; anything else is refused with a
  ``ValueError`` naming the key, and a refused call changes nothing. It returns the names that
  changed.

:meth:`Info.columns` gives the kind's own metric columns by name, one value per run, as the
class's ``COLUMNS`` schema declares them (name, unit, dtype, description); the recorder writes
the common columns (run, step, t, best fitness, speeds) followed by these. A kind that
optimises nothing has no ``best_fitness`` in its state and none in its metrics.
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from .schema import Schema


@runtime_checkable
class State(Protocol):
    """What the recorder, the history and the views may read of a running engine."""

    k: int  # control ticks since reset
    x: np.ndarray  # (R, N, d) positions
    u: np.ndarray  # (R, N, d) velocities
    heading: np.ndarray  # (R, N) direction of each robot
    status: np.ndarray  # (R, N) int8, 0 = active
    # and, for a kind that optimises something, ``best_fitness`` (R,): the best each run found so far


@runtime_checkable
class Info(Protocol):
    """The metrics of one step."""

    @property
    def t(self) -> float: ...

    def columns(self) -> dict[str, np.ndarray]:
        """The kind's own metric columns by name, each (R,), in the order they are written."""
        ...


@runtime_checkable
class Engine(Protocol):
    """A scene kind's engine: ``runs`` seeded runs (``first_run`` … ``first_run + runs − 1``)."""

    LIVE: ClassVar[frozenset[str]]  # the keywords :meth:`retune` accepts
    COLUMNS: ClassVar[Schema]  # the columns of :meth:`Info.columns`, in order
    runs: int
    seed: int
    first_run: int

    @property
    def state(self) -> State: ...

    @property
    def dt(self) -> float: ...

    @property
    def t(self) -> float: ...

    @property
    def robots(self) -> int: ...

    def reset(self, seed: int | None = None) -> None:
        """Start again from step 0 with ``seed`` (or the current seed)."""
        ...

    def step(self) -> Info:
        """Advance every run by one control tick."""
        ...

    def info(self) -> Info:
        """The metrics of the current step (before the first tick too)."""
        ...

    def retune(self, **changes: Any) -> list[str]:
        """Apply ``changes`` (keywords of ``LIVE``) from the next tick on; the names that changed."""
        ...


def check_live(live: frozenset[str], changes: dict[str, Any]) -> None:
    """Refuse (``ValueError`` naming them) the keywords of ``changes`` outside ``live``."""
    fixed = sorted(set(changes) - live)
    if fixed:
        raise ValueError(f"{', '.join(fixed)}: cannot change mid-run (reset the swarm instead)")
