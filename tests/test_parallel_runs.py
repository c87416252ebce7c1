"""Batches of runs on every core (``engine/core/parallel.py``): the same bytes whatever the
number of threads, and the same as each run simulated alone."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

from shoal.engine.core import parallel
from shoal.engine.core.objectives import Objective
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.coeffs import Constant, Physical, Segment
from shoal.engine.pso.laws import Law

STATE = ("x", "u", "a", "y", "f_y", "yg", "best_fitness", "f", "heading")


@pytest.fixture
def threads():
    """Set the thread count for one test, and put it back."""
    yield parallel.set_threads
    parallel.set_threads(None)


def _swarm(runs: int = 7, first_run: int = 0, **kw) -> Simulation:
    args = dict(robots=30, d=10, dt=1.0, law=Law("standard"), policy=Constant(0.7298, (1.49618, 1.49618)),
                objective=Objective("rastrigin", source=np.zeros(10)), seed=3, init_spread=10.24, init_speed=0.2)
    return Simulation(**(args | kw), runs=runs, first_run=first_run)


def _digest(sim: Simulation, series) -> str:
    h = hashlib.sha256()
    for name in STATE:
        h.update(np.ascontiguousarray(getattr(sim.state, name)).tobytes())
    for a in (series.best_fitness, series.speeds, series.tracked, series.t):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(np.array([g.random() for g in sim.rngs]).tobytes())  # where each generator was left
    return h.hexdigest()


def test_blocks_cover_the_runs_in_order():
    assert parallel.blocks(7, 2) == [(0, 4), (4, 7)]
    assert parallel.blocks(2, 5) == [(0, 1), (1, 2)]
    assert parallel.blocks(9, 1) == [(0, 9)]
    for runs in range(1, 30):
        for n in range(1, 6):
            b = parallel.blocks(runs, n)
            assert b[0][0] == 0 and b[-1][1] == runs and all(x[1] == y[0] for x, y in zip(b, b[1:]))
            assert max(hi - lo for lo, hi in b) - min(hi - lo for lo, hi in b) <= 1


def test_set_threads_refuses_a_bad_count(threads):
    for bad in (0, -1, 1.5, "2"):
        with pytest.raises(ValueError, match="threads"):
            threads(bad)
    threads(3)
    assert parallel.threads() == 3


def test_each_block_runs_in_threads_and_raises_a_blocks_error(threads):
    threads(3)
    seen: list[tuple[int, int, str]] = []

    def fn(lo: int, hi: int) -> None:
        seen.append((lo, hi, threading.current_thread().name))
        if lo == 4:
            raise RuntimeError("block 4")

    with pytest.raises(RuntimeError, match="block 4"):
        parallel.each_block(fn, 10)
    assert sorted(s[:2] for s in seen) == [(0, 4), (4, 7), (7, 10)]  # every block ran before the error
    assert "MainThread" in {s[2] for s in seen} and len({s[2] for s in seen}) >= 2  # the first block here


@pytest.mark.parametrize("kw", [
    {},
    dict(law=Law("adapted-sgn"), dt=0.1, policy=Physical((Segment(0.0, 1.0, 2.0), Segment(3.0, 0.5, 2.0))),
         pbest_order="after_velocity", d=3, objective=Objective("sphere", source=np.ones(3))),
    dict(attractors="ahead", d=2, law=Law("adapted-sgn"), dt=0.1, objective=Objective("source-distance")),
])
def test_a_batch_is_the_same_on_one_thread_two_and_three(threads, kw):
    digests = []
    for n in (1, 2, 3):
        threads(n)
        sim = _swarm(**kw)
        digests.append(_digest(sim, sim.run(120, track=3)))
    assert len(set(digests)) == 1


def test_each_run_of_a_parallel_batch_is_the_run_alone(threads):
    threads(2)
    batch = _swarm(runs=5)
    series = batch.run(90, track=1)
    for i in range(5):
        alone = _swarm(runs=1, first_run=i)
        one = alone.run(90, track=1)
        for name in STATE:
            assert getattr(batch.state, name)[i].tobytes() == getattr(alone.state, name)[0].tobytes(), (i, name)
        assert series.best_fitness[:, i].tobytes() == one.best_fitness[:, 0].tobytes()
        assert series.tracked[:, i].tobytes() == one.tracked[:, 0].tobytes()
        assert batch.rngs[i].random() == alone.rngs[0].random()


def test_a_parallel_batch_equals_the_numpy_ticks(threads):
    """The threaded run against the numpy reference tick by tick (the draws and the stream too)."""
    threads(2)
    a, b = _swarm(runs=4), _swarm(runs=4, compiled=False)
    a.run(3), [b.step() for _ in range(3)]
    a.step(), b.step()  # a block of draws taken ahead by the single tick, settled by the run after it
    a.run(50), [b.step() for _ in range(50)]
    for name in STATE:
        assert getattr(a.state, name).tobytes() == getattr(b.state, name).tobytes(), name
    assert [g.random() for g in a.rngs] == [g.random() for g in b.rngs]


CHILD = """
import hashlib, json, numpy as np
from shoal.engine.core.objectives import Objective
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.coeffs import Constant
from shoal.engine.pso.laws import Law
from shoal.engine.core import parallel
sim = Simulation(robots=30, d=10, dt=1.0, law=Law("standard"), policy=Constant(0.7298, (1.49618, 1.49618)),
                 objective=Objective("sphere", source=np.zeros(10)), runs=6, seed=9, init_spread=10.24)
