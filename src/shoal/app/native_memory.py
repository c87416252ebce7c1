"""Let the server give back the memory a closed tab frees.

Each new tab makes viser read, serialise and compress several megabytes at once (plotly's
JavaScript bundle among them) on one of its many threads. glibc's ``malloc`` serves blocks
that large with ``mmap`` and returns them on ``free`` at first, but each such free raises its
threshold (up to 32 MiB), after which they come from per-thread heaps that keep the freed
pages: the server's resident memory grew by about 5 MiB for every tab that came and went
(``benchmarks/bench_tabs_memory.py``). Fixing the threshold at glibc's default of 128 KiB
keeps large blocks on ``mmap``, so their memory goes back the moment they are freed.

Smaller blocks (a frame of a tab's history, a panel's messages: under 128 KiB each) come
from those heaps too; a closed tab frees them, but glibc returns a heap's free pages only at
its top, so tens of megabytes stayed resident after a mixed session of tabs (a 10-minute soak
went from 305 to 424 MB). :func:`give_back` asks glibc to return every free page
(``malloc_trim(0)``); the server calls it a few seconds after a tab closes (``TRIM_DELAY``),
after a garbage collection (a closed tab's objects in reference cycles are freed then, not at
Python's next full collection).
"""

from __future__ import annotations

import ctypes
import ctypes.util
from typing import Any

M_MMAP_THRESHOLD = -3  # mallopt parameter (glibc malloc.h)
TRIM_DELAY = 3.0  # s after a tab closes (its retired panels and viser's handles are gone by then) to give back
MMAP_THRESHOLD = 128 * 1024  # glibc's initial value, no longer raised on free


def _libc() -> Any:
    name = ctypes.util.find_library("c")
    try:
        return ctypes.CDLL(name) if name else None
    except OSError:
        return None


def give_back() -> bool:
    """Return the C heap's free pages to the system (glibc's ``malloc_trim(0)``); False (and
    nothing done) on other C libraries."""
    trim = getattr(_libc(), "malloc_trim", None)
    if trim is None:
        return False
    trim.argtypes, trim.restype = (ctypes.c_size_t,), ctypes.c_int
    return bool(trim(0))


def keep_large_blocks_returnable() -> bool:
    """Fix glibc's mmap threshold; returns False (and does nothing) on other C libraries."""
    name = ctypes.util.find_library("c")
    try:
        mallopt = ctypes.CDLL(name).mallopt if name else None
    except (OSError, AttributeError):
        mallopt = None
    if mallopt is None:
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD))
