"""The browser app without a browser: GUI handles driven from Python, session, plots, scene.

Assigning ``handle.value`` runs the handle's callbacks synchronously in the test thread,
exactly as a browser change would run them on viser's pool, so these tests exercise the
real panel wiring on a real viser server (``server.gui`` stands in for ``client.gui``).
"""

from __future__ import annotations

import csv
import io
import json
import socket
import threading
import time

import numpy as np
import pytest
from viser import GuiEvent

from shoal.app.kinds import swarm
from shoal.app.kinds.registry import session_for
from shoal.app.kinds.swarm import SPEED
from shoal.app.panel import figures
from shoal.app.panel.spec import field_bounds
from shoal.app.server import PortInUseError, serve, start_server
from shoal.app.session.upload import MAX_UPLOAD_BYTES
from shoal.app.view.camera import VIEW_HALF
from shoal.app.view.layers import landscape_rgb
from shoal.engine.core.objectives import Objective
from shoal.engine.core.recorder import TRAJECTORY_COLUMNS
from shoal.engine.pso import stability
from shoal.engine.pso.coeffs import Constant, Physical
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError

from app_helpers import HAND_TAB, shown


def _raw(tab):
    """Switch the tab to raw mode through the GUI."""
    tab.panels.handles["controller.mode"].value = "raw"
    assert tab.session.scenario.controller.mode == "raw"


def _last_message(tab):
    assert tab.messages, "expected a notification"
    return tab.messages[-1]


# ---------------------------------------------------------------------------- slider → engine
def test_omega_slider_reaches_the_running_policy_without_restart(tab):
    s = tab.session
    s.step(7)
    _raw(tab)
    x_before = s.sim.state.x.copy()
    tab.panels.handles["controller.omega"].value = 0.83
    assert isinstance(s.sim.policy, Constant)
    assert s.sim.policy.omega == pytest.approx(0.83)
    assert swarm.driver(s).coefficients()[0] == pytest.approx(0.83)
    assert s.scenario.controller.omega == pytest.approx(0.83)  # scenario kept in sync (export, download)
    assert s.sim.state.k == 7 and np.array_equal(s.sim.state.x, x_before)  # not restarted
    s.step(1)  # and the next step really uses it
    assert s.metric_arrays()["omega"][-1] == pytest.approx(0.83)


def test_c1_c2_dt_and_robots_sliders_apply_at_once(tab):
    s = tab.session
    _raw(tab)
    p = tab.panels
    p.handles["controller.c1"].value = 1.25
    p.handles["controller.c2"].value = 0.75
    assert s.sim.policy.c == pytest.approx((1.25, 0.75))
    p.handles["controller.dt"].value = 0.05
    assert s.sim.dt == pytest.approx(0.05)
    s.step(3)
    p.handles["sim.robots"].value = 33
    assert s.sim.state.x.shape == (1, 33, 2)
    assert s.sim.state.k == 3


def test_physical_mode_derives_omega_c_beta_from_U_A_dt(tab):
    s = tab.session
    p = tab.panels
    assert s.scenario.controller.mode == "physical"
    p.handles["controller.dt"].value = 0.1
    p.handles["controller.U"].value = 5.0
    p.handles["controller.A_plus"].value = 20.0
    assert isinstance(s.sim.policy, Physical)
    beta = 20.0 * 0.1 / 5.0
    omega, c_hat = swarm.driver(s).coefficients()
    assert omega == pytest.approx(1 - beta)  # [3.35]
    assert c_hat == pytest.approx(20.0 * 0.1 / np.sqrt(2))  # [3.32]
    tab.tick(10.0)
    table = shown(p.handles["readout"].content)  # the coefficients and bounds as a table, ĉ included
    assert f"| β = A+Δt/U [3.34] | {beta:.4g} |" in table and f"| ω = 1 − β [3.35] | {1 - beta:.4g} |" in table
    assert f"| ĉ = A+Δt/√d [3.32] | {c_hat:.4g} m/s |" in table
    h = p.handles  # ω, c1, c2 in force are read-outs on their sliders (moving one switches to raw mode)
    assert h["controller.omega"].value == pytest.approx(1 - beta, rel=1e-3)
    assert h["controller.c1"].value + h["controller.c2"].value == pytest.approx(c_hat, rel=1e-3)
    h["controller.omega"].value = 0.5
    assert s.scenario.controller.mode == "raw" and s.scenario.controller.omega == 0.5
    assert s.scenario.controller.c1 + s.scenario.controller.c2 == pytest.approx(c_hat, rel=1e-3)


