"""A browser tab without the browser: viser's websocket protocol spoken from Python.

The viser server counts a websocket as a client once it reports its camera (the page does so
right after connecting); from then on it builds the tab's GUI and scene and streams updates.
:class:`WireClient` does exactly that much: it connects with viser's subprotocol, sends one
camera message and counts (optionally decodes) the frames it receives. Load tests use it to
measure the server alone (no rendering), and trust tests to open and drop many tabs fast.

Frame layout (viser 1.x): 8-byte msgpack size, 8-byte compressed size, zstd-compressed
msgpack ``{"messages": [...]}``, then raw binary buffers.
"""

from __future__ import annotations

import json
import socket
import threading
import time
from typing import Any

import msgspec
import numpy as np
import viser
import zstandard
from viser import _messages
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from app_helpers import shown


def decode_frame(payload: bytes, arrays: bool = False) -> list[dict[str, Any]]:
    """The messages of one viser frame (binary buffers left out, or with ``arrays`` read into the
    numpy arrays they stand for)."""
    size = int.from_bytes(payload[:8], "little")
    csize = int.from_bytes(payload[8:16], "little")
    inner = msgspec.msgpack.decode(zstandard.ZstdDecompressor().decompress(payload[16:16 + csize],
                                                                           max_output_size=size))
    messages = list(inner.get("messages", ()))
    if not arrays:
        return messages
    buffers, at = [], 16 + csize
    for n in inner.get("binaryBufferLengths", ()):
        at += (8 - at % 8) % 8
        buffers.append(payload[at:at + n])
        at += n

    def resolve(v: Any) -> Any:
        if isinstance(v, dict):
            if "__binary_index" in v and "dtype" in v:
                return np.frombuffer(buffers[v["__binary_index"]], dtype=np.dtype(v["dtype"]))
            return {k: resolve(x) for k, x in v.items()}
        if isinstance(v, list):
            return [resolve(x) for x in v]
        return v

    return [resolve(m) for m in messages]


PLOT_CALL = "window.__shoalPage&&window.__shoalPage.plot("


def _without_arrays(v: Any) -> Any:
    """``v`` with every numpy array replaced by its shape (what the GUI log keeps)."""
    if isinstance(v, np.ndarray):
        return {"shape": v.shape}
    if isinstance(v, dict):
        return {k: _without_arrays(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_without_arrays(x) for x in v]
    return v


class PagePlots:
    """The uPlot data a page holds, kept from the messages it receives as the page does: a chart's
    data as created, replaced by a data update, or (the page script's ``plot`` call, see
    ``app/view/page.py``) its rows slid on by an append. ``refused`` counts appends whose base the
    page did not hold (where the page asks for a keyframe)."""

    def __init__(self) -> None:
        self.data: dict[str, list[np.ndarray]] = {}
        self.scales: dict[str, Any] = {}
        self.appends = self.keyframes = self.refused = 0
        self.append_bytes = self.keyframe_bytes = 0

    def take(self, m: dict[str, Any]) -> None:
        kind = m.get("type", "")
        if kind == "GuiUplotMessage":
            self.data[m["uuid"]] = [np.asarray(a, dtype=float) for a in m["props"]["data"]]
        elif kind == "GuiUpdateMessage" and m.get("uuid") in self.data and "data" in m["updates"]:
            self.data[m["uuid"]] = [np.asarray(a, dtype=float) for a in m["updates"]["data"]]
            self.keyframes += 1
            self.keyframe_bytes += sum(len(a) * 8 for a in self.data[m["uuid"]])
        elif kind == "GuiUpdateMessage" and m.get("uuid") in self.data and "scales" in m["updates"]:
            self.scales[m["uuid"]] = m["updates"]["scales"]
        elif kind == "RunJavascriptMessage" and m["source"].startswith(PLOT_CALL):
            args = json.loads("[" + m["source"][len(PLOT_CALL):].rstrip(");") + "]")  # (NaN, Infinity: JSON's)
            _, uuid, n0, x0, x1, drop, cols, scales = args
            held = self.data.get(uuid)
            self.append_bytes += len(m["source"])
            if held is None or len(held[0]) != n0 or held[0][0] != x0 or held[0][-1] != x1 or len(held) != len(cols):
                self.refused += 1
                return
            self.data[uuid] = [np.concatenate([a[drop:], np.asarray(c, dtype=float)]) for a, c in zip(held, cols)]
            self.scales[uuid] = scales
            self.appends += 1


def decode_arrays(payload: bytes) -> list[dict[str, Any]]:
    """The messages of one viser frame with their binary buffers as 1-D numpy arrays."""
    return decode_frame(payload, arrays=True)


def _texts(value: Any) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, dict):
        return [t for v in value.values() for t in _texts(v)]
    if isinstance(value, (list, tuple)):
        return [t for v in value for t in _texts(v)]
    return []


