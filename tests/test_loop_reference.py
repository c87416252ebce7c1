"""The plain-loop Adapted PSO of ``benchmarks/bench_pso_compare.py`` computes what the engine
computes, so the speed comparison in ``benchmarks/README.md`` compares equal work."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_pso_compare.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_pso_compare", BENCH)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("bench_pso_compare", module)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("robots, runs, seed", [(2, 1, 0), (7, 3, 5), (40, 2, 11)])
def test_loop_reference_equals_the_engine_step(bench, robots, runs, seed):
    sim, loop, rngs, args = bench.engine_and_loop(robots, runs=runs, seed=seed)
    x0 = sim.state.x.copy()
    for _ in range(60):
        sim.step()
        bench.loop_step(loop, rngs, *args)
        bench.check_same(sim, loop)
    assert np.array_equal(sim.state.x, np.asarray(loop.x))  # bit for bit, not merely close
    assert sim.state.k == 60 and np.any(np.linalg.norm(sim.state.x - x0, axis=-1) > 1.0)  # the swarm moved


def test_the_check_notices_a_different_step(bench):
    sim, loop, rngs, args = bench.engine_and_loop(5)
    sim.step()
    omega, c, dt, source = args
    bench.loop_step(loop, rngs, omega, (c[0], c[1] * (1 + 1e-12)), dt, source)
    with pytest.raises(AssertionError):
        bench.check_same(sim, loop)
