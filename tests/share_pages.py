"""Reading an exported page back in tests: its JSON block and the scene viser recorded in it."""

from __future__ import annotations

import base64
import json
import re
from dataclasses import dataclass
from typing import Any

import msgspec
import numpy as np
import zstandard


@dataclass(frozen=True)
class Recorded:
    """The recording inside a page: (time, message) pairs, arrays decoded (flat)."""

    duration: float
    messages: list[tuple[float, dict[str, Any]]]

    def updates(self, name: str, prop: str) -> list[tuple[float, np.ndarray]]:
        """(time, value) of every creation or update of ``prop`` of node ``name``, in order."""
        out = []
        for t, m in self.messages:
            if m.get("name") != name:
                continue
            props = m.get("props") if "props" in m else m.get("updates")
            if isinstance(props, dict) and prop in props:
                out.append((t, props[prop]))
        return out

    def frames(self, name: str, prop: str = "points") -> list[np.ndarray]:
        """The value of ``prop`` of ``name`` at the end of each distinct recorded time."""
        last: dict[float, np.ndarray] = {}
        for t, value in self.updates(name, prop):
            last[t] = value
        return [last[t] for t in sorted(last)]


def data_block(html: str) -> dict[str, Any]:
    m = re.search(r'<script type="application/json" id="shoal-run-data">(.*?)</script>', html, re.S)
    assert m, "no #shoal-run-data block"
    return json.loads(m.group(1))


def _resolve(obj: Any, buffers: list[np.ndarray]) -> Any:
    if isinstance(obj, dict):
        if "__binary_index" in obj and "dtype" in obj:
            return buffers[obj["__binary_index"]].view(np.dtype(obj["dtype"])).copy()
        return {k: _resolve(v, buffers) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_resolve(v, buffers) for v in obj]
    return obj


def recorded(html: str) -> Recorded:
    """Decode ``window.__VISER_EMBED_DATA__`` as viser's player does (zstd, msgpack, aligned buffers)."""
    m = re.search(r'window\.__VISER_EMBED_DATA__="([A-Za-z0-9+/=]+)"', html)
    assert m, "no embedded scene"
    raw = base64.b64decode(m.group(1))
    size = int.from_bytes(raw[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=size)
    n = int.from_bytes(inner[:8], "little")
    data = msgspec.msgpack.decode(inner[8:8 + n])
    offset, buffers = 8 + n, []
    for length in data["binaryBufferLengths"]:
        offset += (8 - offset % 8) % 8
        buffers.append(np.frombuffer(inner, np.uint8, length, offset))
        offset += length
    messages = [(float(t), _resolve(msg, buffers)) for t, msg in data["messages"]]
    return Recorded(duration=float(data["durationSeconds"]), messages=messages)
