"""Let the server give back the memory a closed tab frees.

Each new tab makes viser read, serialise and compress several megabytes at once (plotly's
JavaScript bundle among them) on one of its many threads. glibc's ``malloc`` serves blocks
that large with ``mmap`` and returns them on ``free`` at first, but each such free raises its
threshold (up to 32 MiB), after which they come from per-thread heaps that keep the freed
pages: the server's resident memory grew by about 5 MiB for every tab that came and went
(``benchmarks/bench_tabs_memory.py``). Fixing the threshold at glibc's default of 128 KiB
keeps large blocks on ``mmap``, so their memory goes back the moment they are freed.
"""

from __future__ import annotations

import ctypes
import ctypes.util

M_MMAP_THRESHOLD = -3  # mallopt parameter (glibc malloc.h)
MMAP_THRESHOLD = 128 * 1024  # glibc's initial value, no longer raised on free


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
