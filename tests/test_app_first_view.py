"""The first view of a new tab starts at step 0 and plays once the page has drawn (its first
camera report), or after a while when no report comes; a scene the user (or a lesson's Set up)
has touched meanwhile is left as it is."""

from __future__ import annotations

import time

import pytest

from shoal.app.tab import TabApp
from shoal.presets.io import load


class Camera:
    """What a tab reads of viser's ``CameraHandle`` and how it hears of a report."""

    def __init__(self) -> None:
        self.callbacks: list = []
        self.aspect, self.image_height, self.fov = 1.6, 800, 0.14
        self.position, self.look_at, self.up_direction = (0.0, 0.0, 140.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)

    def on_update(self, cb) -> None:
        self.callbacks.append(cb)

    def report(self) -> None:
        for cb in self.callbacks:
            cb(self)


@pytest.fixture(autouse=True)
def _clean(server):
    yield
    server.viser.gui.reset()
    server.viser.scene.reset()


def _tab(server, camera):
    from shoal.app.kinds.registry import session_for

    tab = TabApp(session_for(load("default")), server.viser.gui, server.viser.scene, camera=camera)
    tab.auto_tick = False
    return tab


def test_a_new_tab_waits_at_step_0_for_its_page_to_draw_then_plays(server):
    camera = Camera()
    tab = _tab(server, camera)
    tab.play_when_drawn(60.0)
    for k in range(10):
        tab.tick(float(k))
    assert not tab.session.playing and tab.session.k == 0  # nothing shown yet: nothing run
    camera.report()  # the page's first frame is up
    assert tab.session.playing
    tab.tick(20.0)
    tab.tick(21.0)
    assert tab.session.k > 0


def test_without_a_camera_report_it_plays_after_a_while_unless_the_scene_was_touched(server):
    tab = _tab(server, Camera())
    tab.play_when_drawn(0.0)
    tab.tick(time.monotonic() + 1.0)
    assert tab.session.playing  # no report at all (a page that never draws): it plays anyway
    touched = _tab(server, Camera())
    touched.play_when_drawn(0.0)
    touched.replace(load("standard-pso"), play=False)  # a lesson's Set up: paused at step 0, on purpose
    touched.tick(time.monotonic() + 1.0)
    assert not touched.session.playing and touched.session.k == 0
