"""The private sessions a lecture has handed out, by id: a take-over (with the state it starts
from) or a plain session, each held by at most one tab at a time.

A private page is ``/p/<id>`` (:mod:`.routes`); whichever process serves it *claims* the id
here first, and *releases* it when its tab closes. An id is one tab's: a claim while another
tab holds it is refused. A claim after the holder let go (the tab reconnected, or the process
that ran it stopped: :meth:`Desk.release_all`) is granted again, with ``again`` set, so the tab
is told it starts afresh from where it took over. Ids nobody holds are forgotten after
:data:`IDLE_SECONDS`, and at most :data:`MAX_RECORDS` are kept (the oldest idle ones go first).

The desk lives in the lecture's process; the workers of ``shoal hall`` reach it through
:mod:`.channel`. A record's state is bytes made by :mod:`.takeover`, never anything a client sent.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Callable, Hashable

from . import routes

TAKEOVER, PLAIN = "takeover", "plain"
IDLE_SECONDS = 3600.0
MAX_RECORDS = 4000
MAX_STATE_BYTES = 64 * 2**20  # of one take-over's state


@dataclass
class Record:
    kind: str  # TAKEOVER or PLAIN
    state: bytes  # the take-over's state (:mod:`.takeover`); b"" for a plain session
    step: int  # the lecture's step it was taken at
    holder: Hashable | None = None  # who holds it now
    claims: int = 0
    idle_since: float = 0.0


@dataclass(frozen=True)
class Claim:
    """What a process gets for an id it may open: the kind, the state, the step, and whether a tab
    had it before (``again``)."""

    pid: str
    kind: str
    state: bytes
    step: int
    again: bool


class Refused(Exception):
    """An id that cannot be opened; the message says why, for the tab."""


class Desk:
    def __init__(self) -> None:
        self._records: OrderedDict[str, Record] = OrderedDict()
        self._lock = threading.Lock()
        self._clock = time.monotonic
        self.alive: Callable[[Hashable], bool] = lambda owner: True  # is the process ``owner`` still there?

    def __len__(self) -> int:
        return len(self._records)

    def issue(self, kind: str, state: bytes = b"", step: int = 0) -> str:
        """A new id for a take-over (its ``state``) or a plain session."""
        if kind not in (TAKEOVER, PLAIN):
            raise ValueError(f"no private session of kind {kind!r}")
        if len(state) > MAX_STATE_BYTES:
            raise Refused(f"this run's state is {len(state) / 2**20:.0f} MiB, more than a take-over carries")
        pid = routes.new_id()
        with self._lock:
            self._forget_idle()
            self._records[pid] = Record(kind, bytes(state), int(step), idle_since=self._clock())
        return pid

    def issue_plain(self) -> str:
        return self.issue(PLAIN)

    def claim(self, pid: str, holder: Hashable) -> Claim:
        """Open ``pid`` for ``holder``; :class:`Refused` (saying why) when it cannot be."""
        with self._lock:
            record = self._records.get(pid)
            if record is None:
                raise Refused("this private session is not known here (the lecture may have started again, "
                              "or the address is an old one): take over again from the class page")
            if record.holder is not None and record.holder != holder and self._live(record.holder):
                raise Refused("this private session is open in another tab")
            record.holder = holder
            record.claims += 1
            self._records.move_to_end(pid)
            return Claim(pid, record.kind, record.state, record.step, again=record.claims > 1)

    def drop(self, pid: str) -> bool:
        """Forget ``pid`` unless a tab holds it (a watcher's earlier take-over it never opened)."""
        with self._lock:
            record = self._records.get(pid)
            if record is None or record.holder is not None:
                return False
            del self._records[pid]
            return True

    def release(self, pid: str, holder: Hashable) -> None:
        """``holder``'s tab of ``pid`` closed (the id may be claimed again)."""
        with self._lock:
            record = self._records.get(pid)
            if record is not None and record.holder == holder:
                record.holder, record.idle_since = None, self._clock()

    def release_all(self, owner: Hashable) -> int:
        """Every id held by a tab of process ``owner`` (a holder ``(owner, tab)``): the process
        stopped. Returns how many were let go."""
        with self._lock:
            held = [r for r in self._records.values()
                    if isinstance(r.holder, tuple) and r.holder[:1] == (owner,)]
            for r in held:
                r.holder, r.idle_since = None, self._clock()
            return len(held)

    def _live(self, holder: Hashable) -> bool:
        """Is the process of ``holder`` (``(owner, tab)``) still there (a stopped one's ids are free)?"""
        return not isinstance(holder, tuple) or not holder or self.alive(holder[0])

    def holders(self) -> dict[str, Hashable]:
        with self._lock:
            return {pid: r.holder for pid, r in self._records.items() if r.holder is not None}

    def _forget_idle(self) -> None:
        now = self._clock()
        for pid in [pid for pid, r in self._records.items()
                    if r.holder is None and now - r.idle_since > IDLE_SECONDS]:
            del self._records[pid]
        while len(self._records) >= MAX_RECORDS:
            idle = next((pid for pid, r in self._records.items() if r.holder is None), None)
            if idle is None:
                raise Refused(f"{MAX_RECORDS} private sessions are open; close one first")
            del self._records[idle]