def test_law_dropdown_swaps_the_law(tab):
    tab.panels.handles["controller.law"].value = "adapted-tanh"
    assert tab.session.sim.law.name == "adapted-tanh"
    assert tab.panels.handles["controller.smooth_width"].visible


def test_mode_switch_keeps_the_controllers_behaviour(tab):
    s = tab.session
    before = swarm.driver(s).coefficients()
    tab.panels.handles["controller.mode"].value = "raw"
    assert swarm.driver(s).coefficients() == pytest.approx(before, rel=1e-5)
    tab.panels.handles["controller.mode"].value = "physical"
    assert swarm.driver(s).coefficients() == pytest.approx(before, rel=1e-5)
    h = tab.panels.handles
    assert h["controller.U"].visible and h["controller.omega"].visible  # ω, c1, c2 are on screen in both modes
    tab.panels.handles["controller.mode"].value = "raw"
    assert not h["controller.U"].visible and h["controller.omega"].visible


# ---------------------------------------------------------------------------- refusals
def test_omega_at_one_with_an_adapted_law_is_refused_and_restored(tab):
    s = tab.session
    _raw(tab)
    tab.panels.handles["controller.omega"].value = 0.6
    policy, scenario = s.sim.policy, s.scenario
    tab.panels.handles["controller.omega"].value = 1.05
    title, body, color = _last_message(tab)
    assert color == "red" and "omega" in body and "controller" in body
    assert tab.panels.handles["controller.omega"].value == pytest.approx(0.6)  # handle restored
    assert s.sim.policy is policy and s.scenario is scenario  # engine untouched


def test_beta_above_one_is_refused(tab):
    s = tab.session
    p = tab.panels
    p.handles["controller.U"].value = 3.0
    p.handles["controller.A_plus"].value = 15.0
    dt, policy = s.sim.dt, s.sim.policy
    p.handles["controller.dt"].value = 0.5  # β = 15·0.5/3 = 2.5
    assert "beta" in _last_message(tab)[1] and _last_message(tab)[2] == "red"
    assert p.handles["controller.dt"].value == pytest.approx(dt)
    assert s.sim.dt == dt and s.sim.policy is policy


def test_standard_law_in_physical_mode_is_refused(tab):
    tab.panels.handles["controller.law"].value = "standard"
    assert "physical" in _last_message(tab)[1]
    assert tab.panels.handles["controller.law"].value == "adapted-sgn"
    assert tab.session.sim.law.name == "adapted-sgn"


def test_out_of_model_range_value_is_refused(tab):
    """viser does not clamp Python-side values; the model does."""
    before = tab.session.scenario.controller.c1_share
    tab.panels.handles["controller.c1_share"].value = 1.5
    assert "c1_share" in _last_message(tab)[1]
    assert tab.session.scenario.controller.c1_share == before


def test_slider_limits_come_from_the_model(tab):
    lo, hi = field_bounds("controller.omega")
    assert (lo, hi) == (-1.0, 1.2)
    assert tab.panels.control("controller.omega").range(0.5) == (-1.0, 1.2)
    # a preset value above the on-screen range widens it, never past the model
    lo, hi = tab.panels.control("controller.A_plus").range(900.0)
    assert hi >= 900.0 and hi <= field_bounds("controller.A_plus")[1]


