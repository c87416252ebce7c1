"""Checks judged with the uncertainty of their statistic (shoal.studies.experiments.verdict):
holds, fails, or undecided at this run count."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.studies.experiments import verdict as vd
from shoal.studies.experiments.output import check
from shoal.studies.experiments.verdict import Estimate
from shoal.studies.sweep.outcomes import median_interval


def test_a_median_carries_the_sweep_tabs_interval():
    v = np.arange(31, dtype=float)
    e = Estimate.median(v)
    assert e.value == 15.0 and (e.lo, e.hi) == median_interval("x", v) and e.runs == 31
    assert e.lo < 15.0 < e.hi


def test_too_few_runs_for_an_interval_leave_every_comparison_undecided():
    e = Estimate.median([1.0, 2.0, 3.0, 4.0, 5.0])
    assert not e.decided
    for v in (vd.at_least(e, 0.0), vd.at_most(e, 100.0), vd.less(e, Estimate.exact(10.0))):
        assert v.outcome == vd.UNDECIDED and v.runs == 5


def test_a_threshold_inside_the_interval_is_undecided_outside_it_decided():
    e = Estimate.median(np.linspace(0.0, 10.0, 41))
    assert vd.at_least(e, 5.0).outcome == vd.UNDECIDED
    assert vd.at_least(e, 1.0).outcome == vd.HOLDS and vd.at_least(e, 9.0).outcome == vd.FAILS
    assert vd.within(e, 0.0, 10.0).outcome == vd.HOLDS and vd.within(e, 8.0, 10.0).outcome == vd.FAILS


def test_first_passage_times_count_runs_that_never_got_there_as_infinite():
    never = Estimate.median([np.nan] * 20 + [5.0] * 5, first_passage=True)
    assert never.value == math.inf and vd.below(never, math.inf).outcome == vd.FAILS
    sure = Estimate.median([5.0] * 20 + [math.inf] * 5, first_passage=True)
    assert sure.value == 5.0 and vd.below(sure, math.inf).outcome == vd.HOLDS


def test_two_medians_are_compared_interval_against_interval():
    a, b = Estimate.median(np.arange(30.0)), Estimate.median(np.arange(30.0) + 100)
    assert vd.less(a, b).outcome == vd.HOLDS and vd.less(b, a).outcome == vd.FAILS
    c = Estimate.median(np.arange(30.0) + 3)
    assert vd.less(a, c).outcome == vd.UNDECIDED  # overlapping intervals


def test_combinations_fail_on_one_failure_and_wait_on_one_undecided():
    h, f, u = vd.Verdict(vd.HOLDS, 10), vd.Verdict(vd.FAILS, 20), vd.Verdict(vd.UNDECIDED, 5)
    assert vd.all_of(h, u).outcome == vd.UNDECIDED and vd.all_of(h, u, f).outcome == vd.FAILS
    assert vd.all_of(h, h).outcome == vd.HOLDS and vd.all_of(h, f).runs == 10
    assert vd.any_of(f, u).outcome == vd.UNDECIDED and vd.any_of(f, h).outcome == vd.HOLDS
    assert vd.negate(h).outcome == vd.FAILS and vd.negate(u).outcome == vd.UNDECIDED


def test_a_claim_about_the_median_run_is_decided_over_every_run_that_could_be_it():
    fitness = np.arange(40.0)
    collided = np.zeros(40, int)
    assert vd.over_choices(lambda c: c == 0, collided[vd.median_runs(fitness)]).outcome == vd.HOLDS
    collided[21] = 1  # a run near the median collided: it could be the median run
    assert vd.over_choices(lambda c: c == 0, collided[vd.median_runs(fitness)]).outcome == vd.UNDECIDED
    collided[:] = 2
    assert vd.over_choices(lambda c: c == 0, collided[vd.median_runs(fitness)]).outcome == vd.FAILS


def test_a_verdict_that_contradicts_its_point_estimate_is_refused():
    with pytest.raises(ValueError, match="contradicts"):
        check("x", "y", "z", False, vd.exact(True))
    assert check("x", "y", "z", True, vd.Verdict(vd.UNDECIDED, 3))["verdict"] == vd.UNDECIDED


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.0, 100.0), min_size=6, max_size=60), st.floats(0.0, 100.0))
def test_a_decided_verdict_agrees_with_the_point_estimate(values, threshold):
    e = Estimate.median(values)
    for v, point in ((vd.at_least(e, threshold), e.value >= threshold), (vd.below(e, threshold), e.value < threshold)):
        if v.outcome == vd.HOLDS:
            assert point
        if v.outcome == vd.FAILS:
            assert not point


def test_ratios_spread_and_pooled_means_carry_intervals():
    a, b = Estimate.median(np.arange(30.0) + 100), Estimate.median(np.arange(30.0) + 10)
    r = a.ratio(b)
    assert r.lo <= r.value <= r.hi and r.lo > 1
    assert vd.ratio_at_most([a, a], 1.0).outcome == vd.UNDECIDED  # the same interval twice
    m = Estimate.mean(np.full(10, 2.0))
    assert (m.lo, m.value, m.hi) == (2.0, 2.0, 2.0)
    assert not Estimate.mean([1.0, 2.0]).decided
    w = Estimate.spread(np.tile(np.arange(100.0), (3, 1)))
    assert w.lo <= w.value <= w.hi
