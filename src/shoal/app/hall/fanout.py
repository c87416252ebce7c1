"""The broadcast of a lecture, built once and sent to every watcher.

Viser sends a server's server-wide scene and GUI (its *broadcast buffer*) to every connection:
each connection's producer (``viser.infra._infra._message_producer``) takes its next window of
messages and serialises it (msgpack, then zstd) for that connection alone, so 200 watchers of
one frame cost 200 serialisations of it. For a server given to :func:`share`, this module's
producer takes their place:

- a **watcher** (every connection whose request path is not private) gets the broadcast as
  viser sends it, but a window of messages that another connection already took is not
  serialised again: the bytes made for the first are sent to the next (:class:`Frames`, keyed by
  the identity of the messages in the window; watchers that are caught up take the same
  windows, since a frame is queued in one atomic block);
- a **private** connection (the lecturer's tab, a taken-over session, a plain tab) gets none of
  the broadcast: only viser's end-of-replay marker, which the page waits for. Its own
  messages (its panel and arena, on ``client.gui`` / ``client.scene``) come as they always do.

Every other buffer (each connection's own, and every server not given to :func:`share`) goes
through viser's producer unchanged. This reads viser 1.x internals (the producer's name and
arguments, the hybrid frame layout); ``pyproject.toml`` bounds viser. If this viser keeps them
elsewhere :func:`install` says so and changes nothing: watchers then cost a serialisation each
and a private tab would see the broadcast too, so :func:`share` refuses to share a server then.
"""

from __future__ import annotations

import sys
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import msgspec
import zstandard

MAX_FRAMES = 32  # windows kept serialised per server (watchers a few windows behind still share them)
Private = Callable[[str], bool]  # request path → is the connection private?


def encode(window: Sequence[Any]) -> bytes:
    """One window of viser messages as viser's producer frames it: 8-byte msgpack size, 8-byte
    compressed size, the zstd-compressed msgpack, then the binary buffers, 8-byte aligned."""
    from viser.infra import _infra

    buffers: list[memoryview] = []
    messages = tuple(m.as_serializable_dict(buffers) for m in window)
    inner = msgspec.msgpack.encode({"messages": messages, "timestampSec": time.perf_counter(),
                                    "binaryBufferLengths": tuple(b.nbytes for b in buffers)})
    compressed = _compressor().compress(inner)
    parts: list[bytes | memoryview] = [len(inner).to_bytes(8, "little"), len(compressed).to_bytes(8, "little"),
                                       compressed]
    _infra._append_aligned_buffers(parts, buffers, 16 + len(compressed))
    return b"".join(parts)


_local = threading.local()


def _compressor() -> zstandard.ZstdCompressor:
    """A zstd compressor at viser's level, one per thread (each viser server has its event loop thread)."""
    z = getattr(_local, "zstd", None)
    if z is None:
        z = _local.zstd = zstandard.ZstdCompressor(level=1)
    return z


@dataclass
class Frames:
    """The windows of one shared server serialised lately, and counts of what was sent."""

    private: Private
    kept: OrderedDict[tuple[int, ...], tuple[tuple[Any, ...], bytes]] = field(default_factory=OrderedDict)
    encoded: int = 0  # windows serialised
    sent: int = 0  # frames sent to watchers
    bytes_sent: int = 0

    def bytes_for(self, window: Sequence[Any]) -> bytes:
        """The frame of ``window``, serialised once for every watcher that takes the same window."""
        key = tuple(map(id, window))
        hit = self.kept.get(key)
        if hit is not None and all(a is b for a, b in zip(hit[0], window)):  # (the entry holds them: ids are theirs)
            data = hit[1]
        else:
            data = encode(window)
            self.encoded += 1
            self.kept[key] = (tuple(window), data)
            while len(self.kept) > MAX_FRAMES:
                self.kept.popitem(last=False)
        self.sent += 1
        self.bytes_sent += len(data)
        return data


FRAMES = "_shoal_frames"  # the attribute of a shared broadcast buffer that holds its Frames
_installed: dict[str, Any] = {}
_lock = threading.Lock()


def request_path(websocket: Any) -> str:
    """The path of a connection's websocket request (its page's path), "" if unknown."""
    request = getattr(websocket, "request", None)
    return str(getattr(request, "path", "") or "").split("?", 1)[0]


async def shared_producer(websocket: Any, buffer: Any, client_id: int, backlog_done_message: Any = None) -> None:
    """Viser's producer for one connection and one buffer, with the sharing of the module doc."""
    frames = getattr(buffer, FRAMES, None)
    if frames is None:
        await _installed["viser"](websocket, buffer, client_id, backlog_done_message)
        return
    private = frames.private(request_path(websocket))
    windows = buffer.window_generator(client_id, backlog_done_message=backlog_done_message)
    try:
        while not buffer.done:
            try:
                window = await windows.__anext__()
            except StopAsyncIteration:
                break
            if private:  # none of the broadcast; the replay marker alone (the page waits for it)
                marker = [m for m in window if m is backlog_done_message]
                if marker:
                    await websocket.send(encode(marker))
                continue
            await websocket.send(frames.bytes_for(window))
    finally:
        await windows.aclose()  # (as viser's: the generator's cursor is dropped now, not at a later GC)


def install() -> bool:
    """Put :func:`shared_producer` in viser's place (process-wide, once). Returns whether it could."""
    with _lock:
        if "viser" in _installed:
            return True
        try:
            from viser.infra import _infra
        except ImportError:
            return False
        current = getattr(_infra, "_message_producer", None)
        if current is None or not callable(current) or getattr(_infra, "_append_aligned_buffers", None) is None:
            print("shoal: this viser sends messages in a way the lecture's broadcast cannot share", file=sys.stderr)
            return False
        _installed["viser"] = current
        _infra._message_producer = shared_producer
        return True


def share(server: Any, private: Private) -> Frames:
    """Send the broadcast of ``server`` (a started ``viser.ViserServer``) as the module doc says:
    built once for all watchers, and to no connection whose request path ``private`` accepts.
    Returns its :class:`Frames` (counts for tests and benchmarks). Raises RuntimeError where
    this viser cannot be shared (a private tab would see the broadcast)."""
    if not install():
        raise RuntimeError("the lecture's broadcast cannot be kept from private tabs with this viser")
    buffer = server._websock_server._broadcast_buffer
    frames = getattr(buffer, FRAMES, None)
    if frames is None:
        frames = Frames(private)
        setattr(buffer, FRAMES, frames)
    return frames


def frames_of(server: Any) -> Frames | None:
    """The :class:`Frames` of a shared server (None: not shared)."""
    return getattr(server._websock_server._broadcast_buffer, FRAMES, None)
