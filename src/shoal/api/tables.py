"""Tables of results: a pandas DataFrame when pandas is installed, else a numpy record array.

Both index by column name (``table["best_fitness"]``), so code written for one mostly runs on
the other; pandas is never required.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np


def has_pandas() -> bool:
    try:
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True


def as_table(columns: Mapping[str, Sequence[Any] | np.ndarray], *, pandas: bool | None = None) -> Any:
    """``columns`` (name → equal-length values) as a ``pandas.DataFrame`` (``pandas`` None: when it
    is installed) or a ``numpy.recarray``. Whole-number columns stay integers, text stays text."""
    arrays = {name: _array(v) for name, v in columns.items()}
    lengths = {len(a) for a in arrays.values()}
    if len(lengths) > 1:
        raise ValueError(f"columns of different lengths: {sorted(lengths)}")
    if pandas is None:
        pandas = has_pandas()
    if pandas:
        import pandas as pd

        return pd.DataFrame(arrays)
    n = lengths.pop() if lengths else 0
    if not arrays:
        return np.recarray((n,), dtype=[])
    return np.rec.fromarrays(list(arrays.values()), names=list(arrays))  # type: ignore[call-overload]


def _array(values: Sequence[Any] | np.ndarray) -> np.ndarray:
    a = np.asarray(values)
    if a.dtype == object:  # mixed grid values (text and numbers): as text, as results.csv holds them
        return np.asarray([str(v) for v in values])
    return a
