"""Arithmetic whose bits do not depend on the machine: for the steps where a seeded run turns
last bits into a decision.

Two kinds of numpy call give other last bits on other computers with the same packages:

- a matrix product (``@``) goes to the BLAS library, which picks its kernel by CPU (OpenBLAS:
  Haswell, SkylakeX, Zen, …), and with it the order of the sums and whether multiply-adds are
  fused;
- the inverse trigonometric, exponential and logarithm ufuncs (``arccos``, ``arctan2``, ``exp``,
  ``log``, …) have AVX-512 versions that numpy uses only on CPUs with AVX-512, with other last
  bits than the C library's functions it calls elsewhere.

The steps that needed care (``tests/test_golden.py::test_golden_on_other_cpus`` runs the golden
presets as other CPUs would):

- the acoustic bearing (Ch. 7) refines the correlation peak and turns it into rays whose
  crossings are kept or dropped by comparisons, so a last bit there changes the run: its
  correlation is :func:`ordered_matmul`, its angle :func:`arccos`;
- Mai's SLO swarm: the angular error e_ang (Tab. 4.2) is the difference of two ``atan2`` of
  nearly the same vector; once an arriving neighbour starts exactly on a geometric candidate
  (entry policy ``geometric_nearest``), many errors are a few 1e-15 rad and their per-run
  median printed in metrics.csv shows the last bits of numpy's AVX-512 ``arctan2``. The
  metric calls the C library's ``atan2`` from a compiled loop (``slo/metric_kernels.py``), the
  headings of the swarm and the attraction–repulsion's ``exp`` use :func:`arctan2` and
  :func:`exp`. (Candidates, CSS, ranges and the PSO use only IEEE
  arithmetic and ``sqrt``; the odometry's rotation numpy's float64 ``cos`` and ``sin``, whose
  loops give the same bits with and without AVX-512.)

These functions give one answer on every x86-64 CPU with AVX2 and FMA or AVX-512: a product
summed in index order (numpy's elementwise arithmetic, or a compiled loop that repeats it), and
the C library's ``acos``, ``atan2`` and ``exp`` (as numpy's own loops without AVX-512), called
from Python's ``math`` or from a numba loop (numba calls the same C functions).
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from . import parallel
from .compiled import config, f64, kernel

_acos = np.frompyfunc(math.acos, 1, 1)
_atan2 = np.frompyfunc(math.atan2, 2, 1)
_exp = np.frompyfunc(math.exp, 1, 1)
# numba calls the C library's atan2 and exp, one element at a time, unless Intel's SVML is installed:
# then LLVM vectorises such loops with SVML's functions (their own last bits, chosen by CPU)
LIBM_KERNELS = not getattr(config, "USING_SVML", False)
ROW_WORK = 1 << 17  # multiply-adds of ordered_matmul a thread is given at least


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
        rows, b = f64(rows), f64(b)

        def block(lo: int, hi: int) -> None:
            _ordered_rows(rows[lo:hi], b, out[lo:hi])

        # rows are independent: blocks of them on every core (the same bits), a block worth a thread
        parallel.each_block(block, rows.shape[0], min_block=max(1, ROW_WORK // max(1, K * L)))
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


def _elementwise(kernel_fn: Callable[..., None], slow: Any, compiled: bool, *args: np.ndarray) -> np.ndarray:
    """``kernel_fn`` (compiled, one element after another) or ``slow`` (numpy calling Python's
    ``math``) over ``args`` broadcast together, float64; both call the C library: the same bits."""
    args = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in args))
    shape = args[0].shape
    if not shape:
        return np.float64(slow(*(float(a) for a in args)))  # type: ignore[return-value]  # a scalar for a scalar
    if compiled and LIBM_KERNELS:
        out = np.empty(shape)
        kernel_fn(*(f64(a).reshape(-1) for a in args), out.reshape(-1))
        return out
    return slow(*args).astype(float)


def arctan2(y: np.ndarray, x: np.ndarray, compiled: bool = True) -> np.ndarray:
    """The C library's ``atan2(y, x)`` of every element pair (float64, broadcast as numpy does)."""
    return _elementwise(_atan2_into, _atan2, compiled, y, x)


def exp(x: np.ndarray, compiled: bool = True) -> np.ndarray:
    """The C library's ``exp`` of every element (float64)."""
    return _elementwise(_exp_into, _exp, compiled, x)


@kernel
def _atan2_into(y: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    for q in range(out.size):
        out[q] = math.atan2(y[q], x[q])


@kernel
def _exp_into(x: np.ndarray, out: np.ndarray) -> None:
    for q in range(out.size):
        out[q] = math.exp(x[q])
