"""Trails reach the page as appended pieces (``app/view/trails.py``): what the pieces hold
together is exactly the trail's segments (or dots), and a draw sends about the same whatever
the run's age."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from shoal.app.kinds.registry import kind_for
from shoal.app.session.history import Trails
from shoal.app.view.shapes import trail_segments
from shoal.app.view.trails import drawn_points
from shoal.presets import io as presets_io


@pytest.fixture
def scene(server):
    yield server.viser.scene
    server.viser.scene.reset()


class Sent:
    """Every scene message a view queues, with the bytes of its arrays."""

    def __init__(self, scene: Any, monkeypatch: Any) -> None:
        self.messages: list[Any] = []
        ws = scene._websock_interface
        queue = ws.queue_message

        def counted(message: Any) -> None:
            self.messages.append(message)
            queue(message)

        monkeypatch.setattr(ws, "queue_message", counted)

    def take(self) -> list[Any]:
        out, self.messages = self.messages, []
        return out


def array_bytes(message: Any) -> int:
    def size(v: Any) -> int:
        if isinstance(v, np.ndarray):
            return v.nbytes
        if isinstance(v, dict):
            return sum(size(x) for x in v.values())
        if isinstance(v, (list, tuple)):
            return sum(size(x) for x in v)
        return 0
    return sum(size(getattr(message, f.name)) for f in dataclasses.fields(message))


def _view(scene, preset: str, *overrides: str):
    sc = presets_io.load(preset, ["sim.steps=100000", *overrides])
    kind = kind_for(sc)
    session = kind.session(sc)
    view = kind.view(scene, None)
    view.rebuild(session.scene_revision)
    return session, view


def _segment_set(segs: np.ndarray) -> np.ndarray:
    """(S, 2, 2) segments as sorted distinct rows (the order of pieces is the page's business, and a
    segment drawn twice looks as one)."""
    return np.unique(np.round(np.asarray(segs, dtype=np.float64).reshape(-1, 4), 4), axis=0)


def _drawn_segments(view, key: str) -> np.ndarray:
    pts = drawn_points(view.canvas, key)
    return pts.reshape(-1, 2, 3)[:, :, :2] if len(pts) else np.zeros((0, 2, 2))


@pytest.mark.parametrize("preset, extra", [("default", ()), ("course-dvc", ("view.trail_seconds=6",)),
                                           ("default", ("view.trail_seconds=1.5",))])
def test_the_pieces_hold_the_trails_segments_at_every_draw(scene, preset, extra):
    session, view = _view(scene, preset, *extra)
    for step in range(260):
        session.step(1)
        snap = session.shown_snapshot()
        view.draw(snap)
        if step % 7 and step < 250:
            continue
        want = view.to_view(trail_segments(snap.trails.points), 0.0)[:, :, :2]
        np.testing.assert_allclose(_segment_set(_drawn_segments(view, "trails")), _segment_set(want), atol=1e-4)
    assert view.canvas.shown("trails")
    pieces = [k for k in view.nodes if k.startswith("trails/")]
    assert 2 <= len(pieces) <= 40 // 4 + 3  # a few pieces of up to four stride segments, not one a step


def test_a_scrubbed_frame_and_swarm_b_draw_their_own_trails_and_a_reset_starts_afresh(scene):
    session, view = _view(scene, "default")
    session.enable_compare({"controller.U": 3.0})
    session.step(200)
    view.draw(session.shown_snapshot())
    session.scrub(120)
    snap = session.shown_snapshot()
    view.draw(snap)
    for key, trails in (("trails", snap.trails), ("twin_trails", snap.twin[1])):
        want = view.to_view(trail_segments(trails.points), 0.0)[:, :, :2]
        np.testing.assert_allclose(_segment_set(_drawn_segments(view, key)), _segment_set(want), atol=1e-4)
        assert trails.steps[-1] == 120
    session.reset()
    session.step(3)
    snap = session.shown_snapshot()
    view.draw(snap)
    want = view.to_view(trail_segments(snap.trails.points), 0.0)[:, :, :2]
    np.testing.assert_allclose(_segment_set(_drawn_segments(view, "trails")), _segment_set(want), atol=1e-4)
    session.disable_compare()
    view.draw(session.shown_snapshot())
    assert not view.canvas.shown("twin_trails") and not any(k.startswith("twin_trails/") for k in view.nodes)


def test_trail_dots_stay_put_and_keep_within_their_budget(scene):
    session, view = _view(scene, "default")
    view.restyle(light=True)
    before: set | None = None
    for step in range(300):
        session.step(1)
        snap = session.shown_snapshot()
        view.draw(snap)
        dots = drawn_points(view.canvas, "trails_dots")[:, :2]
        assert 0 < len(dots) <= 16 * len(snap.trails)
        end = {tuple(p) for p in np.round(view.to_view(snap.trails.points[:, -1], 0.0)[:, :2], 5)}
        now = {tuple(p) for p in np.round(dots, 5)} - end
        if before is not None and step > 160:  # every dot but the newest stays where it was, or leaves
            fresh = now - before
            assert len(fresh) <= len(snap.trails), step  # at most one new column of dots a step
        before = now | end
    assert not view.canvas.shown("trails")


def _per_step(session, view, sent: Sent, steps: int) -> tuple[float, float]:
    """Trail messages and their array bytes per step over the next ``steps`` steps."""
    sent.take()
    for _ in range(steps):
        session.step(1)
        view.draw(session.shown_snapshot())
    msgs = [m for m in sent.take() if "trails" in str(getattr(m, "name", ""))]
    return len(msgs) / steps, sum(array_bytes(m) for m in msgs) / steps


@pytest.mark.parametrize("light", [False, True])
def test_a_draw_sends_the_same_at_step_100_and_at_step_5000(scene, monkeypatch, light):
    """A tab's trail traffic does not grow with the run's age: the pieces sent per step (lines
    and the light drawing's dots) are as many and as large late in the run as early."""
    session, view = _view(scene, "default")
    view.restyle(light=light)
    sent = Sent(scene, monkeypatch)
    session.step(80)
    view.draw(session.shown_snapshot())
    early = _per_step(session, view, sent, 40)
    session.step(4900)
    view.draw(session.shown_snapshot())
    late = _per_step(session, view, sent, 40)
    assert late[0] <= 1.25 * early[0] and late[1] <= 1.25 * early[1], (early, late)
    robots = session.sim.robots
    assert late[1] < 4 * robots * 2 * 3 * 4  # a few segments a robot a step, not the trail (37 a robot)


def test_plain_trails_arrays_still_draw():
    t = Trails.of(np.zeros((3, 5, 2)))
    assert t.shape == (3, 5, 2) and len(t) == 3 and list(t.steps) == [0, 1, 2, 3, 4]
    assert Trails.of(np.zeros((3, 5, 2))).epoch != t.epoch
