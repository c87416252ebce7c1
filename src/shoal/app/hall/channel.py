"""The desk across processes: the workers of ``shoal hall`` claim private sessions from the lecture.

The lecture's process serves its :class:`~.desk.Desk` on a Unix socket in the hall's own folder
(made by ``shoal hall``, readable by its user alone): :class:`DeskService`. Each worker keeps one
connection (:class:`RemoteDesk`): it says the hall's channel key and its name first, then asks
for a fresh plain session's id, claims an id for one of its tabs (getting the take-over's state)
and lets one go. When a worker's connection ends (the worker stopped or died) every id its tabs
held is let go at once (``Desk.release_all``), so those tabs may claim them again from another
worker, and are told they start again.

Each message is a 4-byte length and a msgpack map of plain values (text, numbers, bytes): no
pickle. A message longer than :data:`MAX_MESSAGE` or a wrong key ends the connection.
"""

from __future__ import annotations

import contextlib
import hmac
import os
import socket
import sys
import threading
from collections import Counter
from typing import Any, Hashable

import msgspec

from .desk import MAX_STATE_BYTES, PLAIN, Claim, Desk, Refused

MAX_MESSAGE = MAX_STATE_BYTES + 2**20
TIMEOUT = 30.0  # s a worker waits for the lecture's answer


def send(sock: socket.socket, message: dict[str, Any]) -> None:
    data = msgspec.msgpack.encode(message)
    sock.sendall(len(data).to_bytes(4, "big") + data)


def _exactly(sock: socket.socket, n: int) -> bytes:
    parts, got = [], 0
    while got < n:
        part = sock.recv(min(n - got, 1 << 20))
        if not part:
            raise ConnectionError("the other end closed the channel")
        parts.append(part)
        got += len(part)
    return b"".join(parts)


def receive(sock: socket.socket) -> dict[str, Any]:
    n = int.from_bytes(_exactly(sock, 4), "big")
    if n > MAX_MESSAGE:
        raise ConnectionError(f"a message of {n} bytes on the channel (at most {MAX_MESSAGE})")
    message = msgspec.msgpack.decode(_exactly(sock, n))
    if not isinstance(message, dict):
        raise ConnectionError("not a message")
    return message


class DeskService:
    """``desk`` served on the Unix socket ``path`` to whoever says ``key`` (the hall's workers)."""

    def __init__(self, desk: Desk, path: str, key: str) -> None:
        self.desk, self.path, self.key = desk, path, key
        self.live: Counter[str] = Counter()  # worker name → its open connections
        self._lock = threading.Lock()
        self._server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        old = os.umask(0o177)
        try:
            self._server.bind(path)  # (a socket file only this user may open)
        finally:
            os.umask(old)
        self._server.listen(64)
        self._stopping = threading.Event()
        desk.alive = self.is_live
        threading.Thread(target=self._accept, name="shoal-desk", daemon=True).start()

    def is_live(self, owner: Hashable) -> bool:
        if not isinstance(owner, str) or not owner.startswith("worker-"):
            return True  # (this process's own tabs)
        with self._lock:
            return self.live[owner] > 0

    def _accept(self) -> None:
        while not self._stopping.is_set():
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            threading.Thread(target=self._serve, args=(conn,), name="shoal-desk-conn", daemon=True).start()

    def _serve(self, conn: socket.socket) -> None:
        owner = None
        try:
            hello = receive(conn)
            key, name = hello.get("key"), hello.get("owner")
            if not (isinstance(key, str) and hmac.compare_digest(key.encode(), self.key.encode())
                    and isinstance(name, str) and name.startswith("worker-") and len(name) <= 40):
                return
            owner = name
            with self._lock:
                self.live[owner] += 1
            send(conn, {"ok": True})
            while True:
                send(conn, self._answer(owner, receive(conn)))
        except (OSError, ConnectionError, msgspec.DecodeError):
            pass
        finally:
            conn.close()
            if owner is not None:
                with self._lock:
                    self.live[owner] -= 1
                    gone = self.live[owner] <= 0
                if gone:
                    freed = self.desk.release_all(owner)
                    if freed:
                        print(f"shoal: {owner} stopped; its {freed} private sessions may open elsewhere",
                              file=sys.stderr, flush=True)

    def _answer(self, owner: str, m: dict[str, Any]) -> dict[str, Any]:
        op, pid, tab = m.get("op"), m.get("pid"), m.get("tab")
        try:
            if op == "plain":
                return {"pid": self.desk.issue_plain()}
            if op == "holders":  # (who holds what: for tests and a look from outside)
                return {"holders": {p: list(h) if isinstance(h, tuple) else h for p, h in self.desk.holders().items()}}
            if not isinstance(pid, str) or not isinstance(tab, int) or isinstance(tab, bool):
                return {"refused": "a request without an id and a tab"}
            if op == "claim":
                c = self.desk.claim(pid, (owner, tab))
                return {"kind": c.kind, "state": c.state, "step": c.step, "again": c.again}
            if op == "release":
                self.desk.release(pid, (owner, tab))
                return {}
        except Refused as err:
            return {"refused": str(err)}
        return {"refused": f"no such request {str(op)[:20]!r}"}

    def stop(self) -> None:
        """Stop serving and remove the socket file (it is this service's)."""
        self._stopping.set()
        with contextlib.suppress(OSError):
            self._server.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.path)


