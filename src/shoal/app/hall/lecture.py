"""``shoal serve --lecture``: one run shown to a whole class, driven from the lecturer's tab.

A :class:`LectureServer` is a :class:`~shoal.app.server.ShoalServer` whose connections are told
apart by the path of their page (:mod:`.routes`):

- the class page ``/``: a **watcher**. It holds no session; it sees the broadcast
  (:mod:`.broadcast`: the lecture drawn once on the server's own scene and GUI, sent to every
  watcher as the same bytes by :mod:`.fanout`) and has its own *Take over* button
  (:mod:`.watcher`);
- ``/lecturer`` with the lecturer's key: the lecturer's tab, the full panel on the **lecture
  session** (:class:`Lecture`), which outlives it: a reload or a second lecturer's tab finds the
  run where it was (a second tab takes the lecture from the first);
- ``/p/<id>``: a private session the lecture handed out (:mod:`.desk`): a take-over, or a plain
  session (``/solo``). Private tabs see none of the broadcast and have *Back to the lecture*.

The run advances while the lecturer's tab is connected (its tab steps it, as every tab steps
its own); without it the class is told the run waits.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
import traceback
from typing import Any

import viser

from shoal.presets.models import Scenario

from ..experiment import ExperimentService
from ..kinds.registry import app_presets, session_for
from ..lessons.panel import LessonProgress
from ..panel.view_row import Display
from ..preset_menu import PresetMenu
from ..server import DEFAULT_MAX_SESSIONS
from ..session.session import Session
from ..tab import TabApp
from ..view.camera import home_camera
from ..view.page import install_page, run_script
from . import fanout, routes, takeover
from .broadcast import ORDER_OWN, Broadcast
from .class_panel import ClassPanel, lesson_question
from .desk import TAKEOVER, Refused
from .desk import Desk as LocalDesk
from .private import Desk, PrivateServer, configure_client
from .rounds import Question, Round, Rounds
from .rounds import Refused as RoundRefused
from .watcher import Watcher, notify

DEFAULT_MAX_WATCHERS = 500
TAKE_OVER_SECONDS = 2.0  # between two take-overs of one class tab
HERE = "lecture"  # this process, as a holder of private sessions on the desk
LECTURER_ONLY = ("**This is the lecturer's page.** It opens with the key that `shoal serve --lecture` printed "
                 "(the whole address, `…/lecturer#key=…`). The class watches at the server's own address.")
NOWHERE = "**No such page.** The class watches at this server's address (`/`)."
DISMISSED = "**The lecture is driven from another tab now.** Reload this page to drive it from here again."
FULL = "**This lecture has {n} watchers, its maximum.** Reload this page later."


class Lecture:
    """The lecture's run and what outlives the lecturer's tab: the session (``session``: the
    lecturer's tab's, which a lesson or a preset may swap for one of another kind), where the
    lessons are, the preset menu (uploads included) and the display."""

    def __init__(self, scenario: Scenario, projector: bool = False) -> None:
        self._session = session_for(scenario)  # paused at step 0: the lecturer presses Play
        self.lessons = LessonProgress()
        self.menu = PresetMenu(tuple(app_presets()))
        self.display = Display(projector=projector)  # (``serve --lecture --projector``: the lecturer's tab in it)
        self.lecturer: TabApp | None = None
        self.lecturer_client: int | None = None

    @property
    def session(self) -> Session:
        tab = self.lecturer
        return tab.session if tab is not None else self._session

    def keep(self) -> dict[str, Any]:
        """What a lecturer's tab takes over from the last one."""
        return dict(lesson_progress=self.lessons, menu=self.menu, display=self.display)

    def drop(self, tab: TabApp) -> None:
        """The lecturer's ``tab`` went: the run stays as it left it."""
        if self.lecturer is tab:
            self._session = tab.session
            self.lecturer, self.lecturer_client = None, None


