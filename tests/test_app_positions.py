"""The oracle/SLO positions switch of the fleet and acoustic scenes, without a browser: the
session keeps its kind, the engine class changes with the same seed, the error set retunes
the running swarm, and the view draws the selected robot's ghosts.

As in ``test_app_fleet.py``, GUI handles are driven by assigning ``.value`` (their callbacks
run in the test thread) on a real viser server with ``auto_tick=False``.
"""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.fleet_scene import FleetView
from shoal.app.fleet_session import FleetSession
from shoal.app.server import start_server
from shoal.app.sonar_session import SonarSession
from shoal.engine.fleet import Fleet
from shoal.engine.slo_fleet import SLOFleet
from shoal.engine.slo_sonar import SLOAcousticSwarm
from shoal.engine.sonar import AcousticSwarm


@pytest.fixture(scope="module")
def server():
    srv = start_server("course-dvc", port=0)
    yield srv
    srv.stop()


@pytest.fixture
def tab(server):
    t = server.open_tab(-5, server.viser.gui, server.viser.scene, auto_tick=False)
    t.tick(0.0)
    yield t
    server.close_tab(-5)
    server.viser.gui.reset()
    server.viser.scene.reset()


def _drawn(tab, key: str) -> np.ndarray:
    """World positions of a point node (undoing the view transform and the follow offset)."""
    pts = np.asarray(tab.arena.nodes[key].points, dtype=float)[:, :2]
    return tab.arena.to_world(pts + np.asarray(tab.arena.nodes["root"].position, dtype=float)[:2])


def _shown(tab, key: str) -> bool:
    node = tab.arena.nodes.get(key)
    return node is not None and bool(node.visible)


def test_fleet_switch_keeps_the_fleet_view_and_changes_the_engine(tab):
    s, p = tab.session, tab.panels
    assert isinstance(s, FleetSession) and type(s.sim) is Fleet and s.scenario.slo is None
    assert p.positions_gui.positions.value == "oracle (true)" and not p.positions_gui.errors.visible
    x0 = s.sim.state.x.copy()
    p.positions_gui.positions.value = "SLO (estimated)"
    assert tab.session is s and isinstance(tab.arena, FleetView)  # the same kind of scene
    assert type(s.sim) is SLOFleet and s.scenario.slo.errors == "low" and s.scenario.slo.neighbourhood == "full"
    np.testing.assert_array_equal(s.sim.state.x, x0)  # same seed, same start
    assert p.positions_gui.errors.visible
    s.select(2)
    s.step(4)
    tab.tick(1.0)
    b = s.sim.slo_source.beliefs
    x = s.sim.state.x[0]
    of = np.flatnonzero(b.valid[0, 2])
    np.testing.assert_allclose(_drawn(tab, "ghosts"), x[2] + b.est[0, 2, of], atol=1e-4)
    assert _shown(tab, "ghosts") and _shown(tab, "ghost_best")
    assert "robot 2 localises" in p.positions_gui.readout.content

    sim = s.sim
    p.positions_gui.errors.value = "High"  # retunes the running fleet: beliefs and positions kept
    assert s.sim is sim and s.sim.state.k == 4 and s.scenario.slo.errors == "high"
    assert s.sim.slo_source.errors.range.sigma_m == pytest.approx(0.2)

    p.positions_gui.positions.value = "oracle (true)"
    assert type(s.sim) is Fleet and s.sim.state.k == 0 and s.scenario.slo.positions == "oracle"
    tab.tick(2.0)
    assert not _shown(tab, "ghosts")
    assert "oracle" in p.positions_gui.readout.content


def test_fleet_compare_runs_b_on_slo_positions(tab):
    s, p = tab.session, tab.panels
    choices = p.compare_choices()
    assert "positions: SLO (estimated)" in choices
    s.enable_compare(choices["positions: SLO (estimated)"])
    assert type(s.sim) is Fleet and type(s.twin.sim) is SLOFleet
    s.step(5)
    assert s.twin.sim.state.k == 5


def test_sonar_switch_keeps_the_sonar_view(tab):
    tab.panels.preset.value = "sonar-xb-pso-slo"
    s, p = tab.session, tab.panels  # another kind of scene: new panels
    assert isinstance(s, SonarSession) and type(s.sim) is SLOAcousticSwarm
    assert p.positions_gui.positions.value == "SLO (estimated)"
    s.step(3)
    tab.tick(1.0)
    assert _shown(tab, "ghosts") and len(tab.arena.nodes["ghosts"].points) == s.sim.robots - 1
    snap = s.snapshot()
    np.testing.assert_allclose(snap.ghosts.truth, np.delete(s.sim.state.x[0], snap.selected, axis=0))
    p.positions_gui.positions.value = "oracle (true)"
    assert tab.session is s and type(s.sim) is AcousticSwarm and s.sim.state.k == 0
    tab.tick(2.0)
    assert not _shown(tab, "ghosts")
