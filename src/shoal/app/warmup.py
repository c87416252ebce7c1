"""Compiling the kernels without making anyone wait for them.

A process compiles Shoal's numba kernels the first time it calls them (a minute or more after
an install; later processes load them from the disk cache, engine/core/compiled.py). The
numpy ticks of the Chapter 3 swarm, the fleet and the acoustic swarm are the compiled ticks'
references, bit for bit (docs/architecture.md, "Compiled kernels"), and a run may change from one to the other
between two ticks with the same numbers (tests/test_warmup.py). So:

- :class:`Warmup` compiles the kernels of each group of scenes in a daemon thread, by a few
  steps of every shipped preset of the group, the group asked for first. In ``shoal serve`` the
  compiling itself happens in a child process at a lower priority (:func:`warm`, into the disk
  cache both read; numba compiling in the server's own thread held the interpreter's lock for
  most of a minute and slowed every tab), and the thread then loads what it wrote;
- a scene whose group is not ready runs on its numpy tick meanwhile (:meth:`Warmup.use`) and
  changes over once it is (the acoustic swarm's one kernel is its receiver's correlation);
- scenes on SLO positions and Mai's SLO swarm have no numpy tick: while the warm-up runs, every
  kernel not compiled yet runs as plain Python outside its thread, the same numbers
  (:func:`shoal.engine.core.compiled.defer`), so they play at once, slower
  (:meth:`Warmup.interprets`): nothing waits;
- :meth:`Warmup.status` says what is being compiled, for the app's status line;
- ``shoal warmup`` runs it in the foreground (a machine that wants it done ahead).

A process that never starts a warm-up (a study's worker, a test that builds an engine) compiles
on first call, as before.
"""

from __future__ import annotations

import atexit
import os
import sys
import threading
import time
from typing import TYPE_CHECKING, Any, Callable

from shoal.presets.build import build, kind_of
from shoal.presets.io import list_presets, load
from shoal.presets.models import Scenario

if TYPE_CHECKING:  # (subprocess is imported when a child compiles: a short run never starts one)
    import subprocess

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


def warm(names: list[str], done: Callable[[str], None] | None = None) -> None:
    """Compile (or load from the disk cache) the kernels of the shipped presets ``names``: a few
    steps of each, compiled (``done(name)`` after each)."""
    for name in names:
        sim = build(load(name, ["sim.runs=1"]))
        if hasattr(sim, "compiled"):
            sim.compiled = True
        for _ in range(STEPS):
            sim.step()
        sim.info()
        run = getattr(sim, "run", None)
        if callable(run):  # the headless block of ticks (shoal run's)
            run(2)
        if done is not None:
            done(name)


CHILD = """
import sys
from shoal.app.warmup import warm
warm(sys.argv[1:], lambda name: print("warmed", name, flush=True))
"""
CHILD_NICE = 10  # the child compiles below the server and the browser in the machine's eyes
PR_SET_PDEATHSIG = 1  # Linux prctl: a signal for the child when its parent dies