class LectureServer(PrivateServer):
    """A lecture (see the module doc): ``key`` is the lecturer's (made here if not given),
    ``desk`` hands out and takes back the private sessions (this process's own by default)."""

    def __init__(self, scenario: Scenario, host: str = "127.0.0.1", port: int = 8080, *, key: str | None = None,
                 max_sessions: int = DEFAULT_MAX_SESSIONS, max_watchers: int = DEFAULT_MAX_WATCHERS,
                 allow_origins: tuple[str, ...] = (), experiments: ExperimentService | None = None,
                 proxy_key: str | None = None, desk: Desk | None = None, projector: bool = False) -> None:
        self.key = key or routes.new_key()
        self.lecture = Lecture(scenario, projector=projector)
        self.rounds = Rounds()
        self.class_panel: ClassPanel | None = None  # on the lecturer's tab
        self.max_watchers = max_watchers
        self.watchers: dict[int, Watcher] = {}
        self._said: set[str] = set()
        super().__init__(scenario, host, port, desk=desk if desk is not None else LocalDesk(), owner=HERE,
                         max_sessions=max_sessions, allow_origins=allow_origins, experiments=experiments,
                         proxy_key=proxy_key, projector=projector)

    # ------------------------------------------------------------------ set-up
    def _configure(self) -> None:
        super()._configure()
        self.frames = fanout.share(self.viser, routes.is_private)
        self.broadcast = Broadcast(self.viser, self.lecture, self.rounds)

    @property
    def lecturer_url(self) -> str:
        return f"{self.url.rstrip('/')}{routes.LECTURER_PATH}#key={self.key}"

    # ------------------------------------------------------------------ connections
    def _connect(self, client: viser.ClientHandle) -> None:
        if self._stopping.is_set():
            return
        path, headers = routes.request_of(self.viser, client.client_id)
        which = routes.role(path)
        if which == routes.WATCH:
            self._open_watcher(client)
        elif which == routes.LECTURER:
            self._open_lecturer(client, headers)
        elif which == routes.PRIVATE:
            self._open_private(client, path)
        else:
            client.gui.add_markdown(NOWHERE)

    def _open_watcher(self, client: viser.ClientHandle) -> None:
        cid = client.client_id
        with self._lock:
            full = len(self.watchers) >= self.max_watchers
        if full:
            client.gui.add_markdown(FULL.format(n=f"{self.max_watchers:d}"), order=ORDER_OWN)
            return
        home_camera(client.camera)
        fitted = threading.Event()

        @client.camera.on_update
        def _(camera: viser.CameraHandle) -> None:
            if not fitted.is_set():
                fitted.set()
                home_camera(camera)

        install_page(client.gui)  # the top view held, as for every tab
        watcher = Watcher(client, self.take_over, self.rounds)
        with self._lock:
            self.watchers[cid] = watcher
        watcher.show(self.rounds.current)
        if self._gone(cid):
            self._disconnect(client)

    def _open_lecturer(self, client: viser.ClientHandle, headers: Any) -> None:
        if not routes.holds_key(headers, self.key):
            configure_client(client)
            client.gui.add_markdown(LECTURER_ONLY)
            return
        cid = client.client_id
        configure_client(client)
        with self._lock:
            before = self.lecture.lecturer_client
        if before is not None:
            self._dismiss(before)
        panel = ClassPanel(client.gui, self, notify=lambda title, body, colour: notify(client, title, body, colour),
                           send_file=lambda name, data: client.send_file_download(name, data, save_immediately=True))
        tab = self._open_client(client, self.lecture.session, play=False, ask=self.ask_lesson, **self.lecture.keep())
        with self._lock:
            self.lecture.lecturer, self.lecture.lecturer_client = tab, cid
            self.class_panel = panel
        if self._gone(cid):
            self._disconnect(client)

    def _dismiss(self, cid: int) -> None:
        """A second lecturer's tab takes the lecture from the tab ``cid``."""
        with self._lock:
            tab = self.tabs.get(cid)
        if tab is not None:
            self.lecture.drop(tab)
        self.close_tab(cid)
        with self._lock:
            self.class_panel = None
        client = self.viser.get_clients().get(cid)
        if client is not None:
            with contextlib.suppress(Exception):
                client.gui.reset()
                client.gui.add_markdown(DISMISSED)

    def _disconnect(self, client: viser.ClientHandle) -> None:
        cid = client.client_id
        with self._lock:
            self.watchers.pop(cid, None)
            tab = self.tabs.get(cid) if self.lecture.lecturer_client == cid else None
            if tab is not None:
                self.class_panel = None
        if tab is not None:
            self.lecture.drop(tab)
        self.rounds.forget(cid)
        super()._disconnect(client)

    # ------------------------------------------------------------------ take over
    def take_over(self, watcher: Watcher) -> str | None:
        """``watcher``'s *Take over*: the lecture's state now, under a new id its page then opens.
        Returns the id (None: refused, and the watcher told why)."""
        now = time.monotonic()
        if now - watcher.taken_at < TAKE_OVER_SECONDS:
            watcher.refuse("Cannot take over", "a take-over is on its way to this tab; wait a moment")
            return None
        s = self.lecture.session
        try:
            with s.lock:
                state, step = takeover.capture(s, self.lecture.lessons), s.k
            pid = self.desk.issue(TAKEOVER, state, step)
        except (Refused, takeover.CannotTakeOver) as err:
            watcher.refuse("Cannot take over", str(err))
            return None
        if watcher.taken is not None and isinstance(self.desk, LocalDesk):
            self.desk.drop(watcher.taken)  # (one unopened take-over a tab at most: its state is memory)
        watcher.taken, watcher.taken_at = pid, now
        run_script(watcher.client.gui, routes.go_script(routes.private_path(pid)))
        return pid

    # ------------------------------------------------------------------ rounds
    def watching(self) -> int:
        with self._lock:
            return len(self.watchers)

    def _watchers(self) -> list[Watcher]:
        with self._lock:
            return list(self.watchers.values())

    def _show_round(self) -> None:
        r = self.rounds.current
        for w in self._watchers():
            with contextlib.suppress(Exception):  # (a tab closing meanwhile)
                w.show(r)
        panel = self.class_panel
        if panel is not None:
            panel.refresh()

    def open_round(self, question: Question) -> Round:
        """Ask every class tab ``question`` (the round before closes)."""
        r = self.rounds.open(question)
        self._show_round()
        return r

    def close_round(self) -> None:
        self.rounds.close()
        self._show_round()

    def reveal_round(self) -> None:
        """Show every tab the distribution and the answer, and play the run on all screens."""
        self.rounds.close()
        self.rounds.reveal()
        self._show_round()
        self.lecture.session.play()

    def ask_lesson(self, lesson: Any, index: int) -> None:
        """A lesson step's question, asked of the class with one click (its ``round`` block)."""
        panel = self.class_panel
        try:
            self.open_round(lesson_question(lesson, index))
        except RoundRefused as err:
            if panel is not None:
                panel.notify("Refused: round", str(err), "red")

    # ------------------------------------------------------------------ ticking
    def _round(self, turn: int, start: float, period: float) -> int:
        """Every tab's tick (the lecturer's steps the run), then the class's screen."""
        turn = super()._round(turn, start, period)
        tab = self.lecture.lecturer
        lock = tab._ticking if tab is not None else contextlib.nullcontext()
        try:
            with lock:  # (not while the lecturer's tab swaps its scene)
                self.broadcast.tick(start)
            panel = self.class_panel
            if panel is not None and self.broadcast.plots_due:
                panel.refresh()
        except Exception as err:
            self._say_once(err)
        return turn

    def _say_once(self, err: Exception) -> None:
        if repr(err) in self._said or len(self._said) > 32:
            return
        self._said.add(repr(err))
        where = traceback.extract_tb(err.__traceback__)[-3:]
        at = " < ".join(f"{f.filename.rsplit('/', 1)[-1]}:{f.lineno} {f.name}" for f in reversed(where))
        print(f"shoal: the class's screen failed to update: {err!r} at {at}", file=sys.stderr)