s = sim.run(200)
h = hashlib.sha256(sim.state.x.tobytes() + sim.state.f_y.tobytes() + s.best_fitness.tobytes())
print(json.dumps({"threads": parallel.threads(), "digest": h.hexdigest()}))
"""


def test_numba_num_threads_does_not_change_a_batch():
    """A fresh process with NUMBA_NUM_THREADS=1 and one with 2 give the same bytes."""
    out = []
    for n in ("1", "2"):
        env = os.environ | {"NUMBA_NUM_THREADS": n}
        done = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        out.append(json.loads(done.stdout.strip().splitlines()[-1]))
    assert [o["threads"] for o in out] == [1, 2]
    assert out[0]["digest"] == out[1]["digest"]


def test_a_batch_of_acoustic_swarms_is_the_same_on_one_thread_or_three(threads):
    """The sonar's draws and its lag-grid correlation go to blocks of runs: the same bytes."""
    from shoal.presets.build import build
    from shoal.presets.io import load

    out = []
    for n in (1, 3):
        threads(n)
        sim = build(load("sonar-xb-pso"), runs=24, seed=2)
        for _ in range(8):
            info = sim.step()
        out.append((sim.state.x.tobytes(), sim.state.f_hat.tobytes(), info.com_dist.tobytes(),
                    [g.random() for g in sim.rngs]))
    assert out[0] == out[1]


def test_compiled_draws_in_blocks_are_the_generators_own_numbers(threads):
    from shoal.engine.core.compiled_draws import CompiledDraws
    from shoal.engine.core.rng import run_generators

    threads(3)
    a, b = run_generators(4, 0, 9), run_generators(4, 0, 9)
    u, z = np.empty((9, 5000)), np.empty((9, 3, 2000))
    CompiledDraws(a).fill(u, z, normal=(False, True))
    for g, ur, zr in zip(b, u, z):
        assert ur.tobytes() == g.random(5000).tobytes() and zr.tobytes() == g.standard_normal((3, 2000)).tobytes()
    assert [g.random() for g in a] == [g.random() for g in b]


def test_a_forked_child_runs_its_batches_on_a_pool_of_its_own(threads):
    """A process forked after a parallel batch (as the local process pool forks) gets the same bytes."""
    import multiprocessing

    threads(2)
    here = _digest(sim := _swarm(runs=4), sim.run(40))
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(1) as pool:
        there = pool.apply(_child_digest)
    assert there == here


def _child_digest() -> str:
    sim = _swarm(runs=4)
    return _digest(sim, sim.run(40))


def _worker_threads(_: int) -> int:
    return parallel.threads()


def test_local_pool_workers_share_the_cores(threads):
    """Two worker processes on four threads' worth: two each, so workers × threads stays the count."""
    from shoal.studies.experiments.schedulers import LocalPool

    threads(4)
    pool = LocalPool(2)
    assert {t for _, t in pool.map_unordered(_worker_threads, [0, 1, 2])} == {2}
