"""The oracle/SLO positions switch of the Chapter 3, fleet and acoustic scenes, without a
browser: the session keeps its kind, the engine class changes with the same seed, the error
set retunes the running swarm, and the view draws the selected robot's ghosts. In the
Chapter 3 scene the controller still changes live on a swarm on SLO positions.

As in ``test_app_fleet.py``, GUI handles are driven by assigning ``.value`` (their callbacks
run in the test thread) on a real viser server with ``auto_tick=False``.
"""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app import replay
from shoal.app.fleet_scene import FleetView
from shoal.app.fleet_session import FleetSession
from shoal.app.panels import Panels
from shoal.app.scene import ArenaView
from shoal.app.session import Session
from shoal.app.sonar_session import SonarSession
from shoal.app.tab import session_for
from shoal.app.timeline import verify_replay
from shoal.engine.kinds.fleet import Fleet
from shoal.engine.kinds.swarm import Simulation
from shoal.presets.io import validate

APP_PRESET = "course-dvc"  # the shared ``server`` fixture (conftest.py) shows this scene


def _drawn(tab, key: str) -> np.ndarray:
    """World positions of a point node (undoing the view transform and the follow offset)."""
    pts = np.asarray(tab.arena.nodes[key].points, dtype=float)[:, :2]
    return tab.arena.to_world(pts + np.asarray(tab.arena.nodes["root"].position, dtype=float)[:2])


def _shown(tab, key: str) -> bool:
    node = tab.arena.nodes.get(key)
    return node is not None and bool(node.visible)


def test_fleet_switch_keeps_the_fleet_view_and_changes_the_engine(tab):
    s, p = tab.session, tab.panels
    assert isinstance(s, FleetSession) and type(s.sim) is Fleet and s.sim.positions.exact and s.scenario.slo is None
    assert p.positions_gui.positions.value == "oracle (true)" and not p.positions_gui.errors.visible
    x0 = s.sim.state.x.copy()
    p.positions_gui.positions.value = "SLO (estimated)"
    assert tab.session is s and isinstance(tab.arena, FleetView)  # the same kind of scene
    assert type(s.sim) is Fleet and not s.sim.positions.exact
    assert s.scenario.slo.errors == "low" and s.scenario.slo.neighbourhood == "full"
    np.testing.assert_array_equal(s.sim.state.x, x0)  # same seed, same start
    assert p.positions_gui.errors.visible
    s.select(2)
    s.step(4)
    tab.tick(1.0)
    b = s.sim.positions.beliefs
    x = s.sim.state.x[0]
    of = np.flatnonzero(b.valid[0, 2])
    np.testing.assert_allclose(_drawn(tab, "ghosts"), x[2] + b.est[0, 2, of], atol=1e-4)
    assert _shown(tab, "ghosts") and _shown(tab, "ghost_best")
    assert "robot 2 localises" in p.positions_gui.readout.content

    sim = s.sim
    p.positions_gui.errors.value = "High"  # retunes the running fleet: beliefs and positions kept
    assert s.sim is sim and s.sim.state.k == 4 and s.scenario.slo.errors == "high"
    assert s.sim.positions.tracker.errors.range.sigma_m == pytest.approx(0.2)

    p.positions_gui.positions.value = "oracle (true)"
    assert s.sim.positions.exact and s.sim.state.k == 0 and s.scenario.slo.positions == "oracle"
    tab.tick(2.0)
    assert not _shown(tab, "ghosts")
    assert "oracle" in p.positions_gui.readout.content


def test_fleet_compare_runs_b_on_slo_positions(tab):
    s, p = tab.session, tab.panels
    choices = p.compare_choices()
    assert "positions: SLO (estimated)" in choices
    s.enable_compare(choices["positions: SLO (estimated)"])
    assert s.sim.positions.exact and not s.twin.sim.positions.exact
    s.step(5)
    assert s.twin.sim.state.k == 5


def test_sonar_switch_keeps_the_sonar_view(tab):
    tab.panels.preset.value = "sonar-xb-pso-slo"
    s, p = tab.session, tab.panels  # another kind of scene: new panels
    assert isinstance(s, SonarSession) and not s.sim.positions.exact
    assert p.positions_gui.positions.value == "SLO (estimated)"
    s.step(3)
    tab.tick(1.0)
    assert _shown(tab, "ghosts") and len(tab.arena.nodes["ghosts"].points) == s.sim.robots - 1
    snap = s.snapshot()
    np.testing.assert_allclose(snap.ghosts.truth, np.delete(s.sim.state.x[0], snap.selected, axis=0))
    p.positions_gui.positions.value = "oracle (true)"
    assert tab.session is s and s.sim.positions.exact and s.sim.state.k == 0
    tab.tick(2.0)
    assert not _shown(tab, "ghosts")


