"""The compiled Chapter 3 step against the numpy step, to the byte: numpy's row sum, every
objective the kernel evaluates, and whole seeded runs (both laws it knows, both bests
orders, literal and "ahead" attractors, constant, physical and per-robot coefficients, a
diverging swarm)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from shoal.engine.core.objectives import Objective
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso import kernels
from shoal.engine.pso.coeffs import Constant, Physical, Segment
from shoal.engine.pso.laws import Law


def _bytes(a) -> bytes:
    """Every bit of an array: −0 and +0, NaN payloads and all."""
    return np.ascontiguousarray(a).tobytes()


def test_numpy_sum_adds_a_row_as_numpy_does():
    rng = np.random.default_rng(0)
    for n in range(1, kernels.MAX_TERMS + 1):
        for _ in range(20):
            a = rng.normal(0.0, 1.0, n) * 10.0 ** rng.integers(-6, 6, n)
            assert _bytes(kernels.numpy_sum(a, n)) == _bytes(np.sum(a))
    assert _bytes(kernels.numpy_sum(np.array([-0.0, -0.0]), 2)) == _bytes(np.sum(np.array([-0.0, -0.0])))


@pytest.mark.parametrize("name", kernels.OBJECTIVES)
@pytest.mark.parametrize("d", [1, 2, 3, 10, 17, 64])
def test_compiled_objectives_equal_numpy(name, d):
    rng = np.random.default_rng(d)
    x = rng.normal(0.0, 5.0, (3, 7, d)) * 10.0 ** rng.integers(-3, 3, (3, 7, d))
    x[0, 0] = 0.0
    for source, scale in ((np.zeros(d + 1), 1.0), (rng.normal(0.0, 2.0, d + 1), 1.7)):
        obj = Objective(name, source=source, scale=scale)
        want = obj(x)
        got = np.empty((3, 7))
        for r in range(3):
            kernels.objective(kernels.OBJECTIVES.index(name), x, r, np.ascontiguousarray(source[:d]), scale,
                              np.empty(d), got)
        assert _bytes(got) == _bytes(want)


@dataclass(frozen=True)
class PerRobot:
    """Coefficients that differ per robot and per tick (as a DVC-like policy would give)."""

    def coefficients(self, t: float, dt: float, d: int):
        phase = np.sin(t + np.arange(3 * 11).reshape(3, 11))
        return 0.5 + 0.1 * phase, np.stack([0.4 + 0.1 * phase, 0.3 - 0.05 * phase])


STATE = ("x", "u", "a", "y", "f_y", "yg", "best_fitness", "f", "heading", "status")
INFO = ("max_speed", "max_component", "best_fitness")


def _same_runs(steps: int, **kw) -> None:
    a, b = Simulation(**kw), Simulation(**kw, compiled=False)
    assert a._compiled_tick() and not b._compiled_tick()
    for k in range(steps):
        ia, ib = a.step(), b.step()
        for name in STATE:
            assert _bytes(getattr(a.state, name)) == _bytes(getattr(b.state, name)), f"{name}, tick {k}"
        for name in INFO:
            assert _bytes(getattr(ia, name)) == _bytes(getattr(ib, name)), f"info.{name}, tick {k}"
        assert ia.columns().keys() == ib.columns().keys()


@pytest.mark.parametrize("objective", [*kernels.OBJECTIVES, "ackley"])
@pytest.mark.parametrize("law", ["standard", "adapted-sgn"])
def test_compiled_step_equals_the_numpy_step(objective, law):
    for d, order in ((2, "before_velocity"), (10, "after_velocity"), (3, "before_velocity")):
        _same_runs(60, robots=13, d=d, dt=1.0 if law == "standard" else 0.1, law=Law(law),
                   policy=Constant(0.7298, (1.49618, 1.49618)), runs=3, seed=4, pbest_order=order,
                   objective=Objective(objective, source=np.arange(d) * 0.3, scale=1.7), init_spread=5.0,
                   init_speed=0.5)


def test_compiled_step_equals_the_numpy_step_for_other_policies_and_attractors():
    _same_runs(80, robots=10, d=2, policy=Physical((Segment(0.0, 1.0, 2.0), Segment(3.0, 0.5, 2.0))),
               attractors="ahead", runs=2, seed=1)
    _same_runs(40, robots=11, d=2, law=Law("adapted-sgn"), policy=PerRobot(), runs=3, seed=2)
    _same_runs(40, robots=5, d=1, law=Law("standard"), policy=Constant(0.7, (1.4, 1.4)), runs=2, seed=3)


def test_a_diverging_swarm_stays_equal_through_inf_and_nan():
    _same_runs(3000, robots=10, d=2, law=Law("standard"), policy=Constant(1.1, (1.49618, 1.49618)), runs=2, seed=1)


def test_the_swarm_falls_back_to_numpy_where_the_kernel_does_not_apply():
    assert not Simulation(robots=3, d=2, policy=Constant(0.5, (0.5, 0.5)), law=Law("adapted-tanh"))._compiled_tick()
    assert not Simulation(robots=3, d=200, policy=Constant(0.5, (0.5, 0.5)),
                          objective=Objective("sphere", source=np.zeros(200)))._compiled_tick()


def test_run_equals_step_by_step_with_headings_read_now_and_then():
    """``run`` (whole blocks of ticks in one compiled call, draws taken many ticks ahead) gives
    the numpy steps' numbers; headings worked out only when read are the ones of every tick."""
    kw = dict(robots=13, d=3, law=Law("standard"), policy=Constant(0.7298, (1.49618, 1.49618)), runs=3, seed=5,
              objective=Objective("rastrigin", source=np.arange(3) * 0.3, scale=1.7), init_spread=5.0,
              init_speed=0.5)
    a, b = Simulation(**kw), Simulation(**kw, compiled=False)
    for steps in (1, 70, 3, 130):  # across blocks of draws
        series = a.run(steps, track=2)
        infos = [b.step() for _ in range(steps)]
        for name in STATE:
            assert _bytes(getattr(a.state, name)) == _bytes(getattr(b.state, name)), name
        assert _bytes(series.best_fitness) == _bytes(np.stack([i.best_fitness for i in infos]))
        assert _bytes(series.speeds[:, 0]) == _bytes(np.stack([i.max_speed for i in infos]))
        assert _bytes(series.speeds[:, 1]) == _bytes(np.stack([i.max_component for i in infos]))
        assert _bytes(series.t) == _bytes(np.array([i.t for i in infos]))
        assert series.omega == [i.omega for i in infos]
    for k in range(40):  # headings read every 7 ticks only
        a.step(), b.step()
        if k % 7 == 0:
            assert _bytes(a.state.heading) == _bytes(b.state.heading), k


