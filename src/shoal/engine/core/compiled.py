"""The one way Shoal compiles a kernel: numba, IEEE arithmetic (a division by zero gives inf or
NaN as in numpy, no exception) and no fast-math reordering, so a kernel can repeat numpy's or
pymunk's operations to the bit.

Machine code is cached on disk, so only the first run after an install or a change pays the
compile: in Shoal's folder of the user's cache (``~/.cache/shoal/numba`` on Linux, by
platformdirs; ``NUMBA_CACHE_DIR`` chooses another), else beside the modules, else numba's own
user folder. Where none can be written (a read-only install and an unwritable home, as on some
lab machines and containers) the kernels compile in memory in every process: a slower start,
never an error. ``shoal warmup`` compiles them ahead.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import Any, Callable, TypeVar, cast

import numpy as np
import platformdirs
from numba import njit
from numba.core import config as numba_config

config: Any = numba_config  # numba's settings (CACHE_DIR is set when numba starts; its stubs do not list it)
NO_LOCATOR = "no locator available"  # numba's words when no cache folder can be written

F = TypeVar("F", bound=Callable)
_decorating = threading.Lock()  # numba's CACHE_DIR is set only while one of ours is decorated
uncached: list[str] = []  # kernels that compile in memory (no writable cache folder)


def cache_dir() -> Path:
    """Where kernels are cached when it can be written: ``NUMBA_CACHE_DIR``, else Shoal's folder
    in the user's cache."""
    chosen = os.environ.get("NUMBA_CACHE_DIR")
    return Path(chosen) if chosen else Path(platformdirs.user_cache_dir("shoal", appauthor=False)) / "numba"


def kernel(fn: F) -> F:
    """``fn`` compiled by numba at its first call (each new signature again), cached if it can be."""
    with _decorating:
        before = config.CACHE_DIR
        config.CACHE_DIR = str(cache_dir())  # numba's first choice of folder, for this function only
        try:
            return cast(F, njit(cache=True, error_model="numpy", nogil=True)(fn))  # a Dispatcher, called as fn
        except RuntimeError as err:
            if NO_LOCATOR not in str(err):
                raise
            uncached.append(fn.__qualname__)
            return cast(F, njit(cache=False, error_model="numpy", nogil=True)(fn))
        finally:
            config.CACHE_DIR = before


def f64(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous float64 array, as the kernels take their float inputs (no copy if it is one)."""
    return np.ascontiguousarray(a, dtype=float)
