"""The experiments of a shared ``shoal serve``: sweeps asked for from the page.

An experiment is a sweep of the tab's scene over one or two fields, run by the machinery of
``shoal sweep`` (the same :class:`~shoal.studies.sweep.plan.SweepPlan`, jobs, seeds and
chunked runs, :func:`~shoal.studies.experiments.runner.iter_jobs`) on the scheduler the
server was given: a local process pool, or a Dask cluster (``shoal serve --scheduler``). Its
finished cells stay in memory (:class:`~shoal.studies.sweep.table.CellTable`); nothing
is written on the server.

Fairness on a shared server:

* one experiment per tab (its owner): another is refused while one is queued or running;
* one queue for the whole server, first come first served, one experiment running at a time,
  holding at most :attr:`Limits.max_queue_runs` cells × runs; a request that does not fit is
  refused, saying how much is queued;
* Cancel drops a queued experiment, or stops a running one within a second or two: the
  scheduler is interrupted, its runs in progress stop at their next step (a local worker that
  does not is killed), and its finished cells are kept; a tab that closes cancels its experiment.

Every change of an experiment (queued, its place in the queue, a chunk of runs, a cell,
the end) is passed to its listener, on whichever thread made it: the page's panel.
"""

from __future__ import annotations

import itertools
import multiprocessing
import sys
import threading
from collections import deque
from typing import Any, Callable, Hashable

from shoal.presets.models import Scenario
from shoal.studies.experiments.runner import iter_jobs
from shoal.studies.experiments.schedulers import LocalPool, Scheduler
from shoal.studies.sweep import outcomes
from shoal.studies.sweep.plan import SweepPlan
from shoal.studies.sweep.table import CellTable

from ..markdown import escape
from .request import ExperimentRequest, Limits, Refused, plan_seconds, resolve

QUEUED, RUNNING, FINISHED, CANCELLED, FAILED = "queued", "running", "finished", "cancelled", "failed"
CHUNK = 10  # runs per task at most: the progress bar moves after each chunk
STOP_SECONDS = 10.0  # stop() waits this long for the running experiment to end (it is interrupted)

Listener = Callable[["Experiment"], None]


class Experiment:
    """One tab's sweep: its plan, its finished cells and where it stands (``phase``)."""

    def __init__(self, number: int, owner: Hashable, plan: SweepPlan, outcome: str, name: str,
                 seconds: float | None = None) -> None:
        self.number, self.owner, self.plan, self.outcome, self.name = number, owner, plan, outcome, name
        self.seconds = plan_seconds(plan) if seconds is None else seconds  # estimated CPU
        self.table = CellTable(plan)
        self.phase = QUEUED
        self.place = 0  # in the queue: 1 = next to run
        self.runs_done = 0
        self.error = ""
        self._cancel = threading.Event()
        self._listener: Listener | None = None

    @property
    def cost(self) -> int:
        """Cells that run × runs."""
        return self.cells * self.plan.runs

    @property
    def cells(self) -> int:
        """The cells that run (a grid's cells but those left out as invalid)."""
        return len(self.plan.runnable)

    @property
    def over(self) -> bool:
        return self.phase in (FINISHED, CANCELLED, FAILED)

    @property
    def cancelling(self) -> bool:
        return self._cancel.is_set() and not self.over

    def listen(self, listener: Listener | None) -> None:
        """Send every change to ``listener`` (replacing the previous one; None: to nobody)."""
        self._listener = listener

    def changed(self) -> None:
        listener = self._listener
        if listener is None:
            return
        try:
            listener(self)
        except Exception as err:  # a broken page must not stop the queue
            print(f"shoal: experiment listener failed: {err!r}", file=sys.stderr)

    def status(self) -> str:
        """Where it stands, in words (markdown: the error's text escaped)."""
        cells, done = int(self.cells), len(self.table)
        runs = f"{self.runs_done:d} of {self.cost:d} runs"
        left_out = f" ({len(self.plan.skipped):d} invalid left out)" if self.plan.skipped else ""
        if self.phase == QUEUED:
            return f"queued: {self.place:d}{_ordinal(self.place)} in the server's queue"
        if self.phase == RUNNING:
            return f"{'cancelling' if self.cancelling else 'running'}: {done} of {cells} cells{left_out}, {runs}"
        if self.phase == FINISHED:
            return f"finished: {cells:d} cells × {self.plan.runs:d} runs{left_out}"
        if self.phase == CANCELLED:
            return f"cancelled: {done} of {cells} cells finished and kept"
        return f"failed after {done} of {cells} cells: {escape(self.error)}"


