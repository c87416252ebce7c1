"""The shared arena of every scene kind, without a browser: one View built from a kind's layers
on a real viser scene, its legend built from the layers drawn, and the fit hook called with
the extent of each scene built."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.kinds import fleet
from shoal.app.kinds.registry import kind_for
from shoal.app.view.camera import VIEW_HALF
from shoal.presets import io as presets_io
from shoal.testing import example_presets

KINDS = tuple(example_presets().values())  # one preset of every registered kind (shoal.testing)


class Part:
    """What a kind's layers ask of its panel part: where a drag in the arena goes."""

    def __init__(self) -> None:
        self.drags: list[tuple] = []

    def drag(self, *args) -> None:
        self.drags.append(args)


@pytest.fixture
def scene(server):
    yield server.viser.scene
    server.viser.scene.reset()


def _view(scene, preset: str, fits: list | None = None):
    sc = presets_io.load(preset)
    kind = kind_for(sc)
    session = kind.session(sc)
    view = kind.view(scene, Part(), fit=(lambda w, h: fits.append((w, h))) if fits is not None else None)
    view.rebuild(session.scene_revision)
    return session, view


def _labels(view) -> set[str]:
    return {entry.label for entry in view.legend()}


@pytest.mark.parametrize("preset", KINDS)
def test_every_kind_draws_its_robots_where_the_engine_has_them(scene, preset):
    session, view = _view(scene, preset)
    session.step(3)
    view.draw(session.snapshot())
    assert view.name == kind_for(session.scenario).name and view.drawn_revision == session.revision
    pts = np.asarray(view.nodes["robots"].points, dtype=float)[:, :2]
    np.testing.assert_allclose(pts, view.to_view(session.sim.state.x[0])[:, :2], atol=1e-5)
    assert {"robot", "trail"} <= _labels(view)


def test_the_legend_names_what_is_on_screen(scene):
    session, view = _view(scene, "default")
    session.step(5)
    view.draw(session.snapshot())
    assert {"robot", "heading", "trail", "personal best", "global best", "optimum / source"} <= _labels(view)
    assert not _labels(view) & {"swarm B", "believed position"}  # no B, true positions
    session.enable_compare({"controller.law": "adapted-tanh"})
    session.step(5)
    view.draw(session.snapshot())
    assert "swarm B" in _labels(view)
    session.scrub(2)  # a recorded frame: no bests
    view.draw(session.shown_snapshot())
    assert not _labels(view) & {"personal best", "global best"}


def test_a_scene_on_slo_positions_lists_the_beliefs(scene):
    session, view = _view(scene, "slo-adapted")
    session.step(2)
    view.draw(session.snapshot())
    assert {"believed position", "believed global best"} <= _labels(view)


def test_fit_is_called_with_each_scene_built(scene):
    fits: list = []
    session, view = _view(scene, "default", fits)
    view.draw(session.snapshot())
    view.draw(session.snapshot())  # the same scene: not built again
    assert fits == [pytest.approx((VIEW_HALF, VIEW_HALF))]
    session.apply({"objective.kind": "rastrigin"})  # a new static scene
    view.rebuild(session.scene_revision)
    view.draw(session.snapshot())
    assert len(fits) == 2 and "landscape" in view.nodes


def test_a_fleet_zoom_builds_the_scene_again_at_the_new_scale(scene):
    fits: list = []
    session, view = _view(scene, "course-dvc", fits)
    view.draw(session.snapshot())
    scale = view.scale
    fleet.driver(session).set_view("swarm", 2.5)
    view.draw(session.snapshot())
    assert view.scale == pytest.approx(2.5 * scale) and len(fits) == 2
    assert view.camera.zoom == pytest.approx(2.5)


def _on_screen(view, xy) -> bool:
    """Is world point ``xy`` inside the scene square the home camera shows (± VIEW_HALF)?"""
    return bool(np.all(np.abs(view.to_scene(np.asarray(xy, dtype=float))) <= VIEW_HALF))


