"""Where chunks of Monte-Carlo runs execute: this process, a local process pool or a Dask cluster.

A scheduler maps a module-level, picklable function over a list of items and yields
``(index, result)`` as each item finishes, in any order. Results are keyed by the index,
and every chunk of runs is seeded by its run indices, so the outcome never depends on the
scheduler. A lost worker (a killed process, a crashed cluster node) only costs a retry of
the items it was running: the local pool starts a fresh pool for the unfinished items, Dask
reschedules them on the surviving workers.

``interrupt()`` stops the items in progress within a fraction of a second, wherever they run:
the function checks :func:`check_interrupt` as it goes (a cell's runs do, every step) and
raises :class:`Interrupted` once its scheduler was interrupted (a flag the local pool's worker
processes share, an event of the Dask scheduler, a thread's flag in process); a local worker
that does not stop within :data:`GRACE` seconds is killed. The interrupted map then ends
without retrying, and the next one starts afresh.

:func:`using` makes a scheduler the default for every
:func:`~shoal.studies.experiments.runner.run_jobs` call in its block, so a reproduction
target sends its chunks to a cluster without knowing about it.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import socket
import threading
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Callable, Iterator, Protocol, Sequence

from shoal.engine.core import parallel

Item = Any
Results = Iterator[tuple[int, Any]]
CHECK_PERIOD = 0.1  # s between two looks at the interrupt flag in a running item
GRACE = 2.0  # s a local worker has to stop after an interrupt before it is killed
WAIT_TICK = 0.2  # s between two looks, while waiting on items, at whether the map was interrupted
DASK_PERIOD = 0.5  # s between two questions of a Dask worker to the scheduler: interrupted?


class SchedulerError(RuntimeError):
    """A scheduler could not be used (Dask missing, scheduler unreachable, pool broken too often)."""


class Interrupted(Exception):
    """The scheduler running this item was interrupted (the item stops where it is)."""


# ---------------------------------------------------------------------------- worker side
_PROCESS_FLAG: Any = None  # a local pool's worker process: the pool's shared event (set by its initializer)
_thread = threading.local()  # ``flag`` of the item running in this thread (in process, or a Dask worker's thread)


def _install_flag(flag: Any, threads: int | None = None) -> None:
    """A worker process's set-up: the interrupt flag, and its share of the cores for a batch's
    runs (workers × threads ≤ cores: a batch's bytes do not depend on it)."""
    global _PROCESS_FLAG
    _PROCESS_FLAG = flag
    if threads is not None:
        parallel.set_threads(threads)


def check_interrupt() -> None:
    """Raise :class:`Interrupted` if the scheduler running the current item was interrupted
    (looked at every :data:`CHECK_PERIOD` seconds at most: call it as often as convenient)."""
    flag = getattr(_thread, "flag", None) or _PROCESS_FLAG
    if flag is None:
        return
    now = time.monotonic()
    if now < getattr(_thread, "next_look", 0.0):
        return
    _thread.next_look = now + CHECK_PERIOD
    if flag.is_set():
        raise Interrupted()


@contextlib.contextmanager
def _flagged(flag: Any) -> Iterator[None]:
    before = getattr(_thread, "flag", None)
    _thread.flag, _thread.next_look = flag, 0.0
    try:
        yield
    finally:
        _thread.flag = before


class _DaskFlag:
    """The Dask scheduler's event ``name``, seen from a worker (``is_set`` asks the scheduler,
    at most every :data:`DASK_PERIOD` seconds)."""

    def __init__(self, name: str) -> None:
        self.name, self.next_ask, self.set = name, 0.0, False

    def is_set(self) -> bool:
        from distributed import Event

        now = time.monotonic()
        if not self.set and now >= self.next_ask:
            self.next_ask = now + DASK_PERIOD
            try:
                self.set = Event(self.name).is_set()
            except Exception:  # no scheduler to ask (a worker shutting down): carry on
                pass
        return self.set


def _flagged_call(fn: Callable[[Item], Any], item: Item, name: str) -> Any:
    """``fn(item)`` on a Dask worker, interruptible through the event ``name``."""
    with _flagged(_DaskFlag(name)):
        return fn(item)


class Scheduler(Protocol):
    """Runs ``fn(item)`` for every item; ``workers`` = how many items run at once."""

    workers: int

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results: ...

    def describe(self) -> str: ...


class InProcess:
    """Every item in this process, in order (``--workers 1``)."""

    workers = 1

    def __init__(self) -> None:
        self._flag = threading.Event()

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results:
        flag = self._flag = threading.Event()
        with _flagged(flag):
            for i, item in enumerate(items):
                try:
                    res = fn(item)
                except Interrupted:
                    return
                yield i, res

    def interrupt(self) -> None:
        """Stop the item in progress (the map ends)."""
        self._flag.set()

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
        self.context = multiprocessing.get_context(start) if start else multiprocessing.get_context()
        self.broken = 0  # pools that lost a worker process, over every call
        self._lock = threading.Lock()
        self._flag: Any = None  # the running map's event, shared with its worker processes
        self._pool: ProcessPoolExecutor | None = None

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results:
        pending = dict(enumerate(items))
        flag = self.context.Event()
        with self._lock:
            self._flag = flag
        for attempt in range(self.restarts + 2):
            if not pending or flag.is_set():
                return
            if attempt > self.restarts:
                raise SchedulerError(f"the local process pool broke {attempt} times in one batch; giving up")
            if attempt > 0:
                self.broken += 1
            share = max(1, parallel.threads() // self.workers)
            pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self.context, initializer=_install_flag,
                                       initargs=(flag, share))
            with self._lock:
                self._pool = pool
            try:
                futures = {pool.submit(fn, item): i for i, item in pending.items()}
                while futures and not flag.is_set():
                    done, _ = wait(futures, timeout=WAIT_TICK, return_when=FIRST_COMPLETED)
                    while done:
                        fut = done.pop()
                        i = futures.pop(fut)  # a finished future keeps its result: drop it
                        try:
                            res = fut.result()
                        except (BrokenProcessPool, Interrupted):
                            continue  # every unfinished item fails alike; retried by the next pool
                        finally:
                            del fut
                        del pending[i]
                        yield i, res
            finally:
                with self._lock:
                    self._pool = None
                if flag.is_set():
                    _stop_workers(pool)
                else:
                    pool.shutdown(wait=True, cancel_futures=True)

    def interrupt(self) -> None:
        """Stop the items in progress: they stop at their next look at the flag, and a worker
        still running :data:`GRACE` seconds later is killed. The map ends without retrying."""
        with self._lock:
            flag, pool = self._flag, self._pool
        if flag is not None:
            flag.set()
        if pool is not None:
            threading.Thread(target=_kill_after, args=(_workers(pool), GRACE), name="shoal-pool-kill",
                             daemon=True).start()

    def describe(self) -> str:
        return f"local pool of {self.workers} processes"


def _workers(pool: ProcessPoolExecutor) -> list[Any]:
    """The live worker processes of ``pool`` (``ProcessPoolExecutor._processes``, CPython 3.8+)."""
    return [p for p in list((getattr(pool, "_processes", None) or {}).values()) if p.is_alive()]


def _kill_after(processes: list[Any], grace: float) -> None:
    """Kill those of ``processes`` still alive ``grace`` seconds from now."""
    end = time.monotonic() + grace
    while time.monotonic() < end and any(p.is_alive() for p in processes):
        time.sleep(0.05)
    for p in processes:
        if p.is_alive():
            p.kill()


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """After an interrupt: no more items, idle workers leave, and a worker still busy
    :data:`GRACE` seconds later is killed (the shutdown never waits on an item that does not
    look at the flag)."""
    processes = _workers(pool)
    pool.shutdown(wait=False, cancel_futures=True)
    _kill_after(processes, GRACE)
    for p in processes:
        p.join(timeout=GRACE)


SCHEMES = ("tcp", "tls")  # the Dask protocols --scheduler takes (no scheme: tcp)


def scheduler_address(text: str) -> str:
    """``text`` as a Dask scheduler address ``tcp://HOST:PORT`` (or ``tls://``), else
    :class:`SchedulerError` saying what is wrong (an empty value included)."""
    if not isinstance(text, str) or not text.strip():
        raise SchedulerError("--scheduler is empty: give the Dask scheduler's address, tcp://HOST:PORT")
    text = text.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    host, colon, port = rest.rpartition(":")
    host = host.strip("[]")
    if (scheme not in SCHEMES or not colon or not host or not port.isdigit() or not 0 < int(port) < 65536
            or any(c in rest for c in "/?#@ ")):
        raise SchedulerError(f"--scheduler {text[:100]!r}: expected the Dask scheduler's address, tcp://HOST:PORT "
                             f"(or {', '.join(f'{s}://' for s in SCHEMES[1:])})")
    return f"{scheme}://{rest}"


def _probe(address: str, timeout: float) -> None:
    """Raise :class:`SchedulerError` unless something at ``address`` accepts a connection within
    ``timeout`` s and (tcp) speaks first, as a Dask scheduler does (its handshake); a port that
    accepts and stays silent would hang Dask's client."""
    scheme, _, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout) as s:
            if scheme == "tcp":
                s.settimeout(timeout)
                if not s.recv(1):
                    raise SchedulerError(f"the Dask scheduler at {address!r} closed the connection at once")
    except TimeoutError:
        raise SchedulerError(f"nothing at {address!r} answered as a Dask scheduler within {timeout:g} s") from None
    except OSError as err:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address!r}: {err.strerror or err}") from None


