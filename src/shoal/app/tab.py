"""One browser tab: its session, its panels and its arena, advanced by the server's ticking thread.

``tick(now)`` runs a few steps when playing (``view.steps_per_second``), redraws the arena
at most ``SCENE_HZ`` times a second and the plots and readouts at most ``PLOT_HZ`` times,
so that plot traffic never holds up the scene. Control feedback comes first: after a control
event the scene waits ``CONTROL_HOLD``, so that the page shows the control's answer before
more scene updates and a dragged slider's redraws coalesce.

A tab shows one kind of scene at a time (:mod:`.kinds.registry`): a Chapter 3 swarm, a
Chapter 4–5 fleet, a Chapter 6–8 acoustic swarm or Mai's SLO swarm; the first three run on
true or SLO-estimated positions (``[slo] swarm = "host"``) in their own scene. Loading a
scene of another kind (preset dropdown, upload) swaps session, panels and arena in place.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections import deque
from typing import Any, Callable, ContextManager, Hashable

from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from . import share
from .experiment.service import ExperimentService
from .kinds.registry import app_kind, app_presets, kind_for, session_for
from .lessons.panel import LessonProgress
from .panel.board import Board
from .panel.panel import Panel, Services
from .panel.view_row import DISPLAY, Display
from .preset_menu import PresetMenu
from .session.session import Session
from .view import page, projector
from .view.access import Announcer
from .view.camera import Viewport, home_camera, straighten, tipped
from .warmup import WARMUP

CLICK_MODIFIERS = (None, "shift", "cmd/ctrl")


def share_page(session: Session) -> bytes:
    """The Share button's page; a busy server refuses it like a bad value."""
    try:
        return share.session_html(session)
    except share.Busy as err:
        raise PresetError(err.messages) from None


def _board(gui: Any) -> Board | None:
    try:
        return Board(gui)
    except AttributeError:  # a GUI without panels
        return None


