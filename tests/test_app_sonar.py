"""The browser app's Chapter 6–8 scenes without a browser: acoustic session, panels, scene.

GUI handles are driven by assigning ``.value`` (their callbacks run in the test thread) on a
real viser server; a source drag is fed to the view's drag handler as viser's drag event.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pytest

from shoal.app.kinds import sonar
from shoal.app.kinds.sonar import corr_data, corr_range, true_ray_index
from shoal.engine.kinds.sonar import AcousticSwarm

from app_helpers import shown as shown_text


@dataclass
class Drag:
    """What viser's ``SceneNodeDragEvent`` carries that the view reads."""

    end_position: tuple[float, float, float]
    phase: str
    instance_index: int = 0


APP_PRESET = "sonar-xb-pso"  # the shared ``server`` fixture (conftest.py) shows this scene


def _drawn(tab, now: float):
    tab.tick(now)
    return tab.arena


def test_sonar_preset_builds_an_acoustic_swarm_and_draws_rays_from_the_robots(tab):
    s = tab.session
    assert s.kind.name == "sonar" and isinstance(s.sim, AcousticSwarm)
    assert tab.panels.name == "sonar" and tab.arena.name == "sonar"
    s.step(3)
    view = _drawn(tab, 1.0)
    x = s.sim.state.x[0]
    dashes = np.asarray(view.nodes["rays_mirror"].points).reshape(s.sim.robots, -1, 2, 3)  # a mirror ray: dashed
    assert dashes.shape[1] == 5
    ends = {"rays_true": np.asarray(view.nodes["rays_true"].points),
            "rays_mirror": np.stack([dashes[:, 0, 0], dashes[:, -1, 1]], axis=1)}
    for pts in ends.values():
        assert pts.shape == (s.sim.robots, 2, 3)
        np.testing.assert_allclose(pts[:, 0, :2], view.to_view(x)[:, :2], atol=1e-4)
    # blue = the ray of the pair that points nearer the true source
    true = ends["rays_true"][:, :, :2] / view.scale
    mirror = ends["rays_mirror"][:, :, :2] / view.scale
    to_src = s.sim.state.source[0] - x
    cos = lambda seg: np.einsum("nd,nd->n", seg[:, 1] - seg[:, 0], to_src)  # noqa: E731
    assert np.all(cos(true) >= cos(mirror) - 1e-6)
    idx = true_ray_index(x, s.sim.state.bearing.rays[0], s.sim.state.source[0])
    assert set(np.unique(idx)) <= {0, 1}
    robots = np.asarray(view.nodes["robots"].points)
    np.testing.assert_allclose(robots[:, :2], view.to_view(x)[:, :2], atol=1e-4)
    assert np.asarray(view.nodes["picks"].points).shape[0] >= 1  # selected intersections drawn
    # the true rays lie over the mirror rays: higher, and made (so drawn) after them
    height = {key: float(np.asarray(view.nodes[key].points)[0, 0, 2]) for key in view.layer("rays").keys}
    assert height["rays_true"] > height["rays_mirror"] and height["rays_sel_true"] > height["rays_sel_mirror"]
    order = list(view.nodes)
    assert order.index("rays_true") > order.index("rays_mirror")
    assert order.index("rays_sel_true") > order.index("rays_sel_mirror") > order.index("rays_true")


def test_algorithm_and_Q_reach_the_scenario_and_the_swarm(tab):
    s, p = tab.session, tab.panels
    s.step(2)
    swarm = s.sim
    p.handles["acoustics.Q"].value = 4.0  # live: no rebuild
    assert s.scenario.acoustics.Q == 4.0 and swarm.params.Q == 4.0 and swarm.band.Q == 4.0
    assert s.sim is swarm and swarm.state.k == 2
    p.handles["acoustics.a"].value = 0.5
    assert swarm.strategy.a == 0.5
    p.handles["acoustics.algorithm"].value = "B-PSO"  # rebuilds
    assert s.scenario.acoustics.algorithm == "b-pso" and s.sim.params.algorithm == "b-pso"
    assert s.sim.state.k == 0 and s.sim.params.Q == 4.0
    assert tab.messages[-1][0] == "Swarm rebuilt"
    p.handles["acoustics.algorithm"].value = "GT-PSO"
    s.step(2)
    tab.tick(1.0)
    assert s.sim.params.algorithm == "gt-pso" and s.sim.state.loc.triangles is not None
    assert tab.arena.nodes["triangles"].visible