# ---------------------------------------------------------------------------- upload / presets
def test_bad_upload_lists_the_field_and_leaves_the_scene_untouched(tab):
    s = tab.session
    s.step(5)
    sim, scenario, x = s.sim, s.scenario, s.sim.state.x.copy()
    ok = tab.panels.upload_preset("bad.toml", b"[controller]\nomega = 7\n[sim]\nrobots = 0\n")
    assert not ok
    title, body, color = _last_message(tab)
    assert color == "red" and "controller.omega" in body and "sim.robots" in body
    assert s.sim is sim and s.scenario is scenario and s.sim.state.k == 5
    assert np.array_equal(s.sim.state.x, x)


@pytest.mark.parametrize(
    "name, content, expect",
    [
        ("broken.toml", b"[controller\nomega = 0.5\n", "TOML syntax"),
        ("broken.json", b'{"controller": {"omega": 0.5},}', "JSON syntax"),
        ("huge.toml", b"#" * (MAX_UPLOAD_BYTES + 1), "KiB"),
        ("unknown.toml", b"[controller]\nomegaa = 0.5\n", "controller.omegaa"),
    ],
)
def test_unreadable_uploads_are_refused(tab, name, content, expect):
    sim = tab.session.sim
    assert not tab.panels.upload_preset(name, content)
    assert expect in _last_message(tab)[1]
    assert tab.session.sim is sim


def test_good_upload_replaces_the_scene(tab):
    text = presets_io.to_toml(presets_io.load("rastrigin")).encode()
    assert tab.panels.upload_preset("mine.toml", text)
    s = tab.session
    assert s.scenario.name == "rastrigin" and s.sim.state.k == 0
    assert s.sim.objective.name == "rastrigin"
    tab.tick(1.0)
    assert "landscape" in tab.arena.nodes  # benchmark drawn as a heat map


def test_preset_dropdown_switches_scene_and_syncs_sliders(tab):
    tab.panels.preset.value = "standard-pso"
    s = tab.session
    assert s.scenario.controller.law == "standard" and s.sim.law.name == "standard"
    assert tab.panels.handles["controller.omega"].value == pytest.approx(0.7)
    h = tab.panels.handles
    assert h["controller.law"].value == "standard" and h["controller.mode"].value == "raw"
    assert h["controller.omega"].visible and not h["controller.U"].visible


def test_download_preset_round_trips(tab):
    _raw(tab)
    tab.panels.handles["controller.omega"].value = 0.42
    tab.panels.download.value = True  # fires on_click
    name, content = tab.downloads[-1]
    assert name.endswith(".toml")
    again = presets_io.validate(presets_io.parse_text(content.decode()))
    assert again == tab.session.scenario and again.controller.omega == pytest.approx(0.42)


# ---------------------------------------------------------------------------- playback and export
def test_playback_buttons_and_speed(tab):
    s, p = tab.session, tab.panels
    p.handles["view.steps_per_second"].value = 20.0
    p.press("Play")
    tab.tick(100.0)
    tab.tick(101.0)  # one second at 20 steps/s
    assert s.sim.state.k == 20
    p.press("Pause")
    tab.tick(105.0)
    assert s.sim.state.k == 20
    p.press("Step")
    assert s.sim.state.k == 21 and not s.playing
    p.press("Reset")
    assert s.sim.state.k == 0


def test_run_pauses_at_the_presets_step_count(tab):
    s = tab.session
    s.apply({"sim.steps": 12})
    s.play()
    assert s.step(50) == 12 and not s.playing and s.finished


def test_seed_input_restarts_with_that_seed(tab):
    s = tab.session
    s.step(4)
    tab.panels.seed.value = 77
    assert s.sim.seed == 77 and s.scenario.sim.seed == 77 and s.sim.state.k == 0
    other = session_for(presets_io.load("default", ["sim.seed=77"]))
    assert np.array_equal(other.sim.state.x, s.sim.state.x)


