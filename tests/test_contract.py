"""The engine contract (``shoal.engine.core.contract``) as each built-in kind keeps it: ``retune``
with the class's ``LIVE`` keywords, refusing anything else without changing the engine. The
rules every kind keeps are ``shoal.testing``'s checks (tests/test_kinds.py)."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.pso.coeffs import Constant
from shoal.presets.build import build
from shoal.presets.io import load
from shoal.presets.kinds import KINDS
from shoal.testing import example_of

# The rules every kind keeps (the contract, its columns, seeding, reset, retune refusing what is
# not LIVE, the live rule, the snapshot) are shoal.testing's checks, run on every registered kind
# by tests/test_kinds.py; here, what each built-in kind's retune does.
HOSTS = [example_of(k) for k in KINDS.values() if k.live is not None and k.live.slo]  # kinds on SLO positions too


def engine(preset: str, runs: int = 2):
    return build(load(preset), runs=runs, seed=3)


@pytest.mark.parametrize("preset", HOSTS)
def test_slo_settings_need_slo_positions(preset):
    with pytest.raises(ValueError, match="^slo: .* true positions"):
        engine(preset).retune(slo={"errors": "high"})


def test_the_chapter3_swarm_retunes_its_controller_and_size():
    sim, twin = engine("default"), engine("default")
    sim.step(), twin.step()
    assert sim.retune(policy=sim.policy, law=sim.law, dt=sim.dt, robots=sim.robots) == []
    n, x = sim.robots, sim.state.x.copy()
    assert sim.retune(policy=Constant(0.5, (0.5, 0.5)), robots=n + 2) == ["policy", "robots"]
    np.testing.assert_array_equal(sim.state.x[:, :n], x)  # the swarm kept, two robots more
    info = sim.step()
    assert sim.robots == n + 2 and info.columns()["omega"][0] == 0.5 and info.columns()["c_hat"][0] == 1.0
    with pytest.raises(ValueError, match="^dt: must be > 0"):
        twin.retune(policy=Constant(0.5, (0.5, 0.5)), dt=0.0)
    assert twin.policy != Constant(0.5, (0.5, 0.5))  # refused: nothing changed


def test_the_chapter3_swarm_reports_no_coefficients_before_its_first_tick():
    sim = engine("default")
    cols = sim.info().columns()
    assert np.isnan(cols["omega"]).all() and np.isnan(cols["c_hat"]).all()
    assert np.isfinite(sim.step().columns()["omega"]).all()


def test_the_fleet_retunes_its_controller_from_the_next_tick():
    sim = engine("course-dvc")
    sim.step()
    assert sim.retune(alpha=0.5, beta=sim.params.beta) == ["alpha"] and sim.params.alpha == 0.5
    with pytest.raises(ValueError, match="^robot_radius: cannot change mid-run"):
        sim.retune(robot_radius=1.0)
    assert sim.params.robot_radius == 0.5


def test_the_acoustic_swarm_retunes_its_tuning_and_lets_a_moving_source_carry_on():
    sim = engine("sonar-xb-pso")
    for _ in range(3):
        sim.step()
    omega, source = sim.omega, sim.state.source.copy()
    assert sim.retune(beta=0.5, v_n=0.2) == ["beta", "v_n"]
    assert sim.omega == pytest.approx(0.5) and sim.omega != omega
    np.testing.assert_array_equal(sim.state.source, source)  # it starts moving from where it is
    sim.step()
    np.testing.assert_allclose(np.linalg.norm(sim.state.source - source, axis=-1), 0.2 * sim.params.U * sim.dt)
    with pytest.raises(ValueError, match="^mode: cannot change mid-run"):
        sim.retune(mode="surrogate")
