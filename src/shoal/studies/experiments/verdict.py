"""How sure a check is at its run count: it **holds**, it **fails**, or it is **undecided**.

A check compares a statistic over seeded runs (mostly a median) with a threshold or with
another statistic. The statistic carries its 95 % confidence interval, the distribution-free
interval of a median from order statistics that the Sweep tab draws
(:func:`shoal.studies.sweep.outcomes.median_interval`). The check holds when the whole
interval lies on the passing side, fails when it lies wholly on the other, and is undecided
at this run count when it straddles the threshold, or when the runs are too few for an
interval (fewer than 6). Two statistics are compared interval against interval: ``a < b``
holds when a's interval lies below b's, fails when it lies above (or on) it; overlapping
intervals leave it undecided, a conservative test.

Claims about every sample (a proven bound, an identity of two seeded cases) carry no
sampling uncertainty: :func:`exact`. A claim about "the median run" (Rossides Fig. 4-7) is
decided over every run whose value lies inside the interval of the median
(:func:`median_runs`, :func:`over_choices`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..medians import MEDIAN_LEVEL, median, median_interval, quantile_interval

HOLDS, FAILS, UNDECIDED = "holds", "fails", "undecided"
OUTCOMES = (HOLDS, FAILS, UNDECIDED)
FIRST_PASSAGE = "steps_to_converge"  # a name :mod:`..medians` treats as a first-passage time


@dataclass(frozen=True)
class Estimate:
    """A statistic ``value`` with its ``MEDIAN_LEVEL`` interval ``lo`` … ``hi`` over ``runs``
    runs (NaN ends: too few runs for an interval; ``runs`` None: exact, no sampling)."""

    value: float
    lo: float
    hi: float
    runs: int | None = None

    @classmethod
    def median(cls, values: Any, *, first_passage: bool = False) -> "Estimate":
        """The median over runs and its interval; with ``first_passage`` a missing (NaN or
        inf) value is a run that never got there and counts as +inf."""
        v = np.asarray(values, dtype=float).ravel()
        name = FIRST_PASSAGE if first_passage else "value"
        if first_passage:
            v = np.where(np.isinf(v), np.nan, v)
        lo, hi = median_interval(name, v)
        return cls(median(name, v), lo, hi, int(v.size))

    @classmethod
    def mean(cls, values: Any, level: float = MEDIAN_LEVEL) -> "Estimate":
        """The mean over runs with its Student-t interval, for a statistic pooled over runs
        (e.g. an occupancy fraction); no interval from fewer than 6 runs, as for a median."""
        from scipy.stats import t

        v = np.asarray(values, dtype=float).ravel()
        v = v[~np.isnan(v)]
        m = float(v.mean()) if v.size else math.nan
        if v.size < 6:
            return cls(m, math.nan, math.nan, int(v.size))
        half = float(t.ppf(0.5 + level / 2, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size))
        return cls(m, m - half, m + half, int(v.size))

    @classmethod
    def exact(cls, value: float) -> "Estimate":
        return cls(float(value), float(value), float(value), None)

    @classmethod
    def curve_mean(cls, series: Any, start: int = 0, stop: int | None = None) -> "Estimate":
        """The mean over rows ``start:stop`` of the per-row median over runs of ``series``
        (rows × runs), e.g. generations of an error curve; the interval is the mean of the
        per-row interval ends, which covers the mean of the medians at least as often as
        the rows' intervals cover theirs (conservative)."""
        rows = np.asarray(series, dtype=float)[start:stop]
        ests = [cls.median(r) for r in rows]
        return cls(float(np.mean([e.value for e in ests])), float(np.mean([e.lo for e in ests])),
                   float(np.mean([e.hi for e in ests])), rows.shape[1] if rows.ndim == 2 else None)

    @classmethod
    def spread(cls, series: Any, low: float = 0.05, high: float = 0.95) -> "Estimate":
        """The width between the ``low`` and ``high`` quantiles over runs of ``series`` (rows ×
        runs), averaged over the rows; its interval from the quantiles' order-statistic
        intervals (the widest and narrowest widths they allow), averaged likewise."""
        rows = np.asarray(series, dtype=float)
        width, lo, hi = [], [], []
        for r in rows:
            a_lo, a_hi = quantile_interval(r, low)
            b_lo, b_hi = quantile_interval(r, high)
            width.append(float(np.quantile(r, high) - np.quantile(r, low)))
            lo.append(max(b_lo - a_hi, 0.0))
            hi.append(b_hi - a_lo)
        return cls(float(np.mean(width)), float(np.mean(lo)), float(np.mean(hi)), rows.shape[1])

    @property
    def decided(self) -> bool:
        """Whether the interval exists (enough runs)."""
        return not (math.isnan(self.lo) or math.isnan(self.hi))

    def ratio(self, other: "Estimate") -> "Estimate":
        """self / other for positive statistics, with the interval of the two intervals."""
        with np.errstate(all="ignore"):
            value = _div(self.value, other.value)
            lo, hi = _div(self.lo, other.hi), _div(self.hi, other.lo)
        return Estimate(value, lo, hi, _fewest(self.runs, other.runs))

    def scaled(self, k: float) -> "Estimate":
        """k · self, k > 0."""
        return Estimate(k * self.value, k * self.lo, k * self.hi, self.runs)

    def shifted(self, k: float) -> "Estimate":
        """self + k."""
        return Estimate(self.value + k, self.lo + k, self.hi + k, self.runs)

    def interval_text(self, fmt: str = "{:.3g}") -> str:
        """"95 % interval lo … hi", or why there is none."""
        if self.runs is None:
            return "exact"
        if not self.decided:
            return f"no 95 % interval from {self.runs} runs"
        return f"95 % interval {fmt.format(self.lo)} … {fmt.format(self.hi)}"


