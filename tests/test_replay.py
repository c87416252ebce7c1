"""Replay files (``shoal.app.replay``): round trip, and every kind of bad file refused with a
message that says what is wrong (size, format, version, truncation, shapes, values)."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest

from shoal.app import replay
from shoal.app.replay import ReplayError


def recording(frames: int = 6, robots: tuple[int, ...] = (3,), d: int = 2) -> replay.Recording:
    """A small recording whose robot count changes from frame to frame (``robots`` cycled)."""
    rng = np.random.default_rng(4)
    ns = [robots[i % len(robots)] for i in range(frames)]
    names = ("t", "max_speed")
    meta = replay.make_meta(shoal="0.0.test", preset={"name": "unit", "sim": {"seed": 5}}, name="unit", seed=5,
                            kind="Session", metrics=names, live_edits=2)
    return replay.from_frames(
        meta, k=list(range(frames)), t=[0.1 * i for i in range(frames)],
        xs=[rng.normal(size=(n, d)) for n in ns], headings=[rng.uniform(-3, 3, n) for n in ns],
        statuses=[rng.integers(0, 2, n) for n in ns], metrics=rng.normal(size=(frames, len(names))))


def npz(**arrays: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return buf.getvalue()


def arrays_of(rec: replay.Recording, **changes) -> dict[str, np.ndarray]:
    """The arrays of ``rec``'s file (version 2), with ``changes`` (None drops an array)."""
    with np.load(io.BytesIO(replay.to_bytes(rec))) as npz:
        out = {name: npz[name] for name in npz.files}
    if "meta" in changes:
        changes["meta"] = np.frombuffer(json.dumps(changes["meta"]).encode(), np.uint8)
    out.update(changes)
    return {k: v for k, v in out.items() if v is not None}


def refused(content: bytes) -> str:
    with pytest.raises(ReplayError) as err:
        replay.from_bytes(content, "bad.npz")
    return "\n".join(err.value.messages)


# ---------------------------------------------------------------------------- round trip
@pytest.mark.parametrize("robots, d", [((3,), 2), ((2, 5, 4), 2), ((4,), 1), ((3,), 3)])
def test_round_trip_keeps_every_frame_and_the_metadata(robots, d):
    rec = recording(robots=robots, d=d)
    back = replay.from_bytes(replay.to_bytes(rec), "run.npz")
    assert back.meta == rec.meta
    assert (back.name, back.seed, back.metric_names) == ("unit", 5, ("t", "max_speed"))
    for name in ("k", "t", "n", "x", "heading", "status", "metrics"):
        np.testing.assert_array_equal(getattr(back, name), getattr(rec, name))
    for i in range(rec.frames):
        for a, b in zip(back.robots(i), rec.robots(i)):
            np.testing.assert_array_equal(a, b)
        assert len(back.robots(i)[0]) == robots[i % len(robots)]


def test_the_file_is_compressed():
    rec = recording(frames=400, robots=(20,))
    rec = replay.from_frames(rec.meta, list(rec.k), list(rec.t), [np.zeros((20, 2))] * 400, [np.zeros(20)] * 400,
                             [np.zeros(20)] * 400, rec.metrics)
    assert len(replay.to_bytes(rec)) < rec.x.nbytes / 10


# ---------------------------------------------------------------------------- bad files
def test_a_file_over_the_size_limit_is_refused_before_reading():
    msg = refused(b"\0" * (replay.MAX_REPLAY_BYTES + 1))
    assert "larger than the 20 MiB limit" in msg


@pytest.mark.parametrize("cut", [0.5, 0.9, 0.99])
def test_a_truncated_file_is_refused(cut):
    data = replay.to_bytes(recording(frames=50))
    msg = refused(data[: int(len(data) * cut)])
    assert "truncated" in msg or "damaged" in msg


def test_a_file_that_is_not_a_replay_is_refused():
    assert "not a replay" in refused(b"[controller]\nomega = 0.5\n")
    assert "missing" in refused(npz(a=np.zeros(3)))


@pytest.mark.parametrize("version, words", [(3, "newer than this shoal reads"), ("1", "not one this shoal reads"),
                                            (True, "not one this shoal reads")])