def test_export_csv_rows_match_the_engine_state(tab):
    s = tab.session
    s.step(6)
    tab.panels.export_csv.value = True
    name, content = tab.downloads[-1]
    assert name.endswith(".csv")
    rows = list(csv.DictReader(io.StringIO(content.decode())))
    assert tuple(rows[0].keys()) == TRAJECTORY_COLUMNS
    n = s.sim.robots
    assert len(rows) == 7 * n  # steps 0..6
    last = [r for r in rows if int(r["step"]) == 6]
    xy = np.array([[float(r["x"]), float(r["y"])] for r in last])
    np.testing.assert_allclose(xy, s.sim.state.x[0], rtol=1e-8, atol=1e-8)
    v = np.array([[float(r["vx"]), float(r["vy"])] for r in last])
    np.testing.assert_allclose(v, s.sim.state.u[0], rtol=1e-8, atol=1e-8)
    assert float(last[0]["t"]) == pytest.approx(s.sim.t)


def test_export_json_has_preset_seed_version_and_trajectories(tab):
    s = tab.session
    s.step(2)
    tab.panels.export_json.value = True
    doc = json.loads(tab.downloads[-1][1])
    assert presets_io.validate(doc["preset"]) == s.scenario
    assert doc["seed"] == s.sim.seed and doc["version"]
    assert len(doc["trajectories"]) == 3 * s.sim.robots
    last = doc["trajectories"][-1]
    assert last["step"] == 2 and last["x"] == pytest.approx(s.sim.state.x[0, -1, 0])


def test_history_is_a_bounded_ring_buffer():
    s = session_for(presets_io.load("default"))
    s.history.max_steps = 50
    s.step(120)
    assert len(s.frames) == 50
    rows = s.trajectory_rows()
    assert rows.shape[0] == 50 * s.sim.robots and rows[-1, 1] == 120


def test_trails_cover_the_last_trail_seconds_and_end_at_the_robots():
    s = session_for(presets_io.load("default", ["view.trail_seconds=2.0"]))
    s.step(100)  # 10 s at Δt = 0.1
    snap = s.snapshot(max_trails=5, max_trail_points=8)
    assert snap.trails.shape[0] == 5 and 2 <= snap.trails.shape[1] <= 8
    np.testing.assert_array_equal(snap.trails.points[:, -1], s.sim.state.x[0, :5])
    window = [f for f in s.frames if f.t >= s.clock() - 2.0 - 1e-9]
    assert any(np.array_equal(snap.trails.points[:, 0], f.x[:5]) for f in window)  # starts inside the window
    assert not np.array_equal(snap.trails.points[:, 0], s.frames[0].x[:5])  # not at the start of the run


def test_time_axis_stays_monotonic_when_dt_changes():
    s = session_for(presets_io.load("default"))
    s.step(10)
    s.apply({"controller.dt": 0.05})
    s.step(10)
    t = s.metric_arrays()["t"]
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(1.0 + 0.5)


def test_changes_from_another_thread_while_ticking(tab):
    """Browser callbacks run on a pool while the ticker steps: nothing may break."""
    _raw(tab)
    tab.session.play()
    errors = []

    def ticker():
        try:
            for i in range(200):
                tab.tick(i * 0.05)
        except Exception as err:  # pragma: no cover - reported below
            errors.append(err)

    th = threading.Thread(target=ticker)
    th.start()
    for i in range(60):
        tab.panels.handles["controller.omega"].value = 0.3 + 0.005 * i
        tab.panels.handles["sim.robots"].value = 10 + i % 7
    th.join()
    assert not errors
    assert tab.session.sim.policy.omega == pytest.approx(0.3 + 0.005 * 59)
    assert tab.session.sim.state.x.shape[1] == 10 + 59 % 7


