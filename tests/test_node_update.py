"""``view.node_update.set_array`` sends what viser's own setter sends, message for message, and
keeps what the handle holds the same: a new array of the same shape, the same values again
(nothing sent), another shape, colours, another precision's points, a removed node (refused)."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from shoal.app.view.node_update import set_array


@pytest.fixture(scope="module")
def scene():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield server.scene
    server.stop()


@pytest.fixture
def recorder(scene):
    """``record(node)``: the update messages queued for ``node`` from now on (the scene's queue,
    wrapped for the test and given back after it)."""
    wrapped: list = []

    def record(node) -> list:
        sent: list = []
        node_api = node._impl.api
        queue = node_api._queue_scene_message

        def take(message):
            if getattr(message, "name", None) == node.name:
                sent.append(message)
            queue(message)

        node_api._queue_scene_message = take
        wrapped.append((node_api, queue))
        return sent

    yield record
    for node_api, queue in reversed(wrapped):
        node_api._queue_scene_message = queue


@pytest.mark.parametrize("precision", ["float32", "float16"])
def test_points_and_colours_go_as_the_setter_sends_them(scene, recorder, precision):
    rng = np.random.default_rng(3)
    dtype = np.float32 if precision == "float32" else np.float16
    start = rng.normal(size=(20, 3)).astype(dtype)
    a = scene.add_point_cloud(f"/a_{precision}", start, colors=(255, 0, 0), point_size=0.1, precision=precision)
    b = scene.add_point_cloud(f"/b_{precision}", start, colors=(255, 0, 0), point_size=0.1, precision=precision)
    sent_a, sent_b = recorder(a), recorder(b)
    try:
        steps = [rng.normal(size=(20, 3)).astype(dtype), None, rng.normal(size=(7, 3)).astype(dtype),
                 rng.normal(size=(7, 3)).astype(dtype)]
        for value in steps:
            value = np.array(b.points) if value is None else value  # (None: the same values again)
            kept = value.copy()
            before_a, before_b = len(sent_a), len(sent_b)
            a.points = value
            queued = set_array(b, "points", value)
            assert queued == (len(sent_b) > before_b) and len(sent_a) - before_a == len(sent_b) - before_b
            assert a.points.dtype == b.points.dtype and np.array_equal(a.points, b.points)
            assert np.array_equal(value, kept)  # the caller's array is not changed
            value[...] = 0  # nor kept: a later change of it reaches neither the node nor a queued message
            assert np.array_equal(b.points, kept)
            if len(sent_b) > before_b:
                assert np.array_equal(sent_b[-1].updates["points"], kept)
        colours = rng.integers(0, 255, size=(7, 3)).astype(np.uint8)
        a.colors = colours
        set_array(b, "colors", colours)
        assert np.array_equal(a.colors, b.colors) and a.colors.dtype == b.colors.dtype
        assert [sorted(m.updates) for m in sent_a] == [sorted(m.updates) for m in sent_b]
        for ma, mb in zip(sent_a, sent_b):
            for key in ma.updates:
                assert ma.updates[key].dtype == mb.updates[key].dtype
                assert np.array_equal(ma.updates[key], mb.updates[key])
    finally:
        a.remove()
        b.remove()


def test_segments_and_a_removed_node(scene):
    segs = np.zeros((5, 2, 3), np.float32)
    a = scene.add_line_segments("/segs_a", segs, colors=(0, 0, 255), thickness=2.0)
    b = scene.add_line_segments("/segs_b", segs, colors=(0, 0, 255), thickness=2.0)
    new = np.ones((5, 2, 3), np.float32)
    a.points = new
    assert set_array(b, "points", new) and np.array_equal(a.points, b.points)
    assert not set_array(b, "points", new.copy())  # nothing new: nothing sent
    a.remove()
    b.remove()
    with pytest.raises(RuntimeError):
        a.points = new * 2
    with pytest.raises(RuntimeError):
        set_array(b, "points", new * 2)


def test_a_value_of_another_dtype_goes_through_the_setter(scene):
    a = scene.add_point_cloud("/cast", np.zeros((3, 3), np.float32), colors=(0, 0, 0), point_size=0.1,
                              precision="float32")
    try:
        set_array(a, "points", np.ones((3, 3)))  # float64: viser casts it
        assert a.points.dtype == np.float32 and np.array_equal(a.points, np.ones((3, 3)))
        set_array(a, "colors", np.full((3, 3), 0.5))  # floats in [0, 1]: viser's colours to uint8
        assert a.colors.dtype == np.uint8
    finally:
        a.remove()
