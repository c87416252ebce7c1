"""Arithmetic whose bits do not depend on the machine: for the steps where a seeded run turns
last bits into a decision.

Two kinds of numpy call give other last bits on other computers with the same packages:

- a matrix product (``@``) goes to the BLAS library, which picks its kernel by CPU (OpenBLAS:
  Haswell, SkylakeX, Zen, …), and with it the order of the sums and whether multiply-adds are
  fused;
- the inverse trigonometric, exponential and logarithm ufuncs (``arccos``, ``arctan2``, ``exp``,
  ``log``, …) have AVX-512 versions that numpy uses only on CPUs with AVX-512, with other last
  bits than the C library's functions it calls elsewhere.

The acoustic bearing (Ch. 7) refines the correlation peak and turns it into rays whose
crossings are kept or dropped by comparisons, so a last bit there changes the run
(``tests/test_portable.py`` runs the golden presets as other CPUs would). These functions give
one answer on every x86-64 CPU: a product summed in index order (numpy's elementwise
arithmetic, or a compiled loop that repeats it), and the C library's ``acos`` (as numpy's own
loop without AVX-512).
"""

from __future__ import annotations

import math

import numpy as np

from .compiled import f64, kernel

_acos = np.frompyfunc(math.acos, 1, 1)


def ordered_matmul(a: np.ndarray, b: np.ndarray, compiled: bool = True) -> np.ndarray:
    """``a @ b`` for ``a`` (…, K) and ``b`` (K, L), each output Σ_k a_k·b_kl added one k after
    another from +0: by numpy's elementwise arithmetic (exact IEEE operations on any CPU) or,
    ``compiled``, by :func:`_ordered_rows` (the same operations in the same order: the same bits)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    K, L = b.shape
    if a.shape[-1] != K:
        raise ValueError(f"ordered_matmul: a has {a.shape[-1]} terms, b has {K}")
    rows = a.reshape(-1, K)
    if compiled:
        out = np.empty((rows.shape[0], L))
        _ordered_rows(f64(rows), f64(b), out)
        return out.reshape(a.shape[:-1] + (L,))
    out, term = np.zeros((rows.shape[0], L)), np.empty((rows.shape[0], L))
    for k in range(K):
        np.multiply(rows[:, k, None], b[k], out=term)
        out += term
    return out.reshape(a.shape[:-1] + (L,))


@kernel
def _ordered_rows(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """out[m, l] = Σ_k a[m, k]·b[k, l], from +0 in the order of k: each product rounded, then
    added (no fused multiply-add: no fast-math)."""
    for m in range(a.shape[0]):
        for q in range(b.shape[1]):
            out[m, q] = 0.0
        for k in range(a.shape[1]):
            x = a[m, k]
            for q in range(b.shape[1]):
                out[m, q] += x * b[k, q]


def arccos(x: np.ndarray) -> np.ndarray:
    """The C library's ``acos`` of every element (float64; ``x`` in [−1, 1])."""
    x = np.asarray(x, dtype=float)
    if x.ndim:
        return _acos(x).astype(float)
    return np.float64(math.acos(float(x)))  # type: ignore[return-value]  # a scalar for a scalar, as numpy's