def test_phase_plane_follows_the_chosen_particle_and_dimension(tab):
    s, p = tab.session, tab.panels
    s.step(30)
    p.handles["particle"].value = 3
    p.handles["dimension"].value = "y"
    p.refresh_plots()
    traces = {t.name: t for t in p.handles["phase"].figure.data}
    u_hist = np.array([f.u[3, 1] for f in list(s.frames)[-len(traces["recent"].x):]])
    a_hist = np.array([f.a[3, 1] for f in list(s.frames)[-len(traces["recent"].y):]])
    np.testing.assert_allclose(traces["recent"].x, u_hist)
    np.testing.assert_allclose(traces["recent"].y, a_hist)
    assert (traces["now"].x[0], traces["now"].y[0]) == (s.sim.state.u[0, 3, 1], s.sim.state.a[0, 3, 1])
    assert "particle 3, y" in p.handles["phase"].figure.layout.title.text
    s.pause()
    s.step(40)  # the same particle later: its points are swapped into the figure the page has
    p.refresh_plots()
    sent = {t["name"]: t for t in json.loads(p.handles["phase"]._plotly_json_str)["data"]}
    n = len(sent["recent"]["x"])
    assert n == 71  # (steps 0–70: fewer than the 120 the plane shows)
    np.testing.assert_allclose(sent["recent"]["x"], [f.u[3, 1] for f in list(s.frames)[-n:]])
    np.testing.assert_allclose(sent["recent"]["y"], [f.a[3, 1] for f in list(s.frames)[-n:]])
    assert sent["now"]["x"] == [s.sim.state.u[0, 3, 1]] and sent["now"]["y"] == [s.sim.state.a[0, 3, 1]]
    assert "reachable set" in sent and "particle 3, y" in json.loads(p.handles["phase"]._plotly_json_str)[
        "layout"]["title"]["text"]


# ---------------------------------------------------------------------------- scene
def test_arena_draws_robots_where_the_engine_has_them(tab):
    s = tab.session
    s.step(3)
    tab.tick(50.0)
    drawn = np.asarray(tab.arena.nodes["robots"].points)
    scale = VIEW_HALF / s.scenario.arena.half_size
    np.testing.assert_allclose(drawn[:, :2], s.sim.state.x[0] * scale, rtol=1e-6, atol=1e-5)
    gbest = np.asarray(tab.arena.nodes["gbest"].points)[0, :2]
    np.testing.assert_allclose(gbest, s.sim.state.yg[0] * scale, rtol=1e-6, atol=1e-5)


def test_one_dimensional_preset_draws_on_the_x_axis_and_follows(tab):
    tab.panels.preset.value = "fig3-4a"
    s = tab.session
    s.play()
    s.step(100)  # f = x1: the swarm drifts in +x for ever
    tab.tick(60.0)
    drawn = np.asarray(tab.arena.nodes["robots"].points)
    assert drawn.shape == (s.sim.robots, 3) and np.all(drawn[:, 1] == 0)
    if np.any(s.sim.state.x[0, :, 0] > s.scenario.arena.half_size):
        assert tab.arena.focus[0] > 0  # view moved with the swarm
    tab.panels.refresh_plots()  # plots for d = 1 do not fail either


def test_a_diverging_swarm_keeps_the_home_view_and_is_reported(tab):
    tab.panels.preset.value = "standard-pso"
    tab.panels.handles["controller.omega"].value = 1.1  # standard PSO outside its stable regions
    s = tab.session
    s.step(250)
    tab.tick(70.0)
    assert swarm.driver(s).outside_arena() > 0
    assert np.all(tab.arena.focus == 0)  # too spread to follow: the arena stays in view
    assert "outside the arena" in tab.panels.status.content


def test_landscape_image_rows_run_from_minus_y_as_viser_lays_them_on_the_ground():
    img = landscape_rgb(Objective(name="sphere", source=np.array([5.0, -5.0]), scale=1.0), half_size=10.0, n=41)
    brightness = img.astype(float).sum(axis=-1)
    row, col = np.unravel_index(np.argmax(brightness), brightness.shape)
    assert row < 20 and col > 20  # lightest (lowest cost) in an early row at the right: (+x, −y)


