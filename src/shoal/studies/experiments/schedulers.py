"""Where chunks of Monte-Carlo runs execute: this process, a local process pool or a Dask cluster.

A scheduler maps a module-level, picklable function over a list of items and yields
``(index, result)`` as each item finishes, in any order. Results are keyed by the index,
and every chunk of runs is seeded by its run indices, so the outcome never depends on the
scheduler. A lost worker (a killed process, a crashed cluster node) only costs a retry of
the items it was running: the local pool starts a fresh pool for the unfinished items, Dask
reschedules them on the surviving workers.

:func:`using` makes a scheduler the default for every
:func:`~shoal.studies.experiments.runner.run_jobs` call in its block, so a reproduction
target sends its chunks to a cluster without knowing about it.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Callable, Iterator, Protocol, Sequence

Item = Any
Results = Iterator[tuple[int, Any]]


class SchedulerError(RuntimeError):
    """A scheduler could not be used (Dask missing, scheduler unreachable, pool broken too often)."""


class Scheduler(Protocol):
    """Runs ``fn(item)`` for every item; ``workers`` = how many items run at once."""

    workers: int

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results: ...

    def describe(self) -> str: ...


class InProcess:
    """Every item in this process, in order (``--workers 1``)."""

    workers = 1

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results:
        for i, item in enumerate(items):
            yield i, fn(item)

    def describe(self) -> str:
        return "in-process"


class LocalPool:
    """A local process pool of ``workers`` processes. If a worker process dies (the pool
    breaks), the unfinished items go to a fresh pool, at most ``restarts`` times.

    ``start`` is the multiprocessing start method (default: the platform's). A process with
    threads of its own (the app server) uses ``"forkserver"``: its workers are forked from a
    clean single-threaded server process, never from itself."""

    def __init__(self, workers: int, restarts: int = 3, start: str | None = None) -> None:
        if workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self.workers, self.restarts = int(workers), int(restarts)
        self.context = multiprocessing.get_context(start) if start else None
        self.broken = 0  # pools that lost a worker process, over every call

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results:
        pending = dict(enumerate(items))
        for attempt in range(self.restarts + 2):
            if not pending:
                return
            if attempt > self.restarts:
                raise SchedulerError(f"the local process pool broke {attempt} times in one batch; giving up")
            if attempt > 0:
                self.broken += 1
            pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self.context)
            try:
                futures = {pool.submit(fn, item): i for i, item in pending.items()}
                for fut in as_completed(futures):
                    try:
                        res = fut.result()
                    except BrokenProcessPool:
                        continue  # every unfinished item fails alike; retried by the next pool
                    i = futures.pop(fut)  # a finished future keeps its result: drop it
                    del pending[i]
                    yield i, res
            finally:
                pool.shutdown(wait=True, cancel_futures=True)

    def describe(self) -> str:
        return f"local pool of {self.workers} processes"


class DaskCluster:
    """The workers of a Dask ``distributed`` scheduler at ``address`` (``tcp://HOST:PORT``).
    Each item is one task, retried ``retries`` times if it raises; tasks on a worker that
    dies are rescheduled by Dask itself."""

    def __init__(self, address: str, retries: int = 2, timeout: float = 10.0) -> None:
        try:
            from distributed import Client
        except ImportError:
            raise SchedulerError(
                "--scheduler needs Dask distributed: install shoal[cluster] (pip install 'shoal[cluster]')"
            ) from None
        self.address, self.retries = address, int(retries)
        try:
            self.client = Client(address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as err:
            raise SchedulerError(f"cannot reach the Dask scheduler at {address!r}: {err}") from None
        threads = sum(w.get("nthreads", 1) for w in self.client.scheduler_info()["workers"].values())
        self.workers = max(1, threads)

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results:
        from distributed import as_completed as dask_completed

        n = len(items)
        futures = {
            self.client.submit(fn, item, retries=self.retries, pure=False, priority=n - i): i
            for i, item in enumerate(items)
        }  # earlier items first, so earlier jobs finish (and are saved) first
        try:
            for fut in dask_completed(list(futures), loop=self.client.loop):
                i, res = futures.pop(fut), fut.result()  # a held future keeps its result on a worker
                del fut
                yield i, res
        finally:
            self.client.cancel([f for f in futures if not f.done()])

    def describe(self) -> str:
        return f"Dask cluster at {self.address} ({self.workers} worker threads)"

    def close(self) -> None:
        self.client.close()


def local(workers: int) -> InProcess | LocalPool:
    """This process for one worker, else a local pool."""
    return InProcess() if workers == 1 else LocalPool(workers)


_CURRENT: ContextVar[Scheduler | None] = ContextVar("shoal_scheduler", default=None)


def current() -> Scheduler | None:
    """The scheduler set by the innermost :func:`using` block, if any."""
    return _CURRENT.get()


@contextmanager
def using(scheduler: Scheduler | None) -> Iterator[Scheduler | None]:
    """Make ``scheduler`` the default of ``run_jobs`` inside the block (``None``: no change)."""
    if scheduler is None:
        yield None
        return
    token = _CURRENT.set(scheduler)
    try:
        yield scheduler
    finally:
        _CURRENT.reset(token)


@contextmanager
def connect(address: str | None, workers: int = 1) -> Iterator[Scheduler]:
    """A :class:`DaskCluster` at ``address`` (closed on exit), or the local scheduler of
    ``workers`` processes when ``address`` is ``None``."""
    if address is None:
        yield local(workers)
        return
    cluster = DaskCluster(address)
    try:
        yield cluster
    finally:
        cluster.close()
