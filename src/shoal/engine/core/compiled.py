"""The one way Shoal compiles a kernel: numba, IEEE arithmetic (a division by zero gives inf or
NaN as in numpy, no exception) and no fast-math reordering, so a kernel can repeat numpy's or
pymunk's operations to the bit.

Machine code is cached on disk, so only the first run after an install or a change pays the
compile: in Shoal's folder of the user's cache (``~/.cache/shoal/numba`` on Linux, by
platformdirs; ``NUMBA_CACHE_DIR`` chooses another), else beside the modules, else numba's own
user folder. Where none can be written (a read-only install and an unwritable home, as on some
lab machines and containers) the kernels compile in memory in every process: a slower start,
never an error. ``shoal warmup`` compiles them ahead.

While a process compiles its kernels in the background (:func:`defer`, the app's warm-up), a
kernel that nothing has compiled yet runs as plain Python in every other thread: the same
arithmetic in the same order (numba's IEEE arithmetic without fast-math is Python's), so the
same bits, only slower; an SLO scene, whose kernels have no numpy tick, plays at once instead
of waiting a minute for them (``tests/test_compiled.py`` runs every SLO preset both ways). The
thread that compiles (:func:`compile_here`) always compiles.
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
from numba.core.registry import CPUDispatcher

from . import parallel

config: Any = numba_config  # numba's settings (CACHE_DIR is set when numba starts; its stubs do not list it)
NO_LOCATOR = "no locator available"  # numba's words when no cache folder can be written

F = TypeVar("F", bound=Callable)
_decorating = threading.Lock()  # numba's CACHE_DIR is set only while one of ours is decorated
uncached: list[str] = []  # kernels that compile in memory (no writable cache folder)
_deferred = threading.Event()  # set: a kernel not compiled yet runs as Python outside the compiling thread
_here = threading.local()  # .compiles: this thread compiles (the warm-up's)


def defer(on: bool) -> None:
    """From now on (``on``) a kernel with nothing compiled yet runs as Python in every thread but
    the one that called :func:`compile_here`; ``on=False``: every kernel compiles at its first call."""
    if on:
        _deferred.set()
    else:
        _deferred.clear()


def compile_here() -> None:
    """This thread compiles the kernels it calls (the warm-up's thread, while others run them as Python)."""
    _here.compiles = True


def _compiles_here() -> bool:
    """Does this thread compile: the warm-up's, or a thread of the runs' pool (which carries on a
    call its caller made compiled: :mod:`.parallel`)?"""
    return getattr(_here, "compiles", False) or getattr(parallel._inside, "active", False)


def interpreted(fn: Callable) -> bool:
    """Would a call of kernel ``fn`` in this thread run as Python now (nothing compiled, deferred)?"""
    return _deferred.is_set() and not getattr(fn, "overloads", True) and not _compiles_here()


class Kernel(CPUDispatcher):
    """numba's dispatcher, which runs its Python function while compiling is deferred and nothing
    is compiled yet (:func:`defer`); a compiled kernel calling it calls the compiled one."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        if _deferred.is_set() and not self.overloads and not _compiles_here():
            return self.py_func(*args, **kwargs)
        return CPUDispatcher.__call__(self, *args, **kwargs)


def _kernel(dispatcher: Any) -> Any:
    dispatcher.__class__ = Kernel  # (same object, one more method: numba types it as its dispatcher)
    return dispatcher


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
            return cast(F, _kernel(njit(cache=True, error_model="numpy", nogil=True)(fn)))  # a Dispatcher, called as fn
        except RuntimeError as err:
            if NO_LOCATOR not in str(err):
                raise
            uncached.append(fn.__qualname__)
            return cast(F, _kernel(njit(cache=False, error_model="numpy", nogil=True)(fn)))
        finally:
            config.CACHE_DIR = before


def f64(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous float64 array, as the kernels take their float inputs (no copy if it is one)."""
    return np.ascontiguousarray(a, dtype=float)
