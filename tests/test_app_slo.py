"""The browser app's SLO scenes without a browser: the SLO session, its panels and the
truth-vs-belief overlay.

As in ``test_app_fleet.py``, GUI handles are driven by assigning ``.value`` (their callbacks
run in the test thread) on a real viser server with ``auto_tick=False``.
"""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

from shoal.app.kinds import mai
from shoal.app.session.session import Session
from shoal.engine.core.recorder import TRAJECTORY_COLUMNS
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError

APP_PRESET = "slo-walk"  # the shared ``server`` fixture (conftest.py) shows this scene


def _last(tab):
    assert tab.messages, "expected a notification"
    return tab.messages[-1]


def _drawn(tab, key: str) -> np.ndarray:
    """World positions of a point node (undoing the view transform)."""
    pts = np.asarray(tab.arena.nodes[key].points, dtype=float)[:, :2]
    return pts / tab.arena.scale + tab.arena.centre


def test_slo_walk_builds_an_slo_swarm_and_draws_the_selected_robots_estimates(tab):
    s = tab.session
    assert s.kind.name == "mai" and isinstance(s.sim, SLOSwarm)
    assert tab.panels.name == "mai" and tab.arena.name == "mai"
    s.step(6)
    tab.panels.handles["robot"].value = 3
    tab.tick(1.0)
    st = s.sim.state
    x, est, valid = st.x[0], st.est[0], st.valid[0]
    j = np.flatnonzero(valid[3])
    assert len(j) >= 1
    expected = x[3] + est[3, j]  # ghost = observer's true position + its estimated vector
    np.testing.assert_allclose(_drawn(tab, "ghosts"), expected, atol=1e-4)
    np.testing.assert_allclose(_drawn(tab, "robots"), x, atol=1e-4)
    # error segments ghost → true neighbour, thin while small, thick once large (its second cue)
    drawn = np.concatenate([np.asarray(tab.arena.nodes[key].points, dtype=float)[:, :, :2]
                            for key in ("ghost_errors", "ghost_errors_large") if tab.arena.canvas.shown(key)])
    errs = drawn / tab.arena.scale + tab.arena.centre
    order = lambda a: a[np.lexsort(a.reshape(len(a), -1).T[::-1])]  # noqa: E731  (rows sorted, whatever node)
    np.testing.assert_allclose(order(errs), order(np.stack([expected, x[j]], axis=1)), atol=1e-4)
    edges = np.asarray(tab.arena.nodes["edges"].points)
    adj = st.adjacency[0] | st.adjacency[0].T
    assert len(edges) == np.triu(adj, 1).sum()
    # the triangle inspector: candidates of the pair (3, first neighbour), anchored at robot 3
    pair = s.snapshot().extras["pair"]
    assert pair is not None and pair.i == 3 and adj[3, pair.j]
    c = st.candidates
    np.testing.assert_allclose(pair.candidates[2], x[3] + c.points[0, 3, pair.j, 2])  # x3, dead reckoning
    assert "pair (3 →" in tab.panels.handles["inspector"].content


def test_selection_and_error_preset_reach_the_swarm_config(tab):
    s, p = tab.session, tab.panels
    p.handles["slo.selection"].value = "RTS (round trip)"
    assert s.sim.config.selection == "rts" and s.scenario.slo.selection == "rts"
    p.handles["slo.selection"].value = "Akcan (GDL)"
    assert s.sim.config.selection == "akcan"
    p.handles["slo.errors"].value = "High"
    assert s.sim.config.errors == "high" and s.sim.errors.range.sigma_m == pytest.approx(0.20)
    p.handles["slo.error_values.odometry_perm_sigma_a"].value = 1.5
    assert s.sim.errors.odometry.perm_sigma_a == pytest.approx(1.5)
    assert s.sim.errors.range.sigma_m == pytest.approx(0.20)  # the rest of the set stays
    p.handles["slo.errors"].value = "None"
    assert s.sim.errors.odometry.perm_sigma_a == 0.0 and s.scenario.slo.error_values.values() == {}
    p.handles["slo.prediction_weight"].value = 0.25
    p.handles["slo.neighbourhood"].value = "ring"
    p.handles["slo.neighbourhood_param"].value = 3
    cfg = s.sim.config
    assert (cfg.prediction_weight, cfg.neighbourhood, cfg.neighbourhood_param) == (0.25, "ring", 3)
    p.handles["sim.robots"].value = 12
    assert s.sim.state.x.shape[1] == 12 and p.handles["robot"].max == 11


