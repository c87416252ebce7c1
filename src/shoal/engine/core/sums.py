"""numpy's float64 sums, to the bit, for compiled kernels (numba).

``np.add.reduce`` along a contiguous axis adds by pairwise summation: a run of up to 128
values in eight interleaved partial sums (fewer than eight: one after another from −0), a
longer run halved on a multiple of eight and the halves' sums added; the reduction then adds
its initial +0. Kernels that must give numpy's bits add their rows with these.
"""

from __future__ import annotations

import numpy as np

from .compiled import kernel

BLOCK = 128  # numpy's pairwise-summation block


@kernel
def block_sum(a: np.ndarray, lo: int, n: int) -> float:
    """numpy's pairwise sum of a[lo : lo + n], n ≤ :data:`BLOCK`: one pass from −0 below 8
    values, else 8 interleaved accumulators, then the rest."""
    if n < 8:
        res = -0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        r0, r1, r2, r3 = r0 + a[lo + i], r1 + a[lo + i + 1], r2 + a[lo + i + 2], r3 + a[lo + i + 3]
        r4, r5, r6, r7 = r4 + a[lo + i + 4], r5 + a[lo + i + 5], r6 + a[lo + i + 6], r7 + a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


Stack = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # (the walk's starts, lengths, split flags, sums)


@kernel
def pairwise_stack() -> Stack:
    """Room for :func:`pairwise_sum`'s walk of any length up to 2⁶⁰."""
    return np.empty(192, np.int64), np.empty(192, np.int64), np.empty(192, np.bool_), np.empty(192)


@kernel
def pairwise_sum(a: np.ndarray, lo: int, n: int) -> float:
    """numpy's pairwise sum of a[lo : lo + n] (``np.add.reduce`` along a contiguous axis)."""
    return pairwise_sum_in(a, lo, n, pairwise_stack())


@kernel
def pairwise_sum_in(a: np.ndarray, lo: int, n: int, stack: Stack) -> float:
    """:func:`pairwise_sum` with its stack given: a run longer than a block is halved on a
    multiple of eight and the halves' sums added, recursively (walked here with a stack:
    numba's cache does not keep recursive kernels safely)."""
    if n <= BLOCK:
        return block_sum(a, lo, n)
    los, ns, split, sums = stack
    top, k = 1, 0
    los[0], ns[0], split[0] = lo, n, False
    while top > 0:
        top -= 1
        l, m = los[top], ns[top]
        if m <= BLOCK:
            sums[k] = block_sum(a, l, m)
            k += 1
        elif split[top]:  # both halves summed: add them, left + right
            k -= 1
            sums[k - 1] = sums[k - 1] + sums[k]
        else:
            m2 = m // 2
            m2 -= m2 % 8
            split[top] = True
            los[top + 1], ns[top + 1], split[top + 1] = l + m2, m - m2, False  # right, summed second
            los[top + 2], ns[top + 2], split[top + 2] = l, m2, False  # left, summed first
            top += 3
    return sums[0]