class TabApp:
    SCENE_HZ = 30.0
    CONTROL_HOLD = 0.3  # s without scene redraws after a control event: feedback first, a dragged slider coalesces
    PLOT_HZ = 4.0
    MAX_STEPS_PER_TICK = 25
    RETIRE_SECONDS = 2.0  # a swapped-out panel stays hidden this long before its handles are removed (see replace)
    STEP_BUDGET = 0.025  # s of engine steps per tick: a heavy scene plays slower, it never stalls the other tabs

    def __init__(
        self,
        session: Session,
        gui: Any,
        scene: Any,
        *,
        notify: Callable[[str, str, str], None] | None = None,
        send_file: Callable[[str, bytes], None] | None = None,
        atomic: Callable[[], ContextManager[None]] | None = None,
        experiments: ExperimentService | None = None,
        owner: Hashable = None,
        camera: Any = None,
        script: Callable[[str], None] | None = None,
        backlog: Callable[[], int] | None = None,
        projector: bool = False,
        lesson_progress: LessonProgress | None = None,
        menu: PresetMenu | None = None,
        display: Display | None = None,
        ask: Callable[..., None] | None = None,
    ) -> None:
        self.session = session
        self.experiments, self.owner = experiments, owner  # the server's experiments; this tab's key there
        self.gui, self.scene = gui, scene
        self.messages: deque[tuple[str, str, str]] = deque(maxlen=50)  # (title, body, colour), newest last
        self.downloads: deque[tuple[str, bytes]] = deque(maxlen=5)
        self._notify_client = notify
        self._send_client = send_file
        self._atomic = atomic or contextlib.nullcontext
        self.camera = camera  # the browser's camera (viser ``CameraHandle``), None without one
        self.script, self.backlog = script, backlog  # runs JavaScript in the page; messages on their way there
        # held while the panels are built and while a tick or a swap runs: an upload (or any
        # control) the page sends while the tab is still being built waits for it, then loads
        self._ticking = threading.RLock()
        self._clicks: list[Callable[[Any], None]] = []
        self._retired: deque[tuple[float, Panel]] = deque()  # (when to remove, panel) of swapped-out kinds
        self.auto_tick = True  # False: only explicit tick() calls advance it (tests)
        self.control_hold = self.CONTROL_HOLD
        # kept when the panels are rebuilt (and, given, by whoever outlives the tab: a lecture)
        self.lesson_progress = lesson_progress or LessonProgress()  # the Lessons tab's place
        self.menu = menu or PresetMenu(tuple(app_presets()))  # the preset dropdown's choices, uploads included
        self.display = display or Display(projector=projector)  # how the arena is drawn
        self.ask = ask  # a lesson's question asked of a class (a lecturer's tab)
        self.board = _board(gui)  # the main plot and the legend beside the arena, across swaps
        self._page = Display()  # what the page was last told (flat camera, text scale)
        self._aspect: float | None = None  # the arena's width / height at the camera's last report
        self._window_height: float | None = None  # px, the arena's (the window's) at the camera's last report
        self.announcer = Announcer(gui) if camera is not None else None  # status read out, the page's title
        self.play_at: float | None = None  # play then, or at the page's first camera report (play_when_drawn)
        self._untouched: tuple[Any, int] | None = None  # (session, revision) when that was asked
        self._reported = False  # the page has reported its camera (it has drawn)
        self.closed = False  # the browser tab went away (close)
        with self._ticking:
            self._build_kind()
        if camera is not None:
            camera.on_update(self._camera_report)

    def _build_kind(self) -> None:
        kind = app_kind(self.session)
        services = Services(notify=self.notify, send_file=self.send_file, menu=self.menu, make_session=session_for,
                            replace=self.replace, share=share_page, lessons=self.lesson_progress,
                            experiments=self.experiments, owner=self.owner, view=self.view_action,
                            display=self.display, script=self.script, backlog=self.backlog, veil=self._veil,
                            board=self.board, ask=self.ask)
        self.panels = Panel(self.gui, self.session, kind, services)
        self.arena = kind.view(self.scene, self.panels.part, labels=self._labels())
        self._show_display()
        if self.camera is not None:
            self._camera_moved(self.camera)
        if self.panels.part.click is not None:
            for modifier in CLICK_MODIFIERS:
                self._clicks.append(self.scene.on_click(modifier=modifier)(self.scene_click))
        self._acc = 0.0
        self._was_playing = False
        self._last: float | None = None
        self._next_scene = 0.0
        self._controls = self.panels.controls  # (control events seen: the scene holds after a new one)
        self._next_plot = 0.0
        self._plot_key: tuple | None = None

    def _drop_kind(self) -> None:
        for cb in self._clicks:
            self.scene.remove_click_callback(cb)
        self._clicks.clear()
        self.panels.retire()
        self._retired.append((time.monotonic() + self.RETIRE_SECONDS, self.panels))
        self.arena.clear()

    def _remove_retired(self, now: float) -> None:
        """Remove the handles of panels swapped out long enough ago. viser's page applies the GUI
        updates of a batch of messages after its removals, so an update still on its way to a
        panel removed in the same batch is an error in the page's console: a swapped-out panel is
        hidden and updated no more at once, and removed only when its last updates have landed."""
        while self._retired and self._retired[0][0] <= now:
            _, panel = self._retired.popleft()
            with contextlib.suppress(Exception):  # a tab closing meanwhile
                panel.remove()

    def replace(self, scenario: Scenario, *, play: bool = True) -> Session:
        """Load ``scenario``, playing (``play=False``: paused at step 0); a scene of the other
        kind swaps session, panels and arena (the old panel hidden at once, removed a moment
        later: :meth:`_remove_retired`). Returns the session now shown. Raises
        :class:`PresetError` (nothing changed) when it cannot be shown."""
        kind = kind_for(scenario)
        with self._ticking:
            if app_kind(self.session) is kind:
                self.session.load_scenario(scenario, play=play)
                if self.panels.wanted_main() != self.panels.main_key:  # another plot to show beside the arena
                    self._drop_kind()
                    self._build_kind()
                else:
                    self.panels.sync()
                return self.session
            new = kind.session(scenario)  # may refuse: then the old scene stays
            new.choose_at_end(self.session.at_end)  # the tab's choice outlives the scene
            if play:
                new.play()  # every scene opens playing
            self._drop_kind()
            self.session = new
            self._build_kind()
            return new

    def view_action(self, action: str) -> None:
        """The panel's view buttons: "fit" (everything on screen, the camera back home) or "follow"
        (the swarm's middle stays in the middle); "display": a box of the Display folder changed."""
        if action == "fit":
            self.arena.fit_all()
            self._home_camera()
        elif action == "follow":
            self.arena.follow_swarm()
        elif action == DISPLAY:
            with self._ticking:
                self._show_display(remember=True)

    def _veil(self, text: str | None) -> None:
        if self.camera is not None and not self.closed:
            page.set_veil(self.gui, text)

    def set_projector(self, on: bool) -> None:
        """Projector mode on or off (as the header's box does; a user's choice, remembered by the page)."""
        with self._ticking:
            self.display.projector = bool(on)
            self._show_display(remember=True)

    def _labels(self) -> Any:
        """Where the arena's labels go: HTML over the canvas of a browser's page (None: viser's labels)."""
        from .view.overlay import Labels

        return Labels(self.scene) if self.camera is not None and not self.closed else None

    def _show_display(self, remember: bool = False) -> None:
        """Draw the arena as ``display`` says, tell the page (held top view, text size, projector
        mode; ``remember``: the user's choice, which the page keeps) what changed, place the board
        and show the status area's note."""
        d = self.display
        self.arena.restyle(light=d.light, text_scale=d.text_scale)
        self.panels.show_light(d.light)
        self.panels.view_gui.sync(d)
        self.panels.place(d.projector, self._window_height, page.PANEL_WIDTH * d.text_scale)
        if self.panels.text_scale != d.text_scale:
            self.panels.text_scale = d.text_scale
            self._plot_key = None  # the plots again, at the new size
        if self.camera is None:
            return
        if d.orbit != self._page.orbit:
            if not d.orbit:
                self._home_camera()  # back to the top view, which the page then holds
            page.set_flat(self.gui, not d.orbit)
        if d.light != self._page.light:
            page.set_light(self.gui, d.light)
        if d.projector != self._page.projector:
            page.set_text_scale(self.gui, d.text_scale)  # (the arena's new width re-fits it: _camera_moved)
            projector.set_projector(self.gui, d.projector, remember)
        self._page = Display(d.light, d.orbit, d.projector)

    def play_when_drawn(self, within: float) -> None:
        """Start playing at the page's first camera report (its first frame is drawn), or after
        ``within`` seconds whatever comes: the first view starts at step 0. Nothing is played if
        the user (or a lesson's Set up) has touched the scene meanwhile."""
        self._untouched = (self.session, self.session.revision)
        if self._reported:  # (the page's first report came already)
            self._play_first()
        else:
            self.play_at = time.monotonic() + within

    def _play_first(self) -> None:
        self.play_at = None
        if self._untouched == (self.session, self.session.revision):
            self.session.play()

    def _camera_report(self, camera: Any) -> None:
        """The page reported its camera: it has drawn (the first time), or the user moved it."""
        self._reported = True
        if self.play_at is not None:
            self._play_first()
        self._camera_moved(camera)

    def _camera_moved(self, camera: Any) -> None:
        with contextlib.suppress(Exception):  # no report yet, or a tab closing
            aspect = float(camera.aspect)
            resized = self._aspect is not None and abs(aspect - self._aspect) > 1e-3
            self._aspect = aspect
            # (the canvas' pixels, not CSS pixels: the light drawing renders half of them; a screen
            # of two pixels a CSS pixel would count double, which the board's plot's cap absorbs)
            height = float(camera.image_height) / (page.LIGHT_DPR if self.display.light else 1.0)
            if height > 0 and height != self._window_height:
                self._window_height = height
                self.panels.place(self.display.projector, height, page.PANEL_WIDTH * self.display.text_scale)
            if resized:  # the arena's width changed (a panel folded or widened, the window): show all of it again
                home_camera(camera, self.display.text_scale)
                return
            if not self.display.orbit and tipped(camera):  # a page that does not hold the top view itself
                straighten(camera)
                return
            self.arena.look(Viewport.of(camera))

    def _home_camera(self) -> None:
        if self.camera is not None:
            with contextlib.suppress(Exception):  # a tab closing meanwhile
                home_camera(self.camera, self.display.text_scale)

    def gone(self) -> None:
        """Its page is gone: send it no more scripts (a closed connection would only warn)."""
        self.closed = True
        self.announcer = None
        self.arena.canvas.labels = None

    def close(self) -> None:
        """The browser tab went away: stop listening to its scene and its experiment, and stop
        sending its page scripts (a closed connection would only warn)."""
        self.gone()
        self.panels.detach()
        for cb in self._clicks:
            with contextlib.suppress(Exception):
                self.scene.remove_click_callback(cb)
        self._clicks.clear()

    def scene_click(self, event: Any) -> str:
        """A click in the arena (viser ``SceneClickEvent``): the kind decides what it does; returns
        what it did ("none" where the kind offers nothing or the ray misses the ground)."""
        click = self.panels.part.click
        xy = self.arena.ray_to_world(event.ray_origin, event.ray_direction)
        if click is None or xy is None:
            return "none"
        return click(self.panels, float(xy[0]), float(xy[1]), event.modifier)

    def notify(self, title: str, body: str, color: str = "blue") -> None:
        self.messages.append((title, body, color))
        if self._notify_client is not None:
            self._notify_client(title, body, color)

    def send_file(self, name: str, content: bytes) -> None:
        self.downloads.append((name, content))
        if self._send_client is not None:
            self._send_client(name, content)

    def tick(self, now: float | None = None, plots: bool = True) -> None:
        """Advance playback and redraw what is due (a call while another runs is skipped). With
        ``plots=False`` the plots and readouts wait, still due, for a later tick (a busy server)."""
        if not self._ticking.acquire(blocking=False):
            return
        try:
            self._tick(time.monotonic() if now is None else now, plots)
        finally:
            self._ticking.release()

    def _step(self, n: int) -> None:
        """Up to ``n`` steps; ticked by the server, fewer once ``STEP_BUDGET`` is spent (the rest are
        dropped, not queued). Tabs ticked by hand (tests) always take all ``n``."""
        end = time.monotonic() + self.STEP_BUDGET if self.auto_tick else float("inf")
        for _ in range(n):
            if not self.session.play_step() or time.monotonic() >= end:
                return

    def _tick(self, now: float, plots: bool = True) -> None:
        if self._retired:
            self._remove_retired(time.monotonic())
        if self.play_at is not None and time.monotonic() >= self.play_at:  # no camera report came: play anyway
            self._play_first()
        s = self.session
        elapsed = 0.0 if self._last is None else max(0.0, now - self._last)
        self._last = now
        if s.playing:
            if self._was_playing:  # time before Play was pressed does not count
                self._acc += elapsed * s.scenario.view.steps_per_second
            n = int(self._acc)
            self._acc -= n
            if n:
                self._step(min(n, self.MAX_STEPS_PER_TICK))
            self._acc = min(self._acc, 1.0)
        else:
            self._acc = 0.0
        self._was_playing = s.playing
        if s.scene_revision != self.arena.built_revision:
            if self.arena.built_revision >= 0:  # a scene built again is fitted again, seen from home
                self._home_camera()
            with self._atomic():
                self.arena.rebuild(s.scene_revision)
        if self.panels.controls != self._controls:  # the page is busy with the control's answer: let it show
            self._controls = self.panels.controls
            self._next_scene = max(self._next_scene, now + self.control_hold)
        if now >= self._next_scene and s.revision != self.arena.drawn_revision:
            snap = s.shown_snapshot()  # live, or the recorded frame the timeline points at (and swarm B)
            with self._atomic():  # one wake-up of viser's event loop for the scene and its readouts
                self.arena.draw(snap)
                self.panels.on_snapshot(snap)
                self.panels.view_gui.show_legend(self.arena.legend())
            self._next_scene = now + 1.0 / self.SCENE_HZ
        if plots and now >= self._next_plot:
            key = (s.revision, s.selected_robot, s.selected_dim, s.playing, WARMUP.revision, WARMUP.busy_seconds())
            if key != self._plot_key:
                with self._atomic():  # one wake-up for all of them (wake-ups cost the ticking thread the GIL)
                    self.panels.refresh_status()
                    if self.announcer is not None:
                        self.announcer.name(s.scenario.name)
                        self.announcer.status(self.panels.status.content)
                    self.panels.refresh_readout()
                    self.panels.refresh_plots()
                    self.panels.refresh_timeline()
                    self.panels.refresh_lessons()
                    self.panels.refresh_experiment()
                self._plot_key = key
            self._next_plot = now + 1.0 / self.PLOT_HZ