def _ordinal(n: int) -> str:
    return "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")


def experiment_pool(workers: int) -> LocalPool:
    """Local worker processes for a server's experiments. They start from a forkserver (never
    forked from the server and its threads) that has the sweep code imported already."""
    multiprocessing.get_context("forkserver").set_forkserver_preload([outcomes.__name__])
    return LocalPool(workers, start="forkserver")


class ExperimentService:
    """The server's queue of experiments and the thread that runs them on ``scheduler``."""

    def __init__(self, scheduler: Scheduler, limits: Limits | None = None, *, simulate: Any = outcomes.simulate_cell,
                 chunk: int = CHUNK, owns_scheduler: bool = False) -> None:
        self.scheduler, self.limits = scheduler, limits or Limits()
        self.owns_scheduler = owns_scheduler  # stop() closes it (a Dask client made for this service)
        self.simulate, self.chunk = simulate, chunk
        self._cond = threading.Condition()
        self._queue: deque[Experiment] = deque()
        self._running: Experiment | None = None
        self._owners: dict[Hashable, Experiment] = {}
        self._checking: set[Hashable] = set()  # owners whose request is being checked
        self._numbers = itertools.count(1)
        self._stopping = False
        self._thread = threading.Thread(target=self._loop, name="shoal-experiments", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ asking
    def queued_runs(self) -> int:
        """Cells × runs of the experiments queued or running."""
        with self._cond:
            return self._load()

    def _load(self) -> int:
        return sum(e.cost for e in self._queue) + (self._running.cost if self._running else 0)

    def _seconds(self) -> float:
        """Estimated CPU seconds of the experiments queued or running."""
        return sum(e.seconds for e in self._queue) + (self._running.seconds if self._running else 0.0)

    def experiment(self, owner: Hashable) -> Experiment | None:
        """The owner's latest experiment (running, queued or over), if any."""
        with self._cond:
            return self._owners.get(owner)

    def _busy(self, owner: Hashable) -> str | None:
        old = self._owners.get(owner)
        if owner in self._checking or (old is not None and not old.over):
            return "this tab already has an experiment queued or running: wait for it, or Cancel it first"
        return None

    def submit(self, owner: Hashable, scenario: Scenario, request: ExperimentRequest,
               listener: Listener | None = None) -> Experiment:
        """Queue ``request`` on ``scenario`` for ``owner`` (a tab), or raise :class:`Refused`."""
        with self._cond:
            if self._stopping:
                raise Refused(["the server is stopping"])
            if (why := self._busy(owner)) is not None:
                raise Refused([why])
            self._checking.add(owner)
        try:
            plan, outcome = resolve(scenario, request, self.limits)
            seconds = plan_seconds(plan)
            with self._cond:
                need, load, cap = len(plan.runnable) * plan.runs, self._load(), self.limits.max_queue_runs
                if load + need > cap:
                    raise Refused([f"the server's queue holds {load} of its {cap} cells × runs and this experiment "
                                   f"needs {need}: try again when it has room, or ask for fewer cells or runs"])
                busy, budget = self._seconds(), self.limits.max_queue_seconds
                if busy + seconds > budget:
                    raise Refused([f"the server's queue holds about {busy / 60:.0f} of its {budget / 60:.0f} CPU "
                                   f"minutes and this experiment needs about {seconds / 60:.1f}: try again when "
                                   "it has room, or ask for less"])
                exp = Experiment(next(self._numbers), owner, plan, outcome, scenario.name, seconds)
                exp.listen(listener)
                self._queue.append(exp)
                self._owners[owner] = exp
                self._renumber()
                self._cond.notify_all()
        finally:
            with self._cond:
                self._checking.discard(owner)
        exp.changed()
        return exp

    def cancel(self, owner: Hashable) -> Experiment | None:
        """Cancel the owner's experiment: a queued one at once, a running one within a second or
        two (the scheduler is interrupted; its finished cells are kept). Returns it (None if there
        was none to cancel)."""
        with self._cond:
            exp = self._owners.get(owner)
            if exp is None or exp.over:
                return None
            exp._cancel.set()
            moved = []
            if exp in self._queue:
                self._queue.remove(exp)
                exp.phase = CANCELLED
                moved = self._renumber()
            running = exp is self._running
        if running:
            self._interrupt()
        for e in (exp, *moved):
            e.changed()
        return exp

    def _interrupt(self) -> None:
        """Stop the runs in progress on the scheduler (it runs one experiment at a time)."""
        interrupt = getattr(self.scheduler, "interrupt", None)
        if interrupt is not None:
            try:
                interrupt()
            except Exception as err:  # a lost cluster: the experiment ends when its chunks do
                print(f"shoal: could not interrupt the experiment's runs: {err!r}", file=sys.stderr)

    def close_owner(self, owner: Hashable) -> None:
        """The owner's tab closed: cancel its experiment and forget it."""
        with self._cond:
            exp = self._owners.get(owner)
        if exp is not None:
            exp.listen(None)
            self.cancel(owner)
        with self._cond:
            self._owners.pop(owner, None)

    def _renumber(self) -> list[Experiment]:
        """Set every queued experiment's place; returns those whose place changed."""
        moved = []
        for place, e in enumerate(self._queue, start=1):
            if e.place != place:
                e.place = place
                moved.append(e)
        return moved

    # ------------------------------------------------------------------ running
    def _loop(self) -> None:
        while True:
            with self._cond:
                while not self._queue and not self._stopping:
                    self._cond.wait()
                if self._stopping:
                    return
                exp = self._queue.popleft()
                exp.phase, exp.place = RUNNING, 0
                self._running = exp
                moved = self._renumber()
            for e in (exp, *moved):
                e.changed()
            try:
                self._run(exp)
            except Exception as err:  # a scheduler that fails (a lost cluster) ends this experiment only
                exp.error = f"{type(err).__name__}: {err}"[:300]
                exp.phase = FAILED
            finally:
                with self._cond:
                    self._running = None
            exp.changed()

    def _run(self, exp: Experiment) -> None:
        def progress(runs: int) -> None:
            exp.runs_done += runs
            exp.changed()

        jobs = [exp.plan.job(i) for i in exp.plan.runnable]
        for key, batch in iter_jobs(jobs, scheduler=self.scheduler, progress=progress, chunk=self.chunk,
                                    simulate=self.simulate, merge=outcomes.merge, desc="experiment",
                                    cancelled=exp._cancel.is_set):
            exp.table.add(key, batch)
            exp.changed()
        exp.phase = FINISHED if len(exp.table) == exp.cells else CANCELLED

    def stop(self) -> None:
        """Cancel everything, stop the thread, close the scheduler if it is this service's."""
        with self._cond:
            self._stopping = True
            queued, running = list(self._queue), self._running
            self._queue.clear()
            for e in queued:
                e.phase = CANCELLED
            if running is not None:
                running._cancel.set()
            self._cond.notify_all()
        if running is not None:
            self._interrupt()
        for e in queued:
            e.changed()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout=STOP_SECONDS)
        close = getattr(self.scheduler, "close", None)
        if self.owns_scheduler and close is not None:
            close()