# ---------------------------------------------------------------------------- Chapter 3
def _ch3_drawn(tab, key: str) -> np.ndarray:
    """World positions of a point node of the Chapter 3 arena (its nodes live under /world)."""
    return np.asarray(tab.arena.nodes[key].points, dtype=float)[:, :2] / tab.arena.scale


def _omega(sim) -> float:
    return float(np.mean(sim.policy.coefficients(sim.t, sim.dt, sim.d)[0]))


def test_chapter3_controller_changes_reach_the_running_slo_simulation(tab):
    tab.panels.preset.value = "slo-adapted"
    s, p = tab.session, tab.panels
    assert isinstance(s, Session) and isinstance(p, Panels) and isinstance(tab.arena, ArenaView)
    assert not s.sim.positions.exact and p.positions_gui.positions.value == "SLO (estimated)"
    s.step(5)
    sim, source = s.sim, s.sim.positions
    est = source.beliefs.est.copy()
    assert _omega(sim) == pytest.approx(0.5)  # U = 6, A+ = 30, Δt = 0.1: β = 0.5
    p.sliders["controller.U"].value = 4.0  # physical mode: β = A+Δt/U = 0.75, ω = 0.25
    assert s.sim is sim and sim.positions is source and sim.state.k == 5
    assert _omega(sim) == pytest.approx(0.25) and s.coefficients()[0] == pytest.approx(0.25)
    np.testing.assert_array_equal(source.beliefs.est, est)  # the beliefs are kept
    p.mode.value = "raw"
    p.sliders["controller.omega"].value = 0.3
    p.sliders["controller.dt"].value = 0.05
    p.law.value = "adapted-tanh"
    assert s.sim is sim and sim.state.k == 5
    assert _omega(sim) == pytest.approx(0.3) and sim.dt == 0.05 and sim.law.name == "adapted-tanh"
    s.step(3)
    assert sim.state.k == 8 and sim.positions.sensed_k == 8  # it runs and localises on the new controller
    p.sliders["sim.robots"].value = 24  # new robots join the running swarm and its SLO source
    assert s.sim is sim and sim.robots == 24 and p.particle.max == 23
    b = sim.positions.beliefs
    assert b.est.shape == (1, 24, 24, 2) and sim.positions.pbest.shape == (1, 24, 2)
    s.step(2)
    assert np.isfinite(sim.state.x).all() and sim.positions.sensed_k == 10


def test_chapter3_positions_switch_changes_the_engine_with_the_same_seed(tab):
    tab.panels.preset.value = "slo-adapted"
    s, p = tab.session, tab.panels
    x0, seed = s.sim.state.x.copy(), s.sim.seed
    p.particle.value = 3  # the phase plane's particle is the observer of the ghosts
    s.step(4)
    tab.tick(1.0)
    b, x = s.sim.positions.beliefs, s.sim.state.x[0]
    of = np.flatnonzero(b.valid[0, 3])
    assert len(of) == s.sim.robots - 1
    np.testing.assert_allclose(_ch3_drawn(tab, "ghosts"), x[3] + b.est[0, 3, of], atol=1e-4)
    np.testing.assert_allclose(_ch3_drawn(tab, "ghost_best"), s.sim.believed_gbest()[0, 3][None], atol=1e-4)
    assert _shown(tab, "ghosts") and _shown(tab, "ghost_errors")
    assert "robot 3 localises 19 robots" in p.positions_gui.readout.content

    sim = s.sim
    p.positions_gui.errors.value = "High"  # retunes the running swarm
    assert s.sim is sim and sim.state.k == 4 and sim.positions.tracker.errors.range.sigma_m == pytest.approx(0.2)

    p.positions_gui.positions.value = "oracle (true)"
    assert tab.session is s and isinstance(tab.panels, Panels)  # the same Chapter 3 scene
    assert s.sim.positions.exact and s.sim.seed == seed and s.sim.state.k == 0
    np.testing.assert_array_equal(s.sim.state.x, x0)  # same seed, same start
    assert not p.positions_gui.errors.visible
    s.step(2)
    tab.tick(2.0)
    assert not _shown(tab, "ghosts") and "oracle" in p.positions_gui.readout.content

    p.positions_gui.positions.value = "SLO (estimated)"
    assert type(s.sim) is Simulation and not s.sim.positions.exact and s.scenario.slo.errors == "high"
    np.testing.assert_array_equal(s.sim.state.x, x0)


def test_chapter3_compare_runs_b_on_true_positions_and_the_replay_verifies(tab):
    tab.panels.preset.value = "slo-adapted"
    s = tab.session
    s.enable_compare(tab.panels.compare_choices()["positions: oracle (true)"])
    assert not s.sim.positions.exact and s.twin.sim.positions.exact
    s.step(22)
    np.testing.assert_array_equal(s.frames[0].x, s.twin.frames[0].x)
    rec = replay.from_bytes(s.export_replay(), "run.npz")
    verified, text = verify_replay(session_for(validate(rec.meta["preset"])), rec)
    assert verified is True, text
