"""Compiling the kernels without making anyone wait for them.

A process compiles Shoal's numba kernels the first time it calls them (a minute or more after
an install; later processes load them from the disk cache, engine/core/compiled.py). The
numpy ticks of the Chapter 3 swarm, the fleet and the acoustic swarm are the compiled ticks'
references, bit for bit (docs/architecture.md, "Compiled kernels"), and a run may change from one to the other
between two ticks with the same numbers (tests/test_warmup.py). So:

- :class:`Warmup` compiles the kernels of each group of scenes in a daemon thread, by a few
  steps of every shipped preset of the group, the group asked for first (and before that the
  few that building a scene calls, so that opening one never waits long);
- a scene whose group is not ready runs on its numpy tick meanwhile (:meth:`Warmup.use`) and
  changes over once it is (the acoustic swarm's one kernel is its receiver's correlation);
  scenes on SLO positions and Mai's SLO swarm have no numpy tick: they wait for theirs
  (:meth:`Warmup.waits`);
- :meth:`Warmup.status` says what is being compiled, for the app's status line;
- ``shoal warmup`` runs it in the foreground (a machine that wants it done ahead).

A process that never starts a warm-up (a study's worker, a test that builds an engine) compiles
on first call, as before.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import Any, Callable

from shoal.presets.build import build, kind_of
from shoal.presets.io import list_presets, load
from shoal.presets.models import Scenario

STEPS = 3  # of each preset: every kernel a tick calls, at the argument types the app and `shoal run` use
ORDER = ("swarm", "fleet", "sonar", "slo")  # groups of scenes with kernels
NUMPY_TICK = ("swarm", "fleet", "sonar")  # groups whose engines take ``compiled = False``


def group_of(scenario: Scenario) -> str:
    """The kernels a scene needs: ``slo`` (Mai's swarm, or any swarm on SLO-estimated positions),
    else its kind (``swarm``, ``fleet``, ``sonar``)."""
    slo = scenario.slo
    if slo is not None and (slo.swarm == "slo" or slo.positions != "oracle"):
        return "slo"
    return kind_of(scenario)


def groups() -> dict[str, list[str]]:
    """The shipped presets of each group with kernels, by name."""
    out: dict[str, list[str]] = {g: [] for g in ORDER}
    for name in list_presets():
        group = group_of(load(name))
        if group in out:
            out[group].append(name)
    return out


class Warmup:
    """The kernels of each group compiled in this process, in the background or the foreground."""

    def __init__(self) -> None:
        self.ready = {g: threading.Event() for g in ORDER}
        self.started: float | None = None  # time.monotonic() when it began
        self.finished: float | None = None
        self.current: str | None = None  # the group being compiled
        self.done = 0  # presets warmed
        self.total = 0
        self.error: str | None = None
        self.revision = 0  # moves with each preset warmed (the status line's cue)
        self.scheduled: set[str] = set()  # the groups this warm-up compiles (others compile on first call)
        self._order: list[str] = list(ORDER)
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    # ------------------------------------------------------------------ what a scene does meanwhile
    @property
    def active(self) -> bool:
        """Was a warm-up started in this process (else kernels compile on first call, as ever)?"""
        return bool(self.scheduled)

    def is_ready(self, group: str) -> bool:
        """Are ``group``'s kernels compiled, or left to compile on first call (not scheduled)?"""
        return group not in self.scheduled or self.ready[group].is_set()

    def use(self, sim: Any, scenario: Scenario) -> None:
        """Before a tick: ``sim`` on its compiled tick if its kernels are ready (or no warm-up
        runs), else on its numpy tick (the same numbers)."""
        if hasattr(sim, "compiled"):  # (a swarm on SLO positions: its own kind's kernels too)
            sim.compiled = not self.active or all(self.is_ready(g) for g in {group_of(scenario), kind_of(scenario)})

    def waits(self, scenario: Scenario) -> bool:
        """Must a scene of ``scenario`` wait for its kernels (no numpy tick to run meanwhile)?"""
        group = group_of(scenario)
        return self.active and group not in NUMPY_TICK and not self.is_ready(group)

    def prefer(self, scenario: Scenario) -> None:
        """Compile the kernels of ``scenario``'s group next (a tab opened a scene that needs them)."""
        group = group_of(scenario)
        with self._lock:
            if group in self._order and not self.is_ready(group):
                self._order.remove(group)
                self._order.insert(0, group)

    def compiling(self) -> bool:
        """Whether the warm-up thread is still at work."""
        return self._thread is not None and self._thread.is_alive()

    def busy_seconds(self) -> int | None:
        """Whole seconds since a warm-up started while it runs (None when none runs)."""
        if self.started is None or self.finished is not None:
            return None
        return int(time.monotonic() - self.started)

    def status(self, scenario: Scenario) -> str | None:
        """A few words for the status line while ``scenario``'s kernels are compiled, else None."""
        if not self.active or all(self.is_ready(g) for g in {group_of(scenario), kind_of(scenario)}):
            return None
        seconds = time.monotonic() - (self.started or time.monotonic())
        progress = f"scene {min(self.done + 1, self.total):d} of {self.total:d}, {seconds:.0f} s"
        if self.waits(scenario):
            return f"waiting for this scene's compiled kernels ({progress})"
        return f"compiling kernels in the background ({progress}); numpy meanwhile, the same numbers"

    # ------------------------------------------------------------------ compiling
    def start(self, first: Scenario | None = None, only: bool = False) -> None:
        """Compile in a daemon thread (once per process): ``first``'s group first; with ``only``
        nothing but that group (``shoal run``)."""
        if first is not None:
            self.prefer(first)
        with self._lock:
            if self._thread is not None:
                return
            group = group_of(first) if only and first is not None else None
            self.started = time.monotonic()
            self.scheduled = {group} & set(ORDER) if group is not None else set(ORDER)
            self._thread = threading.Thread(target=self.run, name="shoal-warmup", daemon=True, kwargs={"only": group})
            self._thread.start()

    def run(self, only: str | None = None, say: Callable[[str], None] | None = None) -> float:
        """Compile every group (or ``only`` one) here and now; returns the seconds it took."""
        self.started = self.started or time.monotonic()
        todo = groups()
        if only is not None:
            todo = {only: todo.get(only, [])}
        self.scheduled = self.scheduled or set(todo) & set(ORDER)
        self.total = sum(len(v) for v in todo.values())
        try:
            for first in NUMPY_TICK:  # what building such a scene compiles (spawning a fleet), first: seconds
                if todo.get(first):
                    build(load(todo[first][0], ["sim.runs=1"]))
            while True:
                with self._lock:
                    group = next((g for g in self._order if g in todo and not self.ready[g].is_set()), None)
                if group is None:
                    break
                self.current = group
                start = time.monotonic()
                for name in todo[group]:
                    sim = build(load(name, ["sim.runs=1"]))
                    if hasattr(sim, "compiled"):
                        sim.compiled = True
                    for _ in range(STEPS):
                        sim.step()
                    sim.info()
                    run = getattr(sim, "run", None)
                    if callable(run):  # the headless block of ticks (shoal run's)
                        run(2)
                    self.done += 1
                    self.revision += 1
                self.ready[group].set()
                if say is not None:
                    say(f"{group}: {len(todo[group])} scenes, {time.monotonic() - start:.1f} s")
        except Exception as err:  # never a crash: the scenes compile on first call instead
            self.error = f"{type(err).__name__}: {err}"
            print(f"shoal: compiling the kernels ahead failed ({self.error}); they compile on first use",
                  file=sys.stderr, flush=True)
            for event in self.ready.values():
                event.set()
        finally:
            self.current = None
            self.finished = time.monotonic()
            self.revision += 1
        return self.finished - self.started


WARMUP = Warmup()  # this process' own: the server, ``shoal run`` and the sessions share it
