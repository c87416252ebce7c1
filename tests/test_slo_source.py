"""SLO-estimated positions for the Chapter 3 swarm: oracle vs SLO on the same seed, and the
belief tracker they are made of."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.core.objectives import Objective
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.coeffs import Constant
from shoal.engine.pso.laws import Law
from shoal.engine.slo.positions import Estimated
from shoal.engine.slo.tracker import BeliefTracker
from shoal.presets.build import build_simulation
from shoal.presets.io import load


def ch3_kwargs(**over) -> dict:
    """The default preset's Chapter 3 swarm as plain keywords (40 m arena: unit 0.4)."""
    base = build_simulation(load("default"), runs=2, seed=5)
    kw = dict(robots=12, d=2, dt=base.dt, law=base.law, policy=base.policy, objective=base.objective, runs=2,
              seed=5, init_center=base.init_center, init_spread=base.init_spread, init_speed=base.init_speed)
    kw.update(over)
    return kw


def on_slo(**slo) -> dict:
    """Keywords of a Chapter 3 swarm on SLO positions."""
    return {"positions": Estimated(**slo)}


def trajectories(sim: Simulation, steps: int) -> np.ndarray:
    out = []
    for _ in range(steps):
        sim.step()
        out.append(sim.state.x.copy())
    return np.stack(out)


@pytest.mark.parametrize("order", ["before_velocity", "after_velocity"])
def test_error_free_slo_reproduces_the_oracle_run(order):
    oracle = trajectories(Simulation(**ch3_kwargs(pbest_order=order)), 150)
    slo = trajectories(Simulation(**ch3_kwargs(pbest_order=order), **on_slo(errors="none", unit=0.4)), 150)
    assert np.allclose(slo, oracle, rtol=0, atol=1e-9)


def test_error_free_slo_matches_standard_pso_up_to_rounding():
    kw = ch3_kwargs(law=Law("standard"), policy=Constant(0.6, (0.8, 0.8)), objective=Objective("sphere"),
                    init_spread=20.0)
    oracle = trajectories(Simulation(**kw), 80)
    slo = trajectories(Simulation(**kw, **on_slo(errors="none", selection="css")), 80)
    assert np.allclose(slo, oracle, rtol=1e-7, atol=1e-9)


def test_high_error_changes_the_run():
    oracle = trajectories(Simulation(**ch3_kwargs()), 100)
    slo = trajectories(Simulation(**ch3_kwargs(), **on_slo(errors="high", unit=0.4)), 100)
    assert np.abs(slo - oracle).max() > 1.0
    again = trajectories(Simulation(**ch3_kwargs(), **on_slo(errors="high", unit=0.4)), 100)
    assert np.array_equal(slo, again)


def test_source_beliefs_follow_the_swarm():
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 10, (2, 5, 2))
    src = BeliefTracker(x, seed=1, errors="none")
    for k in range(6):
        move = rng.uniform(-1, 1, x.shape)
        x = x + move
        b = src.observe(x, displacement=move if k % 2 else None)
    truth = x[:, None] - x[:, :, None]
    assert np.allclose(b.est, truth, atol=1e-9)
    target = np.array([3, 0])
    rel = src.relative(target)
    assert rel.shape == (2, 5, 2)
    assert np.allclose(rel, x[np.arange(2), target][:, None] - x, atol=1e-9)
    assert np.all(rel[0, 3] == 0) and np.all(rel[1, 0] == 0)
    assert np.allclose(src.believed_positions()[:, 1], x, atol=1e-9)
    with pytest.raises(ValueError, match="2-D"):
        BeliefTracker(np.zeros((1, 4, 3)))


def test_a_resized_swarm_keeps_its_beliefs_and_the_error_free_run_the_oracle_one():
    """set_robots mid-run (the app's robots slider): kept robots keep their estimates of each
    other, their calibration offsets and their believed personal bests; a new robot starts
    believing the truth (a calibrated deployment) with its best where it stands; an
    error-free run still follows the oracle run through a grow and a shrink."""
    oracle, exact = Simulation(**ch3_kwargs()), Simulation(**ch3_kwargs(), **on_slo(errors="none", unit=0.4))
    for n in (12, 16, 7):
        oracle.set_robots(n), exact.set_robots(n)
        assert np.allclose(trajectories(exact, 25), trajectories(oracle, 25), rtol=0, atol=1e-9)

    noisy = Simulation(**ch3_kwargs(), **on_slo(errors="high", unit=0.4))
    trajectories(noisy, 10)
    pos = noisy.positions
    src = pos.tracker
    est, z, pbest = src.beliefs.est.copy(), src.localiser._z.copy(), pos.pbest.copy()
    noisy.set_robots(15)
    b, x = pos.beliefs, noisy.state.x
    assert pos.tracker is src and b.est.shape == (2, 15, 15, 2) and pos.sensed_k == 10
    assert np.array_equal(b.est[:, :12, :12], est) and np.array_equal(pos.pbest[:, :12], pbest)
    np.testing.assert_allclose(b.est[:, 12:, :12], x[:, None, :12] - x[:, 12:, None], atol=1e-12)
    assert not np.any(pos.pbest[:, 12:])
    assert np.array_equal(src.localiser._z[:, :, :12], z) and np.array_equal(src.x, x)
    trajectories(noisy, 5)
    noisy.set_robots(5)
    assert np.array_equal(src.localiser._z, z[:, :, :5]) and src.beliefs.est.shape == (2, 5, 5, 2)
    assert np.isfinite(trajectories(noisy, 5)).all()
