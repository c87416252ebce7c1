"""The broadcast serialised once for every watcher that takes the same window of messages
(``shoal.app.hall.fanout.Frames``), window by window; the end-to-end count is in
tests/test_hall_lecture.py, the measure in benchmarks/bench_watchers.py."""

from __future__ import annotations

import msgspec
import zstandard
from viser import _messages

from shoal.app.hall.fanout import MAX_FRAMES, Frames, encode


def window(n: int, text: str = "m") -> list:
    return [_messages.RunJavascriptMessage(source=f"{text}{i}") for i in range(n)]


def decoded(frame: bytes) -> list[str]:
    """The sources of a frame's messages, read back as the page's client does (sizes, zstd, msgpack)."""
    size, packed = int.from_bytes(frame[:8], "little"), int.from_bytes(frame[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(frame[16:16 + packed], max_output_size=size)
    return [m["source"] for m in msgspec.msgpack.decode(inner)["messages"]]


def test_a_window_two_watchers_take_is_serialised_once_and_sent_twice():
    frames = Frames(private=lambda path: False)
    w = window(3)
    first, second = frames.bytes_for(w), frames.bytes_for(list(w))  # the same messages, each watcher's list
    assert first is second and (frames.encoded, frames.sent) == (1, 2)
    assert decoded(first) == ["m0", "m1", "m2"]
    assert frames.bytes_sent == 2 * len(first)


def test_a_lagging_watchers_merged_window_is_its_own_frame():
    frames = Frames(private=lambda path: False)
    a, b = window(2, "a"), window(2, "b")
    frames.bytes_for(a), frames.bytes_for(b)  # a watcher that keeps up
    merged = frames.bytes_for(a + b)  # one that lagged takes both as one window
    assert (frames.encoded, frames.sent) == (3, 3) and decoded(merged) == ["a0", "a1", "b0", "b1"]


def test_equal_ids_of_other_messages_are_not_taken_for_the_same_window():
    frames = Frames(private=lambda path: False)
    frames.bytes_for(window(1, "x"))
    for _ in range(MAX_FRAMES + 5):  # (ids of freed messages come back; the kept entry holds its own)
        frames.bytes_for(window(1, "y"))
    assert len(frames.kept) <= MAX_FRAMES
    assert decoded(frames.bytes_for(window(1, "z"))) == ["z0"]


def test_encode_is_what_a_window_holds():
    assert decoded(encode(window(4, "q"))) == ["q0", "q1", "q2", "q3"]
