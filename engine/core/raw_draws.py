"""U(0,1) and standard-normal draws of many runs in one compiled call, from blocks of each run's
raw 64-bit outputs, the same numbers as the run's own ``Generator.random`` and
``Generator.standard_normal`` calls one after another.

A ``Generator`` turns its bit generator's 64-bit outputs into doubles in stream order: a U(0,1)
double is one output (its top 53 bits), a normal is numpy's 256-step ziggurat, one output
almost always and a few more in its rare slow paths. :class:`RawDraws` takes the outputs
of many ticks in one ``random_raw`` call a run and repeats both conversions compiled
(the ziggurat tables are numba's copy of numpy's; ``tests/test_raw_draws.py`` compares the
draws and the generators' states with numpy's own calls). The generators run ahead of the
draws used: :meth:`RawDraws.settle` steps each back over the outputs not used (PCG64), before
anything else draws from them.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from numba.np.random._constants import fi_double, ki_double, wi_double, ziggurat_nor_inv_r, ziggurat_nor_r

from .compiled import kernel

TO_DOUBLE = 1.0 / 9007199254740992.0  # 2⁻⁵³
FF, ONE, MANTISSA = np.uint64(0xFF), np.uint64(1), np.uint64(0x000FFFFFFFFFFFFF)
S11, S8 = np.uint64(11), np.uint64(8)


@kernel
def _normal(buf: np.ndarray, r: int, p: int, end: int) -> tuple[float, int]:
    """numpy's ``random_standard_normal`` from run r's outputs at p: (value, next p), or
    (0, −1) if the block ran out first."""
    while True:
        if p >= end:
            return 0.0, -1
        u = buf[r, p]
        p += 1
        idx = int(u & FF)
        u >>= S8
        rabs = (u >> ONE) & MANTISSA
        x = float(rabs) * wi_double[idx]
        if u & ONE:
            x = -x
        if rabs < ki_double[idx]:
            return x, p
        if idx == 0:  # the tail
            while True:
                if p + 2 > end:
                    return 0.0, -1
                xx = -ziggurat_nor_inv_r * math.log1p(-(float(buf[r, p] >> S11) * TO_DOUBLE))
                yy = -math.log1p(-(float(buf[r, p + 1] >> S11) * TO_DOUBLE))
                p += 2
                if yy + yy > xx * xx:
                    return (-(ziggurat_nor_r + xx) if (rabs >> S8) & ONE else ziggurat_nor_r + xx), p
        else:
            if p >= end:
                return 0.0, -1
            v = float(buf[r, p] >> S11) * TO_DOUBLE
            p += 1
            if (fi_double[idx - 1] - fi_double[idx]) * v + fi_double[idx] < math.exp(-0.5 * x * x):
                return x, p


@kernel
def _fill(buf: np.ndarray, pos: np.ndarray, end: np.ndarray, start: int, parts: tuple, normal: np.ndarray) -> int:
    """Runs ``start`` … in turn: each of ``parts`` (R, k) in order, row r from run r's outputs,
    N(0,1) where ``normal`` else U(0,1); the first run whose block ran out (its position
    kept), or −1 when all are done."""
    R, total = parts[0].shape[0], 0
    for s in range(len(parts)):
        total += parts[s].shape[1]
    for r in range(start, R):
        p, e = pos[r], end[r]
        if e - p < total:
            return r
        for s in range(len(parts)):
            a = parts[s]
            if normal[s]:
                for q in range(a.shape[1]):
                    a[r, q], p = _normal(buf, r, p, e)
                    if p < 0:
                        return r
            else:
                if e - p < a.shape[1]:  # the normals before took more than one output each
                    return r
                for q in range(a.shape[1]):
                    a[r, q] = float(buf[r, p + q] >> S11) * TO_DOUBLE
                p += a.shape[1]
        pos[r] = p
    return -1


class RawDraws:
    """Draws of every run of ``rngs`` (PCG64 generators), ``block`` outputs a run fetched at a
    time."""

    def __init__(self, rngs: Sequence[np.random.Generator], block: int) -> None:
        self.rngs, self.block = list(rngs), int(block)
        R = len(self.rngs)
        self.buf = np.empty((R, 0), np.uint64)
        self.pos, self.end = np.zeros(R, np.int64), np.zeros(R, np.int64)

    def fill(self, *arrays: np.ndarray, normal: Sequence[bool]) -> None:
        """Each run r draws ``arrays[0][r]``, ``arrays[1][r]``, … in turn, N(0,1) where ``normal``
        says so, else U(0,1): as ``rngs[r].random(out=a[r])`` or ``rngs[r].standard_normal(out=a[r])``
        one after another. The arrays (R, …) are filled in place."""
        if not all(a.flags.c_contiguous and a.dtype == np.float64 for a in arrays):
            raise ValueError("RawDraws.fill: the arrays are filled in place and must be C-contiguous float64")
        R = len(self.rngs)
        parts, kinds = tuple(a.reshape(R, -1) for a in arrays), np.array(normal, dtype=bool)
        start = _fill(self.buf, self.pos, self.end, 0, parts, kinds)
        while start >= 0:
            self._refill(sum(a.shape[1] for a in parts))
            start = _fill(self.buf, self.pos, self.end, start, parts, kinds)

    def _refill(self, least: int) -> None:
        """Every run: its unused outputs first, then at least ``least`` and ``block`` new ones."""
        fresh = max(self.block, 2 * least)
        tails = [self.buf[r, self.pos[r]:self.end[r]] for r in range(len(self.rngs))]
        width = max(len(t) for t in tails) + fresh
        buf = np.empty((len(self.rngs), width), np.uint64)
        for r, (g, tail) in enumerate(zip(self.rngs, tails)):
            buf[r, :len(tail)] = tail
            buf[r, len(tail):len(tail) + fresh] = g.bit_generator.random_raw(fresh)
            self.end[r] = len(tail) + fresh
        self.buf, self.pos[:] = buf, 0

    def settle(self) -> None:
        """Step every generator back over the outputs not used (whoever draws next gets them)."""
        for r, g in enumerate(self.rngs):
            unused = int(self.end[r] - self.pos[r])
            if unused:
                g.bit_generator.advance(-unused)
        self.buf = np.empty((len(self.rngs), 0), np.uint64)
        self.pos[:] = self.end[:] = 0