def test_a_bad_value_is_refused_and_the_slider_restored(tab):
    s, p = tab.session, tab.panels
    p.handles["acoustics.r"].value = 30.0  # escorting needs the non-omni controller
    title, body, colour = tab.messages[-1]
    assert colour == "red" and "acoustics" in body and "nonomni" in body
    assert s.scenario.acoustics.r == 0.0 and p.handles["acoustics.r"].value == 0.0
    p.handles["acoustics.Q"].value = 5000.0  # beyond the model's range
    assert tab.messages[-1][2] == "red" and s.scenario.acoustics.Q == 1.5
    assert p.handles["acoustics.Q"].value == 1.5


def test_dragging_the_source_moves_it_in_the_engine(tab):
    s, view = tab.session, tab.arena
    s.step(1)
    _drawn(tab, 1.0)
    target = np.array([-150.0, 120.0])
    sx, sy = view.to_scene(target)
    view.layer("source").dragged(Drag((float(sx), float(sy), 0.0), "start"))
    view.layer("source").dragged(Drag((float(sx), float(sy), 0.0), "update"))
    view.layer("source").dragged(Drag((float(sx), float(sy), 0.0), "end"))
    np.testing.assert_allclose(s.sim.state.source[0], target, atol=1e-6)
    d = np.linalg.norm(s.sim.state.x[0] - target, axis=-1)
    np.testing.assert_allclose(s.sim.state.snr_db[0], 60.0 - 20 * np.log10(np.maximum(d, 1.0)), atol=1e-9)
    s.step(1)  # a still source stays where it was put
    np.testing.assert_allclose(s.sim.state.source[0], target, atol=1e-9)
    _drawn(tab, 2.0)
    src = np.asarray(view.nodes["source"].batched_positions)[0, :2]
    np.testing.assert_allclose(src, view.to_view(target)[:2], atol=1e-4)


def test_a_moving_source_continues_from_where_it_was_dropped(tab):
    tab.panels.preset.value = "escort-moving"
    s = tab.session
    assert s.kind.name == "sonar" and s.scenario.acoustics.v_n > 0
    s.step(2)
    sonar.driver(s).move_source(10.0, 20.0)
    s.step(1)
    v = s.scenario.acoustics.v_n * s.scenario.acoustics.U * s.scenario.acoustics.dt
    np.testing.assert_allclose(s.sim.state.source[0], [10.0 + v, 20.0], atol=1e-9)



def test_an_escort_status_reads_the_robots_distance_and_share_inside_the_ring(tab):
    tab.panels.preset.value = "escort-stationary"
    s = tab.session
    s.step(30)
    tab.panels.refresh_status()
    info = s.sim.info()
    dist, inside = float(info.mean_dist_to_source[0]), float(info.frac_inside_ring[0])
    assert (f"robots {dist:.0f} m from the source on average, {100 * inside:.0f}% inside r"
            in tab.panels.status.content)


def test_the_correlation_plot_shows_the_selected_robots_corr(tab):
    s, p = tab.session, tab.panels
    s.step(2)
    for robot in (0, 4):
        p.handles["robot"].value = robot
        assert s.selected_robot == robot
        tab.tick(float(robot) + 1.0)
        b = s.sim.state.bearing
        x, y, _, mark, _ = (np.asarray(a) for a in p.handles["corr"].data)
        lags_ms = b.lags * 1e3
        first = np.zeros(len(x), bool)
        first[np.unique(x, return_index=True)[1]] = True  # τ_lag may sit on the grid (sample lag)
        on_grid = first & np.isin(x, lags_ms)
        np.testing.assert_allclose(y[on_grid], b.corr[0, robot], rtol=1e-12)
        assert mark.max() == pytest.approx(b.rho[0, robot])
        assert x[np.argmax(mark)] == pytest.approx(b.tau[0, robot] * 1e3)
    snr = np.asarray(p.handles["snr"].data[1])
    assert snr.max() == pytest.approx(s.sim.state.snr_db[0].max())