class WireClient:
    """One tab on ``ws://127.0.0.1:port``: ``frames``/``nbytes`` received, ``texts`` seen
    (with ``decode=True``: every string in the GUI messages, e.g. markdown and modal titles;
    with ``plots=True`` also ``plots``, the uPlot data the page would hold).

    ``origin`` sends an ``Origin`` header as a browser page would; ``host`` connects to
    127.0.0.1 all the same but names ``host`` in the ``Host`` header (a DNS name pointed at
    this machine). ``path`` is the page's path (a lecture's ``/lecturer``, ``/p/<id>``) and
    ``headers`` more request headers (a cookie). A refused upgrade raises
    ``websockets.exceptions.InvalidStatus``."""

    def __init__(self, port: int, *, decode: bool = False, width: int = 1280, height: int = 800,
                 origin: str | None = None, host: str | None = None, plots: bool = False, path: str = "",
                 headers: dict[str, str] | None = None) -> None:
        self.decode = decode or plots
        self.track_plots = plots  # keep the uPlot data the page would hold (``plots``)
        self.frames = 0
        self.nbytes = 0
        self.robot_updates = 0
        self.texts: list[str] = []
        self.plots = PagePlots()  # (decode=True) the uPlot data the page would hold
        self.gui: list[dict[str, Any]] = []  # (decode=True) every GUI message received
        self.downloads: list[str] = []  # (decode=True) names of the files the server sent
        self.last: dict[str, dict[str, Any]] = {}  # (decode=True) the last message of each type
        self.points: dict[str, Any] = {}  # (decode=True) node name → the last points it was sent ((N, 3) float32)
        self.closed = threading.Event()
        self._lock = threading.Lock()
        sock = socket.create_connection(("127.0.0.1", port)) if host else None
        self.ws = connect(f"ws://{host or f'127.0.0.1:{port}'}{path}", subprotocols=[f"viser-v{viser.__version__}"],
                          max_size=None, open_timeout=30, origin=origin, sock=sock,  # type: ignore[arg-type]
                          additional_headers=headers)
        self._camera = _messages.ViewerCameraMessage(
            wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 40.0), fov=0.6, near=0.01, far=1000.0,
            image_height=height, image_width=width, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 1.0, 0.0))
        self.report_camera()
        self._reader = threading.Thread(target=self._read, name="wire-client", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        try:
            for payload in self.ws:
                if isinstance(payload, str):
                    payload = payload.encode()
                texts: list[str] = []
                gui: list[dict[str, Any]] = []
                files: list[str] = []
                robots = 0
                last: dict[str, dict[str, Any]] = {}
                points: dict[str, Any] = {}
                if self.decode:
                    for m in decode_frame(payload, arrays=True):
                        updates = m.get("updates") if m.get("type") == "SceneNodeUpdateMessage" else (
                            m.get("props") if str(m.get("type", "")).endswith("PointCloudMessage") else None)
                        if isinstance(updates, dict) and isinstance(updates.get("points"), np.ndarray):
                            points[str(m.get("name", ""))] = updates["points"].reshape(-1, 3)
                        kind = m.get("type", "")
                        if self.track_plots:
                            with self._lock:
                                self.plots.take(m)
                        m = _without_arrays(m)
                        last[kind] = m
                        if kind.startswith(("Gui", "Notification")):
                            texts += _texts(m)
                            gui.append(m)
                        elif kind == "FileTransferStartDownload":
                            files.append(str(m.get("filename")))
                        elif (kind == "SceneNodeUpdateMessage" and str(m.get("name", "")).endswith("/robots")
                              and "points" in (m.get("updates") or {})):
                            robots += 1
                with self._lock:
                    self.frames += 1
                    self.nbytes += len(payload)
                    self.texts += texts
                    self.gui += gui
                    self.downloads += files
                    self.robot_updates += robots
                    self.last.update(last)
                    self.points.update(points)
        except ConnectionClosed:
            pass
        finally:
            self.closed.set()

    def report_camera(self) -> None:
        """Send the camera, as a page does once it has drawn a frame (a new tab plays at its first
        report after the tab is built, else some seconds later: server.FIRST_FRAME_SECONDS)."""
        self.ws.send(msgspec.msgpack.encode(self._camera.as_serializable_dict()))

    def counts(self) -> tuple[int, int, int]:
        """(frames, bytes, robot point-cloud updates) received so far."""
        with self._lock:
            return self.frames, self.nbytes, self.robot_updates

    def saw(self, text: str) -> bool:
        """Did ``text`` arrive (in markdown: as the page shows it, the app's escapes undone)?"""
        with self._lock:
            return any(text in t or text in shown(t) for t in self.texts)

    def uuid_of(self, label: str) -> str | None:
        """The id of the GUI element labelled ``label`` (decode=True), if it arrived."""
        with self._lock:
            return next((m["uuid"] for m in self.gui if (m.get("props") or {}).get("label") == label), None)

    def wait_uuid(self, label: str, timeout: float = 45.0) -> str:
        """The id of the GUI element labelled ``label``, once it has arrived: a panel's elements
        reach the page one message after another, so one that the test waited for does not mean
        that a later one is there yet."""
        end = time.monotonic() + timeout
        while (uuid := self.uuid_of(label)) is None:
            assert time.monotonic() < end and not self.closed.is_set(), f"no control labelled {label!r} arrived"
            time.sleep(0.02)
        return uuid

    def notifications(self) -> list[tuple[str, str, Any]]:
        """(title, body, colour) of every notification shown so far (decode=True)."""
        with self._lock:
            return [(m["props"]["title"], m["props"]["body"], m["props"]["color"]) for m in self.gui
                    if m.get("type") == "NotificationShowMessage"]

    def markdown(self) -> list[str]:
        """Every content a markdown element of the page was given, in order (decode=True)."""
        with self._lock:
            ids = {m["uuid"] for m in self.gui if m.get("type") == "GuiMarkdownMessage"}
            out = []
            for m in self.gui:
                fields = m.get("props") if m.get("type") == "GuiMarkdownMessage" else (
                    m.get("updates") if m.get("type") == "GuiUpdateMessage" and m.get("uuid") in ids else None)
                out += [str(v) for k, v in (fields or {}).items() if k in ("_markdown", "content", "markdown")]
            return out

    def value_of(self, uuid: str) -> Any:
        """The value the server last gave the GUI element ``uuid`` (decode=True)."""
        with self._lock:
            for m in reversed(self.gui):
                if m.get("uuid") == uuid and "value" in (m.get("updates") or {}):
                    return m["updates"]["value"]
                if m.get("uuid") == uuid and "value" in m:
                    return m["value"]
        raise KeyError(uuid)

    def take_plot_appends(self) -> None:
        """Say what the page script says once it reaches viser's store: plots may come as appends."""
        self.set_value("plot sync", "appends 1")

    def set_value(self, label: str, value: Any) -> None:
        """Send ``value`` for the control labelled ``label``, as the page does when it changes."""
        self.send(_messages.GuiUpdateMessage(self.wait_uuid(label), {"value": value}))

    def upload(self, label: str, name: str, data: bytes, *, parts: int = 1, declared: int | None = None,
               send: int | None = None) -> str:
        """Upload ``data`` as file ``name`` through the upload button ``label`` in ``parts`` parts,
        declaring ``declared`` bytes (default: its size) and sending only the first ``send``
        parts (default: all). Returns the transfer's id."""
        import uuid as _uuid

        button = self.wait_uuid(label)
        tid = str(_uuid.uuid4())
        self.send(_messages.FileTransferStartUpload(
            source_component_uuid=button, transfer_uuid=tid, filename=name, mime_type="application/octet-stream",
            part_count=parts, size_bytes=len(data) if declared is None else declared))
        step = -(-len(data) // parts) if data else 0
        for i in range(parts if send is None else send):
            self.send(_messages.FileTransferPart(source_component_uuid=button, transfer_uuid=tid, part_index=i,
                                                 content=data[i * step:(i + 1) * step]))
        return tid

    def send(self, message: Any) -> None:
        """Send one viser message as a page would."""
        self.ws.send(msgspec.msgpack.encode(message.as_serializable_dict()))

    def close(self) -> None:
        self.ws.close()
        self._reader.join(timeout=10)