class DaskCluster:
    """The workers of a Dask ``distributed`` scheduler at ``address`` (``tcp://HOST:PORT``).
    Each item is one task, retried ``retries`` times if it raises; tasks on a worker that
    dies are rescheduled by Dask itself.

    The address is checked (:func:`scheduler_address`) and probed (:func:`_probe`) before Dask
    connects, and Dask's own connection is given ``timeout`` seconds as well: a bad address, a
    closed port or a port that never answers is a :class:`SchedulerError` in seconds."""

    def __init__(self, address: str, retries: int = 2, timeout: float = 10.0) -> None:
        address = scheduler_address(address)
        try:
            from distributed import Client
        except ImportError:
            raise SchedulerError(
                "--scheduler needs Dask distributed: install shoal[cluster] (pip install 'shoal[cluster]')"
            ) from None
        self.address, self.retries = address, int(retries)
        _probe(address, timeout)
        made: list[Any] = []
        failed: list[BaseException] = []

        def connect() -> None:
            try:
                made.append(Client(address, timeout=timeout, set_as_default=False))
            except BaseException as err:  # handed to the caller's thread
                failed.append(err)

        thread = threading.Thread(target=connect, name="shoal-dask-connect", daemon=True)
        thread.start()
        thread.join(2 * timeout)
        if failed:
            err = failed[0]
            raise SchedulerError(f"cannot reach the Dask scheduler at {address!r}: {err}") from None
        if not made:
            raise SchedulerError(f"the Dask scheduler at {address!r} did not finish connecting within "
                                 f"{2 * timeout:g} s")
        self.client = made[0]
        threads = sum(w.get("nthreads", 1) for w in self.client.scheduler_info()["workers"].values())
        self.workers = max(1, threads)
        self._lock = threading.Lock()
        self._running: tuple[Any, list[Any]] | None = None  # the running map's event and futures

    def map_unordered(self, fn: Callable[[Item], Any], items: Sequence[Item]) -> Results:
        from distributed import Event
        from distributed import as_completed as dask_completed

        n = len(items)
        name = f"shoal-interrupt-{uuid.uuid4().hex}"
        event = Event(name, client=self.client)
        futures = {
            self.client.submit(_flagged_call, fn, item, name, retries=self.retries, pure=False, priority=n - i): i
            for i, item in enumerate(items)
        }  # earlier items first, so earlier jobs finish (and are saved) first
        with self._lock:
            self._running = (event, list(futures))
        try:
            for fut in dask_completed(list(futures), loop=self.client.loop):
                if event.is_set():
                    return
                i = futures.pop(fut)
                try:
                    res = fut.result()  # a held future keeps its result on a worker
                except Exception:
                    if event.is_set():  # interrupted, or cancelled by the interrupt
                        return
                    raise
                del fut
                yield i, res
        finally:
            with self._lock:
                self._running = None
            self.client.cancel([f for f in futures if not f.done()])
            with contextlib.suppress(Exception):
                event.clear()  # (the scheduler forgets an event nobody waits on)

    def interrupt(self) -> None:
        """Stop the tasks in progress (they see the scheduler's event within a second) and
        cancel the others; the map ends."""
        with self._lock:
            running = self._running
        if running is not None:
            event, futures = running
            event.set()
            self.client.cancel(futures)

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