def _child_setup() -> None:
    """In the child, before it runs: a lower priority, and (Linux) an end when the server ends,
    however it ends (an exit that skips Python's clean-up too)."""
    os.nice(CHILD_NICE)
    try:
        import ctypes
        import signal

        ctypes.CDLL(None).prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM))
    except (OSError, AttributeError):  # not Linux: the server's exit stops it (Warmup.stop, at exit)
        pass


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
        self._child: subprocess.Popen | None = None
        self._stopped = False  # stop() was called: compile nothing more

    # ------------------------------------------------------------------ what a scene does meanwhile
    @property
    def active(self) -> bool:
        """Was a warm-up started in this process (else kernels compile on first call, as ever)?"""
        return bool(self.scheduled)

    def is_ready(self, group: str) -> bool:
        """Are ``group``'s kernels compiled, or left to compile on first call (not scheduled)?"""
        return group not in self.scheduled or self.ready[group].is_set()

    def all_ready(self) -> bool:
        """Is every scheduled group compiled (or none scheduled)? Then no scene needs to know its group:
        the ticks ask this first (finding a scene's group costs more than its step)."""
        return all(self.ready[g].is_set() for g in self.scheduled)

    def use(self, sim: Any, scenario: Scenario) -> None:
        """Before a tick: ``sim`` on its compiled tick if its kernels are ready (or no warm-up
        runs), else on its numpy tick (the same numbers)."""
        if hasattr(sim, "compiled"):  # (a swarm on SLO positions: its own kind's kernels too)
            sim.compiled = self.all_ready() or all(self.is_ready(g) for g in {group_of(scenario), kind_of(scenario)})

    def interprets(self, scenario: Scenario) -> bool:
        """Does a scene of ``scenario`` run its kernels as Python now (no numpy tick, not compiled yet)?"""
        if self.all_ready():
            return False
        group = group_of(scenario)
        return group not in NUMPY_TICK and not self.is_ready(group)

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
        if self.interprets(scenario):
            return f"compiling kernels in the background ({progress}); Python meanwhile (slower), the same numbers"
        return f"compiling kernels in the background ({progress}); numpy meanwhile, the same numbers"

    # ------------------------------------------------------------------ compiling
    def start(self, first: Scenario | None = None, only: bool = False, elsewhere: bool = False) -> None:
        """Compile in a daemon thread (once per process): ``first``'s group first; with ``only``
        nothing but that group (``shoal run``); ``elsewhere``: in a child process, the thread
        only loading what it wrote (``shoal serve``)."""
        if first is not None:
            self.prefer(first)
        with self._lock:
            if self._thread is not None:
                return
            group = group_of(first) if only and first is not None else None
            self.started = time.monotonic()
            self.scheduled = {group} & set(ORDER) if group is not None else set(ORDER)
            from shoal.engine.core import compiled  # (numba: only once a warm-up starts)

            compiled.defer(True)  # meanwhile what is not compiled yet runs as Python elsewhere
            self._thread = threading.Thread(target=self.run, name="shoal-warmup", daemon=True,
                                            kwargs={"only": group, "elsewhere": elsewhere})
            self._thread.start()

    def _compile_elsewhere(self, names: list[str]) -> bool:
        """Compile ``names``' kernels in a child process into the disk cache this process reads
        (its progress counted as it goes); False where it cannot (no cache to share, or it failed)."""
        import subprocess

        from shoal.engine.core import compiled

        if compiled.uncached:  # (kernels compiled in memory: a child's work would not reach this process)
            return False
        env = {**os.environ, "NUMBA_CACHE_DIR": str(compiled.cache_dir())}
        try:
            child = self._child = subprocess.Popen([sys.executable, "-c", CHILD, *names], env=env,
                                                   stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                                   preexec_fn=_child_setup)
        except OSError:
            return False
        assert child.stdout is not None
        for line in child.stdout:
            if line.startswith("warmed "):
                self._count()
        code = child.wait()
        self._child = None
        return code == 0

    def stop(self) -> None:
        """End a child still compiling (the server stops; the thread then finds its work undone and
        the scenes compile on first use)."""
        self._stopped = True
        child = self._child
        if child is not None and child.poll() is None:
            child.terminate()

    def run(self, only: str | None = None, say: Callable[[str], None] | None = None, elsewhere: bool = False) -> float:
        """Compile every group (or ``only`` one) here and now (``elsewhere``: in a child process,
        then load it here); returns the seconds it took."""
        from shoal.engine.core import compiled

        compiled.compile_here()
        self.started = self.started or time.monotonic()
        todo = groups()
        if only is not None:
            todo = {only: todo.get(only, [])}
        self.scheduled = self.scheduled or set(todo) & set(ORDER)
        self.total = sum(len(v) for v in todo.values())
        try:
            for first in NUMPY_TICK if not elsewhere else ():  # what building such a scene compiles, first: seconds
                if todo.get(first):
                    build(load(todo[first][0], ["sim.runs=1"]))
            while True:
                with self._lock:
                    group = next((g for g in self._order if g in todo and not self.ready[g].is_set()), None)
                if group is None or self._stopped:
                    break
                self.current = group
                start = time.monotonic()
                if elsewhere and self._compile_elsewhere(todo[group]):
                    warm(todo[group])  # (loaded from the cache the child wrote: seconds)
                elif self._stopped:
                    break
                else:
                    warm(todo[group], lambda name: self._count())
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
            compiled.defer(False)  # (a kernel no preset warmed compiles at its first call, as ever)
        return self.finished - self.started


    def _count(self) -> None:
        self.done += 1
        self.revision += 1


WARMUP = Warmup()  # this process' own: the server, ``shoal run`` and the sessions share it
atexit.register(WARMUP.stop)