def test_another_format_version_is_refused(version, words):
    rec = recording()
    msg = refused(npz(**arrays_of(rec, meta={**rec.meta, "version": version})))
    assert words in msg and "version" in msg


def test_another_format_name_and_missing_meta_fields_are_named():
    rec = recording()
    assert "format" in refused(npz(**arrays_of(rec, meta={**rec.meta, "format": "other"})))
    meta = {k: v for k, v in rec.meta.items() if k != "seed"}
    assert "meta.seed" in refused(npz(**arrays_of(rec, meta=meta)))
    assert "meta.metrics" in refused(npz(**arrays_of(rec, meta={**rec.meta, "metrics": "t"})))


@pytest.mark.parametrize("change, name", [
    (dict(heading=np.zeros(5)), "heading"),
    (dict(status=np.zeros((3, 3))), "status"),
    (dict(x=np.zeros((18, 4))), "x"),
    (dict(t=np.zeros(4)), "t"),
    (dict(metrics=np.zeros((6, 3))), "metrics"),
    (dict(n=np.full(6, 2)), "n"),
    (dict(k=np.array([0, 1, 2, 2, 3, 4])), "k"),
    (dict(t=np.array([0.0, 0.1, 0.2, np.nan, 0.4, 0.5])), "t"),
    (dict(x=np.where(np.arange(36).reshape(18, 2) == 7, np.nan, 1.0)), "x"),
    (dict(x=np.full((18, 2), np.inf)), "x"),
    (dict(heading=np.array([0.0] * 17 + [-np.inf])), "heading"),
])
def test_wrong_shapes_and_values_are_named(change, name):
    msg = refused(npz(**arrays_of(recording(), **change)))
    assert f"bad.npz: {name}:" in msg


def test_pickled_objects_are_refused():
    rec = recording()
    arrays = arrays_of(rec, x=np.array([{"a": 1}] * 18, dtype=object))
    buf = io.BytesIO()
    np.savez(buf, **arrays)  # object arrays need pickle
    assert "expected numbers" in refused(buf.getvalue())


def test_a_zip_bomb_is_refused_from_the_array_headers():
    """An array that claims 10⁹ numbers is refused before anything is unpacked."""
    rec = recording()
    good = arrays_of(rec)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, arr in good.items():
            if name == "x":
                head = io.BytesIO()
                np.lib.format.write_array_header_1_0(
                    head, {"descr": "<f8", "fortran_order": False, "shape": (10**9, 2)})
                zf.writestr("x.npy", head.getvalue())  # a header and no data
            else:
                member = io.BytesIO()
                np.save(member, arr)
                zf.writestr(f"{name}.npy", member.getvalue())
    msg = refused(buf.getvalue())
    assert "x: 1,000,000,000 robot rows" in msg  # (from the header, before the count of all numbers)


# ---------------------------------------------------------------------------- version 2: B and the scene
def full_recording(frames: int = 6) -> replay.Recording:
    """Three robots a frame, swarm B's two from frame 1 on, two obstacles then three from frame 3, and a
    source that moves every frame."""
    rng = np.random.default_rng(7)
    base = recording(frames)
    xs = [base.robots(i)[0] for i in range(frames)]
    twins = [None] + [(rng.normal(size=(2, 2)), np.array([0, i % 2])) for i in range(1, frames)]
    first = np.array([[5.0, 1.0, 0.5], [7.0, -1.0, 0.75]])
    scenes = [{"obstacles": first if i < 3 else np.vstack([first, [[9.0, 2.0, 1.0]]]),
               "source": np.array([[10.0 + 0.5 * i, -2.0]])} for i in range(frames)]
    meta = {**base.meta, "twin": {"overrides": {"controller.law": "standard"}}}
    return replay.from_frames(meta, list(base.k), list(base.t), xs, [base.robots(i)[1] for i in range(frames)],
                              [base.robots(i)[2] for i in range(frames)], base.metrics, twins=twins, scenes=scenes)


