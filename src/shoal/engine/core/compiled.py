"""The one way Shoal compiles a kernel: numba, machine code cached on disk beside the module
(so only the first run after a change pays the compile), IEEE arithmetic (a division by zero
gives inf or NaN as in numpy, no exception) and no fast-math reordering, so a kernel can
repeat numpy's or pymunk's operations to the bit."""

from __future__ import annotations

import numpy as np
from numba import njit

kernel = njit(cache=True, error_model="numpy", nogil=True)


def f64(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous float64 array, as the kernels take their float inputs (no copy if it is one)."""
    return np.ascontiguousarray(a, dtype=float)
