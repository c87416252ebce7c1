"""U(0,1) and standard-normal draws of many runs in one compiled call, taken from each run's
own generator: the same numbers, and the generators left in the same state, as the runs'
``Generator.random`` and ``Generator.standard_normal`` calls one after another.

A ``Generator`` turns its bit generator's 64-bit outputs into doubles in stream order: a U(0,1)
double is one output (its top 53 bits), a normal is numpy's 256-step ziggurat, one output
almost always and a few more in its rare slow paths. :class:`CompiledDraws` calls each bit
generator's C function for the next output through its ``ctypes`` interface (numpy's own
stream, its state stepped in place) and repeats both conversions compiled; the ziggurat tables
are numba's copy of numpy's. ``tests/test_compiled_draws.py`` compares the draws and the
generators' states with numpy's own calls. What a run saves is a Python call a draw: one call
fills every run's arrays, blocks of runs in parallel threads (:mod:`.parallel`) when there are
enough draws to share.
"""

from __future__ import annotations

import ctypes
import math
from typing import Any, Sequence

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic
from numba.np.random._constants import fi_double, ki_double, wi_double, ziggurat_nor_inv_r, ziggurat_nor_r

from . import parallel
from .compiled import kernel

BLOCK_DRAWS = 1 << 15  # draws a thread is given at least

TO_DOUBLE = 1.0 / 9007199254740992.0  # 2⁻⁵³
FF, ONE, MANTISSA = np.uint64(0xFF), np.uint64(1), np.uint64(0x000FFFFFFFFFFFFF)
S11, S8 = np.uint64(11), np.uint64(8)


@kernel
def next_double(next_u64, state: int) -> float:  # next_u64: a C function pointer
    """numpy's next_double: the top 53 bits of the next output."""
    return float(next_u64(state) >> S11) * TO_DOUBLE


@intrinsic
def _next_u64_at(typingctx: Any, fn: Any, state: Any) -> Any:
    """The next 64-bit output of the bit generator whose C function for it is at address ``fn``
    (numpy's ``uint64_t next_uint64(void *state)``), on the state at address ``state``. Both are
    plain integers, so a kernel takes them as cheaply as any number (a ctypes function object
    costs a Python call to type every time the kernel is called)."""
    if not (isinstance(fn, types.Integer) and isinstance(state, types.Integer)):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        void_p = ir.IntType(8).as_pointer()
        f = builder.inttoptr(args[0], ir.FunctionType(ir.IntType(64), [void_p]).as_pointer())
        return builder.call(f, [builder.inttoptr(args[1], void_p)])

    return types.uint64(fn, state), codegen


@kernel
def double_at(fn: int, state: int) -> float:
    """:func:`next_double` with the generator's C function given by its address (:attr:`CompiledDraws.address`)."""
    return float(_next_u64_at(fn, state) >> S11) * TO_DOUBLE  # type: ignore[call-arg]  # (the typing context is numba's)


@kernel
def _normal(next_u64, state: int) -> float:
    """numpy's ``random_standard_normal`` (the ziggurat) on the generator at ``state``."""
    while True:
        u = next_u64(state)
        idx = int(u & FF)
        u >>= S8
        rabs = (u >> ONE) & MANTISSA
        x = float(rabs) * wi_double[idx]
        if u & ONE:
            x = -x
        if rabs < ki_double[idx]:
            return x
        if idx == 0:  # the tail
            while True:
                xx = -ziggurat_nor_inv_r * math.log1p(-next_double(next_u64, state))
                yy = -math.log1p(-next_double(next_u64, state))
                if yy + yy > xx * xx:
                    return -(ziggurat_nor_r + xx) if (rabs >> S8) & ONE else ziggurat_nor_r + xx
        else:
            u01 = next_double(next_u64, state)
            if (fi_double[idx - 1] - fi_double[idx]) * u01 + fi_double[idx] < math.exp(-0.5 * x * x):
                return x


@kernel
def _fill(next_u64, states: np.ndarray, parts: tuple, normal: np.ndarray) -> None:
    """Each run r in turn draws row r of each of ``parts`` (R, k) in order, N(0,1) where
    ``normal`` else U(0,1)."""
    for r in range(states.shape[0]):
        state = states[r]
        for s in range(len(parts)):
            a = parts[s]
            if normal[s]:
                for q in range(a.shape[1]):
                    a[r, q] = _normal(next_u64, state)
            else:
                for q in range(a.shape[1]):
                    a[r, q] = next_double(next_u64, state)


class CompiledDraws:
    """Draws of every run of ``rngs``, one PCG64 generator a run (Shoal's streams)."""

    def __init__(self, rngs: Sequence[np.random.Generator]) -> None:
        self.__setstate__({"rngs": list(rngs)})

    def __getstate__(self) -> dict:
        """Only the generators: a copy or an unpickled object finds its own generators' C state."""
        return {"rngs": self.rngs}

    def __setstate__(self, state: dict) -> None:
        self.rngs = state["rngs"]
        if not all(type(g.bit_generator) is np.random.PCG64 for g in self.rngs):
            raise ValueError("CompiledDraws: the generators must be PCG64 (a double is its output's top 53 bits)")
        interfaces = [g.bit_generator.ctypes for g in self.rngs]
        self._next = interfaces[0].next_uint64 if interfaces else None  # PCG64's one C function
        self._states = np.array([c.state_address for c in interfaces], dtype=np.uintp)
        self._address = ctypes.cast(self._next, ctypes.c_void_p).value or 0 if self._next is not None else 0

    @property
    def address(self) -> int:
        """The address of PCG64's C function for the next output, for a kernel's :func:`double_at` (0: no runs)."""
        return self._address

    @property
    def next_u64(self) -> object:
        """PCG64's C function for the next output, for a kernel's :func:`next_double` (None: no runs)."""
        return self._next

    @property
    def states(self) -> np.ndarray:
        """The address of each run's generator state, (R,) ``uintp``, for a kernel's :func:`next_double`."""
        return self._states

    def fill(self, *arrays: np.ndarray, normal: Sequence[bool]) -> None:
        """Each run r draws ``arrays[0][r]``, ``arrays[1][r]``, … in turn, N(0,1) where ``normal``
        says so, else U(0,1): as ``rngs[r].random(out=a[r])`` or ``rngs[r].standard_normal(out=a[r])``
        one after another. The arrays (R, …) are filled in place."""
        if not all(a.flags.c_contiguous and a.dtype == np.float64 for a in arrays):
            raise ValueError("CompiledDraws.fill: the arrays are filled in place and must be C-contiguous float64")
        if self.rngs:
            R = len(self.rngs)
            parts, kinds = tuple(a.reshape(R, -1) for a in arrays), np.array(normal, dtype=bool)
            per_run = sum(a.shape[1] for a in parts)

            def block(lo: int, hi: int) -> None:  # a run's draws touch its own generator and rows only
                _fill(self._next, self._states[lo:hi], tuple(a[lo:hi] for a in parts), kinds)

            parallel.each_block(block, R, min_block=max(1, BLOCK_DRAWS // max(1, per_run)))