def test_switching_kinds_and_export(tab):
    p = tab.panels
    p.preset.value = "course-dvc"
    assert tab.session.kind.name == "fleet"
    tab.panels.preset.value = "sonar-gt-pso"
    assert tab.session.kind.name == "sonar" and tab.session.sim.params.algorithm == "gt-pso"
    assert "Chapters 6–8" in tab.panels.notes.content
    tab.session.step(3)
    csv_text = tab.session.export_csv().decode()
    assert csv_text.splitlines()[0].startswith("run,step,t,robot,x,y")
    assert len(csv_text.splitlines()) == 1 + 4 * tab.session.sim.robots
    doc = json.loads(tab.session.export_json())
    assert doc["preset"]["acoustics"]["algorithm"] == "gt-pso" and len(doc["source"]) == 2


def test_upload_of_an_acoustic_preset(tab):
    tab.panels.preset.value = "course-dvc"
    text = (b'name = "mine"\n[sim]\nrobots = 6\nsteps = 100\nseed = 3\n'
            b'[acoustics]\nalgorithm = "x-pso"\nsnr0_db = 4.0\n')
    assert tab.panels.upload_preset("mine.toml", text)
    assert tab.session.kind.name == "sonar" and tab.session.sim.robots == 6
    assert tab.session.sim.params.algorithm == "x-pso"


def test_corr_data_marks_tau_and_the_window_without_a_trace_along_the_plot():
    lags = np.linspace(-1e-3, 1e-3, 21)
    corr = np.cos(lags * 3000)
    x, line, samples, mark, window = corr_data(lags, corr, 2.5e-4, 0.9, window=5e-4)
    lo, hi = corr_range(corr, 0.9)
    assert np.all(np.diff(x) >= 0)
    np.testing.assert_allclose(line, np.interp(x / 1e3, lags, corr))  # the curve as it was
    shown = samples >= lo  # the sample dots: the lag grid, nothing else
    np.testing.assert_allclose(np.sort(x[shown]), lags * 1e3)
    np.testing.assert_allclose(samples[shown], corr[np.argsort(lags)])
    # τ_lag: one point at ρ, everything else below the plot (clipped): no trace along its floor
    assert np.count_nonzero(mark >= lo) == 1 and mark.max() == 0.9 and x[np.argmax(mark)] == pytest.approx(0.25)
    # the window: its two edges at the top, nothing else on the plot
    edges = window >= lo
    assert np.count_nonzero(edges) == 2 and np.all(window[edges] == hi)
    np.testing.assert_allclose(x[edges], [-0.5, 0.5])


def test_corr_note_says_the_sample_rate_and_why_the_curve_is_coarse():
    from shoal.app.kinds.registry import session_for
    from shoal.app.kinds.sonar import corr_note
    from shoal.presets.io import load

    s = session_for(load("sonar-xb-pso"))  # Chapter 7's reading: 4 kHz, the sample lag
    s.step(1)
    text = corr_note(s)
    assert "f_s = 4 kHz" in text and "7 lags" in text and "±D/c = ±0.5 ms" in text and "coarse" in text


def test_the_notes_mark_where_each_value_comes_from(tab):
    p = tab.panels
    p.preset.value = "sonar-xb-pso"
    text = shown_text(tab.panels.marks.content)
    assert "- acoustics.fs = 4000.0: **fitted**" in text and "- acoustics.c1_share = 0.25: **fitted**" in text
    assert "- acoustics.f_c = 1000.0: **stated**, Rossides Table 7.1" in text and "unmarked" not in text
    tab.panels.preset.value = "sonar-gt-pso"
    assert "- acoustics.c1_share = 0.5: **stated**, Rossides Algorithm 2" in shown_text(tab.panels.marks.content)
