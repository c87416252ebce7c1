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
    assert "numbers once unpacked" in msg