class RemoteDesk:
    """The lecture's desk as a worker named ``owner`` sees it, through the socket ``path``."""

    def __init__(self, path: str, key: str, owner: str) -> None:
        self.path, self.key, self.owner = path, key, owner
        self._sock: socket.socket | None = None
        self._lock = threading.Lock()

    def _connect(self) -> socket.socket:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.settimeout(TIMEOUT)
        sock.connect(self.path)
        send(sock, {"key": self.key, "owner": self.owner})
        if receive(sock).get("ok") is not True:
            raise ConnectionError("the lecture refused this worker")
        return sock

    def _call(self, message: dict[str, Any]) -> dict[str, Any]:
        with self._lock:
            for attempt in (1, 2):
                try:
                    if self._sock is None:
                        self._sock = self._connect()
                    send(self._sock, message)
                    answer = receive(self._sock)
                    break
                except (OSError, ConnectionError):
                    if self._sock is not None:
                        self._sock.close()
                    self._sock = None
                    if attempt == 2:
                        raise Refused("the lecture cannot be reached just now; try again in a moment") from None
        if "refused" in answer:
            raise Refused(str(answer["refused"]))
        return answer

    def connect(self) -> None:
        """Open the channel now (the worker is known to the lecture before it serves a tab)."""
        with self._lock:
            if self._sock is None:
                self._sock = self._connect()

    def issue(self, kind: str, state: bytes = b"", step: int = 0) -> str:
        if kind != PLAIN:
            raise Refused("a worker hands out no take-overs")
        return self.issue_plain()

    def issue_plain(self) -> str:
        return str(self._call({"op": "plain"})["pid"])

    def claim(self, pid: str, holder: Hashable) -> Claim:
        tab = holder[1] if isinstance(holder, tuple) and len(holder) == 2 else holder
        a = self._call({"op": "claim", "pid": pid, "tab": tab})
        state = a.get("state", b"")
        return Claim(pid, str(a.get("kind")), bytes(state) if isinstance(state, (bytes, bytearray)) else b"",
                     int(a.get("step", 0)), bool(a.get("again", False)))

    def release(self, pid: str, holder: Hashable) -> None:
        tab = holder[1] if isinstance(holder, tuple) and len(holder) == 2 else holder
        with contextlib.suppress(Refused):
            self._call({"op": "release", "pid": pid, "tab": tab})

    def holders(self) -> dict[str, Any]:
        """Private id → ``[process, tab]`` holding it now."""
        return dict(self._call({"op": "holders"})["holders"])

    def close(self) -> None:
        with self._lock:
            if self._sock is not None:
                self._sock.close()
                self._sock = None