# ---------------------------------------------------------------------------- plots
def test_stability_figure_draws_the_region_boundaries_and_live_point():
    fig = figures.stability_figure(0.42, 3.1, adapted=False)
    traces = {t.name: t for t in fig.data}
    w = np.asarray(traces["order-2 (standard)"].x)
    np.testing.assert_allclose(traces["order-2 (standard)"].y, 24 * (1 - w**2) / (7 - 5 * w))
    np.testing.assert_allclose(traces["order-1 (standard)"].y, 4 * (w + 1))
    assert max(traces["order-2 (standard)"].y) == pytest.approx(4.03, abs=0.01)  # peak near ω ≈ 0.42
    assert (traces["current"].x[0], traces["current"].y[0]) == (0.42, 3.1)
    assert fig.layout.uirevision == "stability"
    assert not any(name.startswith("Adapted") for name in traces)  # only the regions of the law in use
    assert "no unit" in fig.layout.yaxis.title.text and "m/s" not in fig.layout.title.text
    adapted = figures.stability_figure(0.42, 3.1, adapted=True)
    traces = {t.name: t for t in adapted.data}
    assert not any("standard" in name for name in traces) and "3.1 m/s" in adapted.layout.title.text
    assert "bounded" in adapted.layout.annotations[0].text  # "stable" means bounded, beside the point
    robots = traces["Adapted on robots (0 ≤ ω < 1)"]
    assert min(robots.x) == 0 and max(robots.x) == 1
    # the live point is judged against the active law's region
    assert figures.in_region(0.9, 3.0, adapted=True) and not figures.in_region(0.9, 3.0, adapted=False)
    assert not figures.in_region(1.0, 3.0, adapted=True)


def test_plots_update_in_place_like_a_fresh_figure():
    fig = figures.stability_figure(0.5, 1.0, adapted=True)
    assert figures.update_stability_point(fig, 1.1, 12.0, adapted=True) is fig  # moved in place
    fresh = figures.stability_figure(1.1, 12.0, adapted=True)
    for name in ("current", "Adapted (−1 < ω < 1)"):
        a = next(t for t in fig.data if t.name == name)
        b = next(t for t in fresh.data if t.name == name)
        assert list(a.x) == list(b.x) and list(a.y) == list(b.y) and a.marker.color == b.marker.color
    assert fig.layout.title.text == fresh.layout.title.text and "OUTSIDE" in fig.layout.title.text
    assert list(fig.layout.yaxis.range) == list(fresh.layout.yaxis.range)
    assert fig.layout.annotations[0].text == fresh.layout.annotations[0].text
    standard = figures.update_stability_point(fig, 1.1, 12.0, adapted=False)  # the other law: drawn anew
    assert standard is not fig and "order-2 (standard)" in {t.name for t in standard.data}

    phase = figures.phase_figure(0.6, 4.0, 1.0, np.array([1.0]), np.array([1.0]))
    assert figures.update_phase_points(phase, np.array([1.0, 30.0]), np.array([2.0, -3.0]))
    now = next(t for t in phase.data if t.name == "now")
    assert (now.x[0], now.y[0]) == (30.0, -3.0)
    assert phase.layout.xaxis.range[1] >= 30.0  # the axis widened to show the point
    assert not figures.update_phase_points(figures.phase_figure(0.6, 4.0, 1.0), np.array([1.0]), np.array([1.0]))


def test_phase_figure_matches_fig_3_3_worked_example():
    """ω = 0.6, ĉ = 4, Δt = 1: U_j = 10, star (10, 0), square (2, −8), diamond (4, 4)."""
    u = np.array([1.0, 2.0, 3.0])
    a = np.array([0.5, -1.0, 2.0])
    fig = figures.phase_figure(0.6, 4.0, 1.0, u, a)
    traces = {t.name: t for t in fig.data}
    stars = set(zip(traces["★ ±U_j"].x, traces["★ ±U_j"].y))
    assert stars == {(10.0, 0.0), (-10.0, 0.0)}
    assert (2.0, -8.0) in set(zip(traces["■ max deceleration"].x, traces["■ max deceleration"].y))
    assert (4.0, 4.0) in set(zip(traces["◆ max acceleration"].x, traces["◆ max acceleration"].y))
    poly = np.column_stack([traces["reachable set"].x, traces["reachable set"].y])[:4]
    np.testing.assert_allclose(poly, stability.reachable_parallelogram(0.6, 4.0, 1.0))
    for name, fn in (("a2", stability.a2), ("a3", stability.a3)):
        xs, ys = np.asarray(traces[name].x), np.asarray(traces[name].y)
        np.testing.assert_allclose(ys, fn(xs, 0.6, 1.0, 4.0), rtol=1e-9, atol=1e-9)
    xs, ys = np.asarray(traces["a1"].x), np.asarray(traces["a1"].y)
    np.testing.assert_allclose(ys, stability.a1(xs, 0.6, 1.0))
    assert list(traces["recent"].x) == list(u) and traces["now"].x[0] == 3.0