def test_a_rebuild_that_moves_the_source_far_away_fits_source_and_swarm_on_screen(scene):
    session, view = _view(scene, "sonar-xb-pso")
    view.draw(session.snapshot())
    home_scale = view.scale
    session.apply({"acoustics.snr0_db": -10.0})  # the source goes some 3 km away: a new scene
    view.rebuild(session.scene_revision)
    view.draw(session.snapshot())
    source = session.sim.state.source[0]
    assert np.hypot(*source) > 2.5 * session.scenario.arena.half_size
    assert _on_screen(view, source) and all(_on_screen(view, x) for x in session.sim.state.x[0])
    assert view.scale < home_scale
    session.apply({"acoustics.snr0_db": 10.0})  # back near: the home view again
    view.rebuild(session.scene_revision)
    view.draw(session.snapshot())
    assert view.scale == pytest.approx(home_scale) and np.allclose(view.focus, 0.0)


def test_fit_all_frames_a_swarm_that_left_the_arena_and_follow_keeps_it_in_the_middle(scene):
    session, view = _view(scene, "default")
    view.draw(session.snapshot())
    session.sim.state.x[0] += 5 * session.scenario.arena.half_size  # the swarm far off the arena
    session.revision += 1
    view.follow_swarm()
    view.draw(session.snapshot())
    middle = session.sim.state.x[0].mean(axis=0)
    np.testing.assert_allclose(view.focus, middle)
    view.fit_all()
    assert not view.following
    view.draw(session.snapshot())
    assert all(_on_screen(view, x) for x in session.sim.state.x[0]) and _on_screen(view, (0.0, 0.0))


# ---------------------------------------------------------------------------- what the arena says about itself
def test_the_panel_legend_lists_the_glyphs_drawn_and_swarm_b_only_with_compare(server):
    from app_helpers import hand_tab

    with hand_tab(server) as tab:
        tab.session.step(3)
        tab.tick(1.0)
        text = tab.panels.view_gui.legend.content
        assert "robot" in text and "trail" in text and "objective" in text and "swarm B" not in text
        assert "rgb(" in text  # each glyph in its colour
        tab.session.enable_compare({"controller.law": "adapted-tanh"})
        tab.session.step(2)
        tab.tick(2.0)
        assert "swarm B" in tab.panels.view_gui.legend.content


def _scale_bar(view) -> tuple[float, str]:
    """(length in metres of the scale bar drawn, its label)."""
    segs = np.asarray(view.nodes["scale"].points, dtype=float)
    bar = segs[0, :, :2] / view.scale  # scene units under the root → metres
    return float(np.hypot(*(bar[1] - bar[0]))), view.nodes["scale_label"].text


@pytest.mark.parametrize("preset", KINDS)
def test_the_scale_bar_says_its_true_length_and_follows_the_zoom(scene, preset):
    from shoal.app.view.camera import Viewport
    from shoal.app.view.layers import metre_text

    session, view = _view(scene, preset)
    view.draw(session.snapshot())
    metres, text = _scale_bar(view)
    assert text == metre_text(float(f"{metres:.4g}"))  # the label says the bar's true length
    shown = 2 * Viewport().half_height * Viewport().aspect / view.scale  # metres across the screen
    assert 0.05 * shown <= metres <= 0.2 * shown
    view.look(Viewport(half_height=Viewport().half_height / 20))  # the user zooms in 20×
    view.draw(session.snapshot())
    closer, text = _scale_bar(view)
    assert text == metre_text(float(f"{closer:.4g}"))
    assert closer < metres / 5 and 0.05 * shown / 20 <= closer <= 0.2 * shown / 20


@pytest.mark.parametrize("preset, drawn", [("default", True), ("rastrigin", True), ("standard-pso", True),
                                           ("slo-pso-sphere", True), ("slo-adapted", True), ("slo-walk", False)])
def test_chapter_3_and_slo_objectives_are_drawn_with_a_colour_bar(scene, preset, drawn):
    session, view = _view(scene, preset)
    view.draw(session.snapshot())
    assert ("landscape" in view.nodes) is drawn and ("colour_bar" in view.nodes) is drawn
    if drawn:
        low, high = (float(view.nodes[k].text) for k in ("bar_low", "bar_high"))
        assert low < high
        assert "objective (light: low cost)" in _labels(view)