def test_bad_values_are_refused_and_the_run_is_untouched(tab):
    s, p = tab.session, tab.panels
    s.step(4)
    sim, scenario = s.sim, s.scenario
    p.handles["slo.delta_cos"].value = 3.0  # the model wants ≤ 1
    title, body, color = _last(tab)
    assert color == "red" and "slo.delta_cos" in body
    assert p.handles["slo.delta_cos"].value == pytest.approx(0.03)
    p.handles["slo.neighbourhood_param"].value = 2.5  # knn needs a whole number
    title, body, color = _last(tab)
    assert color == "red" and "neighbourhood_param" in body
    assert s.sim is sim and s.scenario is scenario and s.sim.state.k == 4


def test_slo_adapted_opens_in_the_chapter3_scene_and_the_slo_session_keeps_mais_swarm(tab):
    """The Chapter 3 swarm on SLO positions has its own scene (its Positions folder, see
    test_app_positions.py); the SLO session runs Mai's swarm only and says why."""
    tab.panels.preset.value = "slo-adapted"
    assert tab.session.kind.name == "swarm" and tab.panels.name == "swarm"
    assert not tab.session.sim.positions.exact
    with pytest.raises(PresetError, match="slo.swarm"):
        Session(presets_io.load("slo-adapted"), mai.KIND)
    tab.panels.preset.value = "slo-walk"
    assert tab.session.kind.name == "mai" and isinstance(tab.session.sim, SLOSwarm)
    assert "positions" not in tab.panels.handles  # no oracle switch for Mai's swarm: it always localises


def test_plots_notes_and_export(tab):
    s, p = tab.session, tab.panels
    assert "mirror" in p.notes.content and "dead reckoning" in p.notes.content.lower()
    s.step(8)
    p.refresh_plots()
    m = s.metric_arrays()
    np.testing.assert_allclose(p.handles["error"].data[1], m["e_abs_mean"])
    np.testing.assert_allclose(p.handles["fitness"].data[1], np.log10(np.abs(m["generation_best"])))
    assert p.handles["distance"].scales["x"]["time"] is False and p.handles["fitness"].scales["x"]["time"] is False
    assert m["e_abs_mean"][-1] == pytest.approx(s.sim.info().e_abs["mean"][0])
    p.export_csv.value = True
    rows = list(csv.DictReader(io.StringIO(tab.downloads[-1][1].decode())))
    assert tuple(rows[0]) == TRAJECTORY_COLUMNS
    last = [r for r in rows if int(r["step"]) == 8]
    np.testing.assert_allclose([[float(r["x"]), float(r["y"])] for r in last], s.sim.state.x[0], atol=1e-8)
    p.export_json.value = True
    doc = json.loads(tab.downloads[-1][1])
    assert doc["engine"] == "SLOSwarm" and doc["preset"]["slo"]["motion"] == "random_walk"
    assert len(doc["beliefs"]["estimates"]) == s.robots


def test_switching_kinds_and_uploading_an_slo_preset(tab):
    tab.panels.preset.value = "default"
    assert tab.session.kind.name == "swarm"
    text = presets_io.to_toml(presets_io.load("slo-pso-sphere")).encode()
    assert tab.panels.upload_preset("slo.toml", text)
    assert tab.session.kind.name == "mai" and tab.session.sim.config.motion == "pso"
    tab.tick(1.0)
    assert "ghosts" in tab.arena.nodes
    tab.panels.preset.value = "slo-walk"
    assert tab.session.sim.config.motion == "random_walk"
