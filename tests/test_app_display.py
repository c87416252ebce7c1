"""The Display boxes of a tab without a browser: the light drawing, the 3-D view and the
projector mode reach the arena, the plots, the board and the status area, and outlive a swap of
scene kinds; a tipped camera is put straight above what it looks at."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from viser import GuiEvent

from shoal.app.panel.view_row import BOXES, DISPLAY_BUTTON, LIGHT_NOTE, SWITCH, TEXT_SCALE
from shoal.app.view import projector
from shoal.app.view.camera import straighten, tipped
from shoal.app.view.page import LIGHT_LABEL, SHOW_BOXES, SOFTWARE_TOAST, page_script
from shoal.presets.io import load


class Camera:
    """What :func:`tipped` and :func:`straighten` read and set of a viser ``CameraHandle``."""

    def __init__(self, position, look_at, up=(0.0, 1.0, 0.0)) -> None:
        self.position, self.look_at, self.up_direction = position, look_at, up


def test_a_camera_looking_straight_down_is_not_tipped_and_a_tipped_one_is_put_straight():
    assert not tipped(Camera((3.0, -2.0, 160.0), (3.0, -2.0, 0.0)))
    assert not tipped(Camera((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))  # (no report yet: at its target)
    tilt = math.radians(20)
    cam = Camera((1.0 + 50 * math.sin(tilt), 2.0, 50 * math.cos(tilt)), (1.0, 2.0, 0.0), up=(0.3, 0.0, 0.9))
    assert tipped(cam)
    straighten(cam)
    assert cam.look_at == (1.0, 2.0, 0.0)  # the user's pan stays …
    np.testing.assert_allclose(cam.position, (1.0, 2.0, 50.0))  # … and the zoom (the distance)
    assert cam.up_direction == (0.0, 1.0, 0.0) and not tipped(cam)


def test_the_page_script_names_the_box_it_ticks_and_the_toast_it_closes():
    js = page_script()
    assert "%(" not in js and f'"{LIGHT_LABEL}"' in js and f'"{SOFTWARE_TOAST}"' in js and f'"{SHOW_BOXES}"' in js
    assert LIGHT_LABEL == BOXES[0][0] and SHOW_BOXES == DISPLAY_BUTTON  # the panel's names, as the script finds them
    js = projector.projector_script()
    assert "%(" not in js and f'"{SWITCH}"' in js and SWITCH == projector.SWITCH
    assert TEXT_SCALE == projector.PROJECTOR_SCALE == 2.0  # every text twice its size
    assert f'"{projector.PARAM}"' in js and f'"{projector.STORE}"' in js  # the address and the browser keep it


def _box(tab, field):
    return tab.panels.view_gui.boxes[field]


def test_ticking_light_drawing_draws_the_arena_lightly_and_says_so_in_the_status_area(tab):
    tab.session.step(20)
    tab.tick(1.0)
    assert not tab.arena.canvas.light and LIGHT_NOTE not in tab.panels.status.content
    assert tab.arena.canvas.shown("trails") and tab.arena.canvas.shown("headings")
    _box(tab, "light").value = True  # as a click (or the page's own tick on software WebGL) sets it
    assert tab.display.light
    tab.tick(2.0)
    status = tab.panels.status.content
    assert tab.arena.canvas.light and status.endswith("<br>" + LIGHT_NOTE) and "Light drawing" in LIGHT_NOTE
    assert status.startswith("**default**")  # the status line first, the note on a line of its own
    assert tab.arena.canvas.shown("trails_dots") and not tab.arena.canvas.shown("trails")
    assert not tab.arena.canvas.shown("headings")
    _box(tab, "light").value = False
    tab.tick(3.0)
    assert not tab.arena.canvas.light and LIGHT_NOTE not in tab.panels.status.content
    assert tab.arena.canvas.shown("trails")


def test_projector_mode_doubles_the_arena_labels_the_plots_axes_and_figures_and_moves_the_board(tab):
    tab.session.step(5)
    tab.tick(1.0)
    small = tab.arena.nodes["source_label"].font_screen_scale
    axes = tab.panels.handles["best_distance"].axes
    assert "font" not in axes[0]
    fig = tab.panels.handles["stability"].figure
    assert fig.layout.font.size == 12 and fig.layout.title.font.size == 14  # nothing under 12 px
    assert tab.panels.board.placed is False  # left of the arena
    _box(tab, "projector").value = True
    tab.session.step(1)
    tab.tick(2.0)
    assert tab.display.projector and tab.arena.canvas.text_scale == TEXT_SCALE
    assert tab.arena.nodes["source_label"].font_screen_scale == pytest.approx(TEXT_SCALE * small)
    big = tab.panels.handles["best_distance"].axes
    assert big[0]["font"].startswith(f"{round(12 * TEXT_SCALE)}px") and big[1]["size"] > axes[1]["size"]
    fig = tab.panels.handles["stability"].figure
    assert fig.layout.font.size == 24 and fig.layout.title.font.size == 28
    assert all(note.font.size == 24 for note in fig.layout.annotations)
    assert tab.panels.board.placed is True  # under the controls
    _box(tab, "projector").value = False
    tab.tick(3.0)
    assert tab.panels.handles["stability"].figure.layout.font.size == 12 and tab.panels.board.placed is False


def test_the_display_outlives_a_swap_to_another_kind_of_scene(tab):
    _box(tab, "light").value = True
    _box(tab, "orbit").value = True
    tab.replace(load("course-dvc"))
    tab.session.step(3)
    tab.tick(1.0)
    assert tab.session.kind.name == "fleet" and tab.arena.canvas.light and LIGHT_NOTE in tab.panels.status.content
    assert _box(tab, "light").value and _box(tab, "orbit").value and not _box(tab, "projector").value
    assert tab.arena.canvas.shown("trails_dots") and not tab.arena.canvas.shown("obstacle_edges")


def test_a_tick_that_arrives_while_another_display_change_is_drawn_is_not_lost(tab):
    """The page ticks the light drawing (viser stores the value and queues the callback) while another
    Display change is drawn and the boxes are synced; the sync leaves the waiting tick alone and its
    callback then turns the light drawing on (a loaded machine's first page lost it before)."""
    light = _box(tab, "light")
    light._impl.value = True  # what viser does as a user's value arrives, before its callback runs
    light._impl.update_timestamp = time.time()
    _box(tab, "projector").value = True  # another change, drawn and synced meanwhile
    assert light.value and not tab.display.light
    for cb in light._impl.update_cb:
        cb(GuiEvent(client=None, client_id=None, target=light))
    assert tab.display.light and light.value
    tab.tick(1.0)
    assert tab.arena.canvas.light and LIGHT_NOTE in tab.panels.status.content
    _box(tab, "projector").value = False  # once taken, the box follows the display again
    assert light.value and tab.display.light