def test_version_2_keeps_swarm_b_and_the_scene_as_it_changed():
    rec = full_recording()
    back = replay.from_bytes(replay.to_bytes(rec), "run.npz")
    assert back.meta["version"] == 2 and back.twin_overrides == {"controller.law": "standard"}
    assert back.twin(0) is None and back.b_n.tolist() == [0, 2, 2, 2, 2, 2]
    for i in range(1, 6):
        for a, b in zip(back.twin(i), rec.twin(i)):
            np.testing.assert_array_equal(a, b)
    obstacles = back.scene["obstacles"]
    assert obstacles.i.tolist() == [0, 3] and obstacles.n.tolist() == [2, 3]  # changes only, not a copy a frame
    assert len(back.scene_at(2)["obstacles"]) == 2 and len(back.scene_at(5)["obstacles"]) == 3
    assert back.scene["source"].i.tolist() == list(range(6))
    np.testing.assert_array_equal(back.scene_at(4)["source"], [[12.0, -2.0]])


def test_a_scene_part_that_never_changes_is_stored_once():
    rec = recording(frames=400)
    still = np.array([[1.0, 2.0, 0.5]] * 300)
    rec = replay.from_frames(rec.meta, list(rec.k), list(rec.t), [rec.robots(i)[0] for i in range(400)],
                             [rec.robots(i)[1] for i in range(400)], [rec.robots(i)[2] for i in range(400)],
                             rec.metrics, scenes=[{"obstacles": still.copy()} for _ in range(400)])
    back = replay.from_bytes(replay.to_bytes(rec))
    assert back.scene["obstacles"].v.shape == (300, 3) and back.scene["obstacles"].i.tolist() == [0]
    assert "source" not in back.scene and back.twin_overrides is None and not len(back.b_x)


def v1_bytes(rec: replay.Recording) -> bytes:
    """A version-1 file exactly as shoal wrote them before version 2 (meta without ``twin``, the
    seven arrays of the robots and metrics and nothing else)."""
    meta = {key: rec.meta[key] for key in ("format", "version", "shoal", "preset", "name", "seed", "kind",
                                            "metrics", "live_edits")}
    meta["version"] = 1
    buf = io.BytesIO()
    np.savez_compressed(buf, meta=np.frombuffer(json.dumps(meta, separators=(",", ":")).encode("utf-8"), np.uint8),
                        k=rec.k, t=rec.t, n=rec.n, x=rec.x, heading=rec.heading, status=rec.status,
                        metrics=rec.metrics)
    return buf.getvalue()


def test_a_version_1_file_still_loads_without_b_or_scene():
    rec = full_recording()
    back = replay.from_bytes(v1_bytes(rec), "old.npz")
    assert back.meta["version"] == 1 and back.twin_overrides is None and back.scene == {}
    assert all(back.twin(i) is None for i in range(back.frames)) and back.b_x.shape == (0, 2)
    np.testing.assert_array_equal(back.x, rec.x)
    with zipfile.ZipFile(io.BytesIO(v1_bytes(rec))) as zf:
        assert sorted(zf.namelist()) == sorted(f"{a}.npy" for a in ("meta",) + replay.ARRAYS[1])


def test_a_version_2_file_without_its_new_arrays_is_refused():
    rec = full_recording()
    msg = refused(npz(**arrays_of(rec, b_x=None, source_v=None)))
    assert "missing b_x, source_v" in msg and "version-2" in msg
    assert "meta.twin" in refused(npz(**arrays_of(rec, meta={k: v for k, v in rec.meta.items() if k != "twin"})))
    assert "meta.twin" in refused(npz(**arrays_of(rec, meta={**rec.meta, "twin": {"overrides": "x"}})))
    assert "meta.twin" in refused(npz(**arrays_of(rec, meta={**rec.meta, "twin": [1]})))


HUGE = 2**62  # counts that overflow int64 when added up