@pytest.mark.parametrize("preset", KINDS)
def test_every_grid_line_lies_in_the_arena_on_the_cell_pitch_with_every_fifth_a_section(scene, preset):
    """The ground grid is a few dozen line segments (a grid plane's shader runs on every pixel of
    the ground, most of a frame in a software-rendered page): whole cells from the middle of
    the scene, sections every fifth, each line spanning the arena or course and no further."""
    session, view = _view(scene, preset)
    view.draw(session.snapshot())
    cells, sections = (np.asarray(view.nodes[k].points, dtype=float)[..., :2] / view.scale
                       for k in ("grid", "grid_sections"))
    lines = np.concatenate([cells, sections])
    lo, hi = lines.reshape(-1, 2).min(axis=0), lines.reshape(-1, 2).max(axis=0)
    assert len(lines) <= 600 and len(sections) >= 2
    vertical = lines[:, 0, 0] == lines[:, 1, 0]
    at = np.where(vertical, lines[:, 0, 0], lines[:, 0, 1])  # where each line crosses its axis (from the middle)
    pitch = np.min(np.diff(np.unique(np.round(at[vertical], 9))))
    steps = at / pitch
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-3)  # (float32 on the wire)
    is_section = np.arange(len(lines)) >= len(cells)
    assert np.all((np.round(steps).astype(int) % 5 == 0) == is_section)
    spans = np.where(vertical[:, None], lines[:, :, 1], lines[:, :, 0])  # each line runs edge to edge
    edge_lo, edge_hi = np.where(vertical[:, None], lo[1], lo[0]), np.where(vertical[:, None], hi[1], hi[0])
    np.testing.assert_allclose(np.sort(spans, axis=1), np.column_stack([edge_lo, edge_hi]), atol=1e-4 * np.max(hi - lo))


# ---------------------------------------------------------------------------- the light drawing
def _segments(view, key: str) -> int:
    return len(np.asarray(view.nodes[key].points)) if view.canvas.shown(key) else 0


@pytest.mark.parametrize("preset", KINDS)
def test_the_light_drawing_has_no_line_per_robot_and_keeps_the_view(scene, preset):
    """A page without a GPU fills every line segment's triangles on the CPU: in the light drawing
    trails are a few dots each, heading strokes and obstacle outlines go, the grid keeps its
    sections; the robots stay one point cloud and the view stays where it was. (A sonar's rays and
    Mai's neighbour edges stay lines: they are what those scenes show, for tens of robots.)"""
    from shoal.app.view.layers import TRAIL_DOTS

    session, view = _view(scene, preset)
    session.step(30)
    view.draw(session.snapshot())
    robots = session.sim.robots
    assert view.canvas.shown("trails") and not view.canvas.shown("trails_dots")
    full = {k: _segments(view, k) for k in ("grid", "obstacle_edges") if k in view.nodes}
    view.follow_swarm()
    view.draw(session.snapshot())
    focus, scale = view.focus.copy(), view.scale
    assert view.restyle(light=True) and not view.restyle(light=True)  # (a second call changes nothing)
    view.draw(session.snapshot())
    np.testing.assert_allclose(view.focus, focus)
    assert view.scale == scale
    dots = np.asarray(view.nodes["trails_dots"].points)
    assert not view.canvas.shown("trails") and 0 < len(dots) <= TRAIL_DOTS * robots
    assert not view.canvas.shown("headings") and "heading" not in _labels(view)
    assert np.asarray(view.nodes["robots"].points).shape[0] == robots
    assert _segments(view, "grid") == 0 and _segments(view, "grid_sections") > 0
    if "obstacle_edges" in full:
        assert full["obstacle_edges"] > 0 and _segments(view, "obstacle_edges") == 0
    view.restyle(light=False)
    view.draw(session.snapshot())
    assert view.canvas.shown("trails") and not view.canvas.shown("trails_dots")


def test_the_light_drawing_of_a_fleet_rings_stalled_robots_with_dots_and_draws_a_layer_as_one_line(scene):
    session, view = _view(scene, "course-dvc")
    view.restyle(light=True)
    session.step(5)
    snap = session.snapshot()
    snap.extras["stalled"] = np.arange(len(snap.x)) < 3  # three robots stalled
    view.draw(snap)
    assert not view.canvas.shown("stalled") and len(np.asarray(view.nodes["stalled_dots"].points)) == 3
    world = snap.extras["world"]
    assert len(np.asarray(view.nodes["layers"].points)) == len(world.layer_x)


def test_larger_text_builds_the_labels_again_at_their_new_size(scene):
    session, view = _view(scene, "default")
    view.draw(session.snapshot())
    small = view.nodes["source_label"].font_screen_scale
    assert view.restyle(text_scale=1.3)
    view.draw(session.snapshot())
    assert view.nodes["source_label"].font_screen_scale == pytest.approx(1.3 * small)