def test_draws_taken_ahead_leave_the_stream_as_one_call_a_tick_would():
    """Growing the swarm, switching to the numpy tick, or reading the generators between
    compiled ticks sees each generator where one draw a tick would have left it."""
    kw = dict(robots=8, d=2, law=Law("adapted-sgn"), policy=Constant(0.7, (1.4, 1.4)), runs=2, seed=7,
              init_speed=0.3)
    a, b = Simulation(**kw), Simulation(**kw, compiled=False)
    for _ in range(3):
        a.step(), b.step()
    a.set_robots(11), b.set_robots(11)  # spawns from the generators
    for _ in range(5):
        a.step(), b.step()
    a.retune(law=Law("adapted-tanh")), b.retune(law=Law("adapted-tanh"))  # the numpy tick draws next
    for _ in range(4):
        a.step(), b.step()
    a.retune(law=Law("standard")), b.retune(law=Law("standard"))
    a.step(), b.step()
    assert [g.random() for g in a.rngs] == [g.random() for g in b.rngs]
    a.step(), b.step()
    for name in STATE:
        assert _bytes(getattr(a.state, name)) == _bytes(getattr(b.state, name)), name
    assert a.state.copy().heading is not a.state.heading


def test_a_batch_without_a_callback_runs_headless_to_the_same_series():
    """run_batch without on_step goes through Simulation.run; with a callback, tick by tick:
    the same series to the byte (a physical schedule changes the coefficients mid-run)."""
    from shoal.presets.io import load
    from shoal.studies.experiments.runner import run_batch

    scenario = load("fig3-5a", ["sim.robots=12"])  # U steps at 34 s and 67 s, Δt = 1 s
    a = run_batch(scenario, runs=3, seed=2, steps=100, track=4)
    b = run_batch(scenario, runs=3, seed=2, steps=100, track=4, on_step=lambda k, sim, info: None)
    assert len(set(a.omega)) == 2  # ω steps with U and back
    for name in ("t", "max_speed", "tracked", "omega", "c_hat"):
        assert _bytes(getattr(a, name)) == _bytes(getattr(b, name)), name
