"""One browser tab: its session, its panels and its arena, advanced by the server's ticking thread.

``tick(now)`` runs a few steps when playing (``view.steps_per_second``), redraws the arena
at most ``SCENE_HZ`` times a second and the plots and readouts at most ``PLOT_HZ`` times,
so that plot traffic never holds up the scene.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections import deque
from typing import Any, Callable, ContextManager

from .panels import Panels
from .scene import ArenaView
from .session import Session


class TabApp:
    SCENE_HZ = 30.0
    PLOT_HZ = 4.0
    MAX_STEPS_PER_TICK = 25

    def __init__(
        self,
        session: Session,
        gui: Any,
        scene: Any,
        *,
        notify: Callable[[str, str, str], None] | None = None,
        send_file: Callable[[str, bytes], None] | None = None,
        atomic: Callable[[], ContextManager[None]] | None = None,
    ) -> None:
        self.session = session
        self.messages: deque[tuple[str, str, str]] = deque(maxlen=50)  # (title, body, colour), newest last
        self.downloads: deque[tuple[str, bytes]] = deque(maxlen=5)
        self._notify_client = notify
        self._send_client = send_file
        self._atomic = atomic or contextlib.nullcontext
        self.panels = Panels(gui, session, self.notify, self.send_file)
        self.arena = ArenaView(scene)
        self._acc = 0.0
        self._was_playing = False
        self._last: float | None = None
        self._next_scene = 0.0
        self._next_plot = 0.0
        self._plot_key: tuple | None = None
        self._ticking = threading.Lock()
        self.auto_tick = True  # False: only explicit tick() calls advance it (tests)

    def notify(self, title: str, body: str, color: str = "blue") -> None:
        self.messages.append((title, body, color))
        if self._notify_client is not None:
            self._notify_client(title, body, color)

    def send_file(self, name: str, content: bytes) -> None:
        self.downloads.append((name, content))
        if self._send_client is not None:
            self._send_client(name, content)

    def tick(self, now: float | None = None) -> None:
        """Advance playback and redraw what is due (a call while another runs is skipped)."""
        if not self._ticking.acquire(blocking=False):
            return
        try:
            self._tick(time.monotonic() if now is None else now)
        finally:
            self._ticking.release()

    def _tick(self, now: float) -> None:
        s = self.session
        elapsed = 0.0 if self._last is None else max(0.0, now - self._last)
        self._last = now
        if s.playing:
            if self._was_playing:  # time before Play was pressed does not count
                self._acc += elapsed * s.scenario.view.steps_per_second
            n = int(self._acc)
            self._acc -= n
            if n:
                s.step(min(n, self.MAX_STEPS_PER_TICK))
            self._acc = min(self._acc, 1.0)
        else:
            self._acc = 0.0
        self._was_playing = s.playing
        if s.scene_revision != self.arena.built_revision:
            with self._atomic():
                self.arena.rebuild(s.scenario, s.scene_revision)
        if now >= self._next_scene and s.revision != self.arena.drawn_revision:
            snap = s.snapshot()
            with self._atomic():
                self.arena.draw(snap)
            self._next_scene = now + 1.0 / self.SCENE_HZ
        if now >= self._next_plot:
            key = (s.revision, s.selected_robot, s.selected_dim, s.playing)
            if key != self._plot_key:
                self.panels.refresh_status()
                self.panels.refresh_readout()
                self.panels.refresh_plots()
                self._plot_key = key
            self._next_plot = now + 1.0 / self.PLOT_HZ
