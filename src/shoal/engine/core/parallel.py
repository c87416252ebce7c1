"""Independent runs on every core: a batch's runs split into contiguous blocks, one block a
thread, each block one call of a compiled kernel that releases the GIL (``nogil``).

A run touches only its own rows (its state, its generator), so a batch gives the same bits
whatever the number of threads, and the same as each run alone. Plain Python threads, not
numba's threading layers: the workqueue layer aborts the process when two threads launch
parallel kernels at once (the app ticks sessions in several threads), GNU OpenMP breaks in a
forked child (the local process pool forks), and TBB would be one more dependency; threads
over blocks need none of them and work wherever numba does.

The thread count is ``NUMBA_NUM_THREADS`` if set, else the cores this process may use;
:func:`set_threads` changes it (``1``: everything in the calling thread).
"""

from __future__ import annotations

import os
import threading
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:  # (concurrent.futures is imported with the first pool: a one-run command never needs it)
    from concurrent.futures import Future, ThreadPoolExecutor

_lock = threading.Lock()
_inside = threading.local()  # set in a pool's threads: a block there runs its own blocks serially
_pool: tuple[int, int, ThreadPoolExecutor] | None = None  # (pid, threads, pool)
_threads: int | None = None
_default: int | None = None  # default_threads(), read once


def default_threads() -> int:
    """``NUMBA_NUM_THREADS`` if it is set, else the cores this process may run on."""
    chosen = os.environ.get("NUMBA_NUM_THREADS")
    if chosen:
        return max(1, int(chosen))
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def threads() -> int:
    """How many threads a batch of runs is split over."""
    global _default
    if _threads is not None:
        return _threads
    if _default is None:
        _default = default_threads()
    return _default


def set_threads(n: int | None) -> None:
    """Split batches over ``n`` threads from now on (None: back to :func:`default_threads`)."""
    global _threads
    if n is not None and (not isinstance(n, int) or n < 1):
        raise ValueError(f"threads: need a whole number >= 1, got {n!r}")
    _threads = n


def blocks(runs: int, n: int | None = None) -> list[tuple[int, int]]:
    """``runs`` split into at most ``n`` (default :func:`threads`) contiguous (lo, hi) blocks of
    near-equal size, in order."""
    n = max(1, min(threads() if n is None else n, runs))
    size, extra = divmod(runs, n)
    out, lo = [], 0
    for b in range(n):
        hi = lo + size + (b < extra)
        out.append((lo, hi))
        lo = hi
    return out


def _executor(n: int) -> ThreadPoolExecutor:
    """The process's pool of ``n`` threads (a new one after a fork or a change of count)."""
    global _pool
    from concurrent.futures import ThreadPoolExecutor

    with _lock:
        pid = os.getpid()
        if _pool is None or _pool[0] != pid or _pool[1] != n:
            if _pool is not None and _pool[0] == pid:
                _pool[2].shutdown(wait=False)
            _pool = (pid, n, ThreadPoolExecutor(n, thread_name_prefix="shoal-runs", initializer=_mark))
        return _pool[2]


def _mark() -> None:
    _inside.active = True


def _forked() -> None:
    """In a forked child: the parent's pool threads do not exist here, and its lock may have been held."""
    global _lock, _pool
    _lock, _pool = threading.Lock(), None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forked)


def each_block(fn: Callable[[int, int], object], runs: int, min_block: int = 1) -> None:
    """``fn(lo, hi)`` for every block of :func:`blocks`, the blocks in parallel threads (the
    first in the calling thread), with blocks of at least ``min_block`` runs; returns when all
    are done and raises the first block's error, if any. Serial inside a pool thread."""
    n = 1 if runs == 1 or getattr(_inside, "active", False) else min(threads(), max(1, runs // max(1, min_block)))
    if n == 1:
        fn(0, runs)
        return
    parts = blocks(runs, n)
    pool = _executor(max(1, threads() - 1))
    futures: list[Future] = [pool.submit(fn, lo, hi) for lo, hi in parts[1:]]
    first: BaseException | None = None
    try:
        fn(*parts[0])
    except BaseException as err:  # wait for the others before raising: they write the same arrays
        first = err
    for fut in futures:
        failed = fut.exception()
        if first is None and failed is not None:
            first = failed
    if first is not None:
        raise first