@pytest.mark.parametrize("change, name", [
    (dict(b_n=np.zeros(5, np.int64)), "b_n"),
    (dict(b_x=np.zeros((10, 4))), "b_x"),
    (dict(b_x=np.zeros(20)), "b_x"),
    (dict(b_status=np.zeros(11)), "b_status"),
    (dict(b_n=np.array([0, 2, 2, 2, 2, 3])), "b_n"),
    (dict(b_n=np.array([0, HUGE, HUGE, HUGE, HUGE, 10])), "b_n"),  # adds up to 10 in int64
    (dict(b_n=np.array([0, -2, 4, 2, 2, 4])), "b_n"),
    (dict(n=np.array([HUGE, HUGE, HUGE, HUGE, 1, 17])), "n"),  # adds up to 18 in int64
    (dict(b_x=np.full((10, 2), np.nan)), "b_x"),
    (dict(b_x=np.where(np.arange(20).reshape(10, 2) == 13, np.inf, 0.0)), "b_x"),
    (dict(obstacles_v=np.where(np.arange(15).reshape(5, 3) == 4, np.nan, 1.0)), "obstacles_v"),
    (dict(obstacles_v=np.array([[5.0, 1.0, 0.5], [7.0, -1.0, -0.75]] + [[1.0, 1.0, 1.0]] * 3)), "obstacles_v"),
    (dict(obstacles_v=np.zeros((5, 2))), "obstacles_v"),
    (dict(obstacles_v=np.zeros((5, 3, 1))), "obstacles_v"),
    (dict(obstacles_i=np.array([1, 3])), "obstacles_i"),
    (dict(obstacles_i=np.array([0, 6])), "obstacles_i"),
    (dict(obstacles_i=np.array([3, 0])), "obstacles_i"),
    (dict(obstacles_i=np.arange(7), obstacles_n=np.ones(7, np.int64), obstacles_v=np.ones((7, 3))), "obstacles_i"),
    (dict(obstacles_n=np.array([2, 4])), "obstacles_n"),
    (dict(obstacles_n=np.array([HUGE, 5 - HUGE])), "obstacles_n"),
    (dict(obstacles_n=np.array([2])), "obstacles_n"),
    (dict(source_n=np.array([2, 0, 1, 1, 1, 1])), "source_n"),
    (dict(source_v=np.full((6, 2), np.inf)), "source_v"),
    (dict(source_v=np.full((6, 2), 1e300)), "source_v"),  # finite, but no view could draw it
    (dict(obstacles_v=np.array([[5.0, 1.0, 1e300]] * 5)), "obstacles_v"),
    (dict(source_v=np.zeros((6, 3))), "source_v"),
])
def test_wrong_shapes_and_values_of_b_and_the_scene_are_named(change, name):
    msg = refused(npz(**arrays_of(full_recording(), **change)))
    assert f"bad.npz: {name}:" in msg


def test_too_many_obstacles_at_once_are_refused():
    rows = replay.MAX_ROWS_SHOWN + 1
    msg = refused(npz(**arrays_of(full_recording(), obstacles_i=np.array([0]), obstacles_n=np.array([rows]),
                                  obstacles_v=np.ones((rows, 3)))))
    assert "obstacles_n: at most" in msg


@pytest.mark.parametrize("member", ["b_x", "obstacles_v", "source_i"])
def test_a_zip_bomb_in_the_new_arrays_is_refused_from_the_headers(member):
    good = arrays_of(full_recording())
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, arr in good.items():
            head = io.BytesIO()
            if name == member:
                shape = (10**9,) + arr.shape[1:]
                np.lib.format.write_array_header_1_0(head, {"descr": "<f8", "fortran_order": False, "shape": shape})
            else:
                np.save(head, arr)
            zf.writestr(f"{name}.npy", head.getvalue())
    msg = refused(buf.getvalue())
    assert "numbers once unpacked" in msg or f"{member}: 1,000,000,000 robot rows" in msg  # (both from headers)


def test_too_many_frames_are_refused_from_the_headers():
    """Each frame shown becomes objects of its own: a file of a million one-robot frames (within
    the number limit) would take gigabytes once loaded."""
    f = replay.MAX_FRAMES + 1
    rec = replay.from_frames(recording().meta, list(range(f)), [0.0] * f, [np.zeros((1, 2))] * f, [np.zeros(1)] * f,
                             [np.zeros(1)] * f, np.zeros((1, 2)))
    assert "frames, more than the 20,000 a replay may hold" in refused(replay.to_bytes(rec))