def range_of(ests: Sequence[Estimate]) -> Estimate:
    """max − min of several statistics, with the narrowest and widest range their intervals allow."""
    vals, los, his = [e.value for e in ests], [e.lo for e in ests], [e.hi for e in ests]
    return Estimate(max(vals) - min(vals), max(max(los) - min(his), 0.0), max(his) - min(los),
                    _fewest(*(e.runs for e in ests)))


def _div(a: float, b: float) -> float:
    if math.isnan(a) or math.isnan(b):
        return math.nan
    if b == 0.0:
        return math.inf if a > 0 else math.nan
    if math.isinf(a) and math.isinf(b):
        return math.nan
    return a / b


def _fewest(*runs: int | None) -> int | None:
    counted = [r for r in runs if r is not None]
    return min(counted) if counted else None


@dataclass(frozen=True)
class Verdict:
    """A check's outcome and the runs behind it (None: exact)."""

    outcome: str
    runs: int | None = None

    def __post_init__(self) -> None:
        if self.outcome not in OUTCOMES:
            raise ValueError(f"outcome: one of {OUTCOMES}, got {self.outcome!r}")

    @property
    def decided(self) -> bool:
        return self.outcome != UNDECIDED


def exact(passed: bool, runs: int | None = None) -> Verdict:
    """A claim about every sample or an identity: no sampling uncertainty."""
    return Verdict(HOLDS if passed else FAILS, runs)


def _judge(sure: bool, surely_not: bool, *ests: Estimate) -> Verdict:
    runs = _fewest(*(e.runs for e in ests))
    if any(not e.decided for e in ests):
        return Verdict(UNDECIDED, runs)
    return Verdict(HOLDS if sure else FAILS if surely_not else UNDECIDED, runs)


def at_least(e: Estimate, t: float) -> Verdict:
    """e ≥ t."""
    return _judge(e.lo >= t, e.hi < t, e)


