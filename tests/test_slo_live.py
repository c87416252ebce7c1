"""Live changes of an SLO swarm (sliders move, the swarm keeps running)."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.session import Session
from shoal.app.slo_session import SLOSession
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.presets import io as presets_io


def _pair(**kw) -> tuple[SLOSwarm, SLOSwarm]:
    a, b = SLOSwarm(runs=2, seed=5, **kw), SLOSwarm(runs=2, seed=5, **kw)
    for sw in (a, b):
        for _ in range(8):
            sw.step()
    return a, b


def test_a_retune_keeps_the_swarm_and_changes_what_follows():
    a, b = _pair(errors="low")
    x, est = a.state.x.copy(), a.state.est.copy()
    assert a.retune(selection="rts", prediction_weight=0.25) == ["selection", "prediction_weight"]
    np.testing.assert_array_equal(a.state.x, x)  # nothing jumps
    np.testing.assert_array_equal(a.state.est, est)
    assert a.state.k == b.state.k == 8
    a.step(), b.step()
    assert not np.array_equal(a.state.est, b.state.est)  # RTS now decides
    assert np.isfinite(a.state.est).all()


def test_a_retune_to_the_same_values_changes_nothing():
    a, b = _pair(errors="low", selection="css")
    assert a.retune(selection="css", errors="low") == []
    for _ in range(5):
        a.step(), b.step()
    np.testing.assert_array_equal(a.state.x, b.state.x)
    np.testing.assert_array_equal(a.state.est, b.state.est)


def test_new_errors_keep_each_robots_calibration_offsets():
    a, _ = _pair(errors="low")
    before = a.localiser.permanent.range_a / a.errors.range.perm_sigma_a
    a.retune(errors="high")
    after = a.localiser.permanent.range_a / a.errors.range.perm_sigma_a
    np.testing.assert_allclose(after, before)
    assert a.errors.range.sigma_m == 0.2  # Tab. 4.3 High


def test_a_new_objective_restarts_the_bests_at_the_current_positions():
    a, _ = _pair(objective="sphere")
    a.retune(objective="rastrigin")
    assert np.isinf(a.state.fP).all() and np.isinf(a.info().quality_met_at).all()
    np.testing.assert_allclose(a.state.f, 20 + (a.state.x**2 - 10 * np.cos(2 * np.pi * a.state.x)).sum(-1))
    a.step()
    assert np.isfinite(a.state.fP).all()


def test_fields_that_need_a_new_swarm_are_refused_by_name():
    a, _ = _pair()
    with pytest.raises(ValueError, match="particles"):
        a.retune(particles=30)
    with pytest.raises(ValueError, match="prediction_weight"):  # validated, nothing changed
        a.retune(prediction_weight=2.0)
    assert a.config.prediction_weight == 0.5


def test_the_session_retunes_live_and_rebuilds_only_when_it_must():
    s = SLOSession(presets_io.load("slo-walk"))
    s.step(5)
    engine = s.sim
    s.apply({"slo.selection": "akcan", "slo.errors": "high", "slo.prediction_weight": 0.75})
    assert s.sim is engine and s.sim.state.k == 5  # kept running
    assert (engine.config.selection, engine.config.prediction_weight) == ("akcan", 0.75)
    assert engine.errors.range.sigma_m == 0.2
    s.apply({"slo.error_values.range_sigma_m": 0.05})
    assert s.sim is engine and engine.errors.range.sigma_m == 0.05
    s.apply({"sim.robots": 12})  # a new swarm: rebuilt with the same seed
    assert s.sim is not engine and s.sim.state.k == 0 and s.sim.state.x.shape[1] == 12


def test_the_chapter3_swarm_on_slo_positions_retunes_its_source():
    s = Session(presets_io.load("slo-adapted"))  # the Chapter 3 scene runs it (Positions folder)
    assert not s.sim.positions.exact
    s.step(4)
    engine, x = s.sim, s.sim.state.x.copy()
    s.apply({"slo.errors": "none", "slo.selection": "rts"})
    assert s.sim is engine and engine.positions.tracker.params.selection == "rts"
    assert engine.positions.tracker.errors.range.sigma_m == 0.0
    np.testing.assert_array_equal(engine.state.x, x)
    s.apply({"slo.positions": "oracle"})  # the switch: same seed from the start
    assert s.sim.positions.exact and s.sim.state.k == 0
