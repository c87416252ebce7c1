"""Batches sized by cost: how the runner cuts jobs into chunks (every run exactly once, in
consecutive pieces; chunks of about equal cost with several workers, costliest first; whole
jobs with one), and that the estimates rank the engines as their benchmarks do."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from shoal.presets.io import load
from shoal.studies.cost import run_cost
from shoal.studies.experiments.runner import _chunks


@dataclass(frozen=True)
class Costed:
    key: str
    runs: int
    cost: float


@dataclass(frozen=True)
class Plain:
    key: str
    runs: int


def _cover(chunks, jobs) -> None:
    for job in jobs:
        mine = sorted((c.first_run, c.runs) for c in chunks if c.job is job)
        start = 0
        for first, n in mine:
            assert first == start and n >= 1
            start += n
        assert start == job.runs


def test_with_two_workers_chunks_cost_about_the_same_and_the_costliest_go_first():
    jobs = [Costed("cheap", 100, 0.01), Costed("dear", 10, 5.0), Costed("middle", 31, 0.3)]
    chunks = _chunks(jobs, 1000, None, workers=2)
    _cover(chunks, jobs)
    costs = [c.runs * c.job.cost for c in chunks]
    assert costs == sorted(costs, reverse=True)
    share = sum(j.runs * j.cost for j in jobs) / 8  # a quarter of each worker's share
    assert max(costs) <= 2 * share
    assert len(chunks) >= 8  # enough for both workers to the end
    assert [c.runs for c in chunks if c.job.key == "cheap"] == [100]  # a cheap job stays one vectorised batch


def test_one_worker_takes_whole_jobs_in_order_up_to_the_cap():
    jobs = [Costed("a", 60, 1.0), Plain("b", 7)]
    chunks = _chunks(jobs, 25, None, workers=1)
    _cover(chunks, jobs)
    assert [(c.job.key, c.runs) for c in chunks] == [("a", 20), ("a", 20), ("a", 20), ("b", 7)]


@pytest.mark.parametrize("workers", [2, 3, 8])
def test_jobs_without_an_estimate_are_split_evenly(workers):
    jobs = [Plain("x", 13), Plain("y", 2)]
    chunks = _chunks(jobs, 25, None, workers=workers)
    _cover(chunks, jobs)
    sizes = [c.runs for c in chunks if c.job.key == "x"]
    assert max(sizes) - min(sizes) <= 1


def test_the_estimates_rank_engines_as_the_benchmarks_do():
    kinematic = run_cost(load("course-dvc", ["sim.robots=10"]), 60)
    physics = run_cost(load("course-physics", ["sim.robots=10"]), 60)
    swarm = run_cost(load("default", ["sim.robots=10"]), 60)
    slo = run_cost(load("slo-pso-sphere"), 60)
    assert swarm < kinematic < physics
    assert 0 < slo and run_cost(load("slo-pso-sphere", ["sim.robots=40"]), 60) > slo
