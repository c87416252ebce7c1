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

KINDS = ("default", "course-dvc", "sonar-xb-pso", "slo-walk")


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
