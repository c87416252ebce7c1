"""Medians over seeded runs and their confidence intervals, shared by the Sweep tab
(:mod:`shoal.studies.sweep`) and the reproduction's checks
(:mod:`shoal.studies.experiments.verdict`)."""

from __future__ import annotations

import numpy as np

# first-passage times: a run that never got there has none (NaN/inf), and a median counts it as +inf
FIRST_PASSAGE = frozenset({"steps_to_converge", "time_to_converge_s", "quality_met_at"})
MEDIAN_LEVEL = 0.95  # confidence of the interval drawn round a median


def _over_runs(name: str, values: np.ndarray) -> np.ndarray:
    """The values a median is taken of: a missing first-passage time is +inf, any other
    missing value is left out."""
    v = np.asarray(values, dtype=float)
    return np.where(np.isnan(v), np.inf, v) if name in FIRST_PASSAGE else v[~np.isnan(v)]


def median(name: str, values: np.ndarray) -> float:
    """Median over runs: a first-passage time counts a missing one as +inf (``inf`` when
    fewer than half got there); any other metric ignores missing values."""
    v = _over_runs(name, values)
    return float(np.median(v)) if v.size else float("nan")


def median_interval(name: str, values: np.ndarray, level: float = MEDIAN_LEVEL) -> tuple[float, float]:
    """A distribution-free ``level`` confidence interval of the median over runs, from order
    statistics (``scipy.stats.quantile_test``); missing values as in :func:`median`. ``(nan,
    nan)`` when the runs are too few for that confidence (fewer than 6 at 95 %)."""
    from scipy.stats import quantile_test

    v = _over_runs(name, values)
    if v.size == 0:
        return float("nan"), float("nan")
    m = float(np.median(v))
    ci = quantile_test(v, q=m if np.isfinite(m) else 0.0, p=0.5).confidence_interval(level)
    return float(ci.low), float(ci.high)


def quantile_interval(values: np.ndarray, p: float, level: float = MEDIAN_LEVEL) -> tuple[float, float]:
    """The same for the ``p`` quantile over runs (NaN left out): ``(nan, nan)`` when the runs
    are too few for that confidence."""
    from scipy.stats import quantile_test

    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    if v.size == 0:
        return float("nan"), float("nan")
    q = float(np.quantile(v, p))
    ci = quantile_test(v, q=q if np.isfinite(q) else 0.0, p=p).confidence_interval(level)
    return float(ci.low), float(ci.high)