def test_phase_geometry_at_omega_zero_and_without_bound():
    geo = figures.phase_geometry(0.0, 2.0, 0.5)
    assert np.all(geo["a1"][:, 0] == 0)  # vertical a1 at ω = 0
    assert np.all(geo["a2"][:, 0] == 2.0) and np.all(geo["a3"][:, 0] == -2.0)
    assert figures.phase_geometry(1.0, 2.0, 0.5) == {}
    names = {t.name for t in figures.phase_figure(0.7, 1.0, 0.1, adapted=False).data}
    assert "a1" not in names  # standard PSO: no bounds drawn


def test_speed_series_bounds():
    s = session_for(presets_io.load("default"))  # an Adapted law in 2-D
    m = {"t": np.array([0.0, 0.1, 0.2]), "max_speed": np.array([1.0, 2, 3]), "max_component": np.array([1.0, 1, 2]),
         "omega": np.full(3, 0.5), "c_hat": np.full(3, 2.0)}
    data = SPEED.data(m, s)
    assert len(data) == len(SPEED.options(s)) == 5
    np.testing.assert_allclose(data[4], 2.0 / (1 - 0.5))  # U_j = ĉ/(1 − ω)
    np.testing.assert_allclose(data[3], 4.0 * np.sqrt(2))  # U = U_j √d
    assert SPEED.render(m, (0.0, 0.2), s).scales["x"]["time"] is False
    s.apply({"controller.mode": "raw", "controller.law": "standard"})
    hidden = SPEED.options(s)
    assert hidden[3]["show"] is False and hidden[4]["show"] is False


# ---------------------------------------------------------------------------- server
def test_sessions_are_listed_per_tab(server, tab):
    assert server.sessions[HAND_TAB] is tab.session


def test_taken_port_is_refused_clearly():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(PortInUseError, match=str(port)):
            start_server("default", port=port)
        with pytest.raises(SystemExit, match="already in use"):
            serve("default", port=port)


def test_unknown_preset_is_refused():
    with pytest.raises(PresetError, match="no preset"):
        start_server("no-such-preset", port=0)


def _arrives(handle, value) -> None:
    """What viser does when a user's value reaches ``handle``: it stores the value and its time,
    then queues the callbacks on its thread pool (run here later, by :func:`_callback`)."""
    handle._impl.value = value
    handle._impl.update_timestamp = time.time()


def _callback(handle) -> None:
    for cb in handle._impl.update_cb:
        cb(GuiEvent(client=None, client_id=None, target=handle))


def test_a_value_that_arrives_while_another_change_is_applied_is_not_lost(tab):
    """A user moves two controls quickly: the second value arrives (stored, its callback queued)
    while the first change is applied and the panel is synced; the sync keeps the second value
    on its control, and its callback then applies it."""
    p, s = tab.panels, tab.session
    _arrives(p.seed, 5)
    p.handles["sim.robots"].value = 12  # the first change, applied and synced before the seed's callback
    assert s.sim.robots == 12 and p.seed.value == 5  # the sync left the waiting seed alone
    _callback(p.seed)
    assert s.scenario.sim.seed == 5 and p.seed.value == 5
    p.handles["sim.robots"].value = 13  # once taken, the control follows the scenario again
    assert p.seed.value == 5 and s.scenario.sim.seed == 5