def above(e: Estimate, t: float) -> Verdict:
    """e > t."""
    return _judge(e.lo > t, e.hi <= t, e)


def at_most(e: Estimate, t: float) -> Verdict:
    """e ≤ t."""
    return _judge(e.hi <= t, e.lo > t, e)


def below(e: Estimate, t: float) -> Verdict:
    """e < t."""
    return _judge(e.hi < t, e.lo >= t, e)


def within(e: Estimate, lo: float, hi: float) -> Verdict:
    """lo ≤ e ≤ hi."""
    return _judge(lo <= e.lo and e.hi <= hi, e.hi < lo or e.lo > hi, e)


def less(a: Estimate, b: Estimate) -> Verdict:
    """a < b, interval against interval."""
    return _judge(a.hi < b.lo, a.lo >= b.hi, a, b)


def at_most_of(a: Estimate, b: Estimate) -> Verdict:
    """a ≤ b, interval against interval."""
    return _judge(a.hi <= b.lo, a.lo > b.hi, a, b)


def close(a: Estimate, b: Estimate, tol: float) -> Verdict:
    """|a − b| ≤ tol: holds when the two intervals together span at most tol, fails when the
    gap between them exceeds it."""
    return _judge(max(a.hi, b.hi) - min(a.lo, b.lo) <= tol, max(a.lo - b.hi, b.lo - a.hi) > tol, a, b)


def ratio_at_most(ests: Sequence[Estimate], k: float) -> Verdict:
    """max / min of several positive statistics ≤ k: holds when the largest upper end is at
    most k times the smallest lower end, fails when the largest lower end exceeds k times
    the smallest upper end."""
    his, los = [e.hi for e in ests], [e.lo for e in ests]
    return _judge(max(his) <= k * min(los), max(los) > k * min(his), *ests)


def all_of(*verdicts: Verdict | Iterable[Verdict]) -> Verdict:
    """Every part holds: fails if one fails, undecided if none fails and one is undecided."""
    vs = _flat(verdicts)
    runs = _fewest(*(v.runs for v in vs))
    if any(v.outcome == FAILS for v in vs):
        return Verdict(FAILS, runs)
    return Verdict(UNDECIDED if any(v.outcome == UNDECIDED for v in vs) else HOLDS, runs)


def any_of(*verdicts: Verdict | Iterable[Verdict]) -> Verdict:
    """Some part holds: holds if one holds, fails if all fail (the dual of :func:`all_of`)."""
    return negate(all_of(negate(v) for v in _flat(verdicts)))


def negate(v: Verdict) -> Verdict:
    return Verdict({HOLDS: FAILS, FAILS: HOLDS}.get(v.outcome, UNDECIDED), v.runs)


def _flat(verdicts: Sequence[Verdict | Iterable[Verdict]]) -> list[Verdict]:
    out: list[Verdict] = []
    for v in verdicts:
        out.extend([v] if isinstance(v, Verdict) else list(v))
    return out


def median_runs(values: Any) -> np.ndarray:
    """Indices of the runs that could be "the median run" of ``values`` (one per run): those
    whose value lies inside the interval of the median (all runs when there is none)."""
    v = np.asarray(values, dtype=float)
    e = Estimate.median(v)
    if not e.decided:
        return np.arange(v.size)
    return np.flatnonzero((v >= e.lo) & (v <= e.hi))


def over_choices(claim: Callable[..., bool], *choices: ArrayLike, runs: int | None = None) -> Verdict:
    """A claim about one value of each of several sets (e.g. a count at each case's median
    run): holds if it holds for every combination, fails if for none, else undecided."""
    distinct = [sorted(set(np.asarray(c).ravel().tolist())) for c in choices]
    results = {bool(claim(*combo)) for combo in itertools.product(*distinct)}
    return Verdict(HOLDS if results == {True} else FAILS if results == {False} else UNDECIDED, runs)


LEVEL = MEDIAN_LEVEL
