"""The Viser server behind ``shoal serve``: one session per browser tab (Chapter 3 swarm or Chapter 4–5 fleet).

``start_server`` returns at once (tests use it with ``port=0``); ``serve`` blocks until
Ctrl-C. One daemon thread ticks every tab; browser callbacks run on viser's thread pool
and meet the ticking thread only through each session's lock.
"""

from __future__ import annotations

import contextlib
import errno
import gc
import socket
import sys
import threading
import time
import traceback
import weakref
from typing import Any, Callable

import viser

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario
from shoal.studies.experiments.schedulers import DaskCluster, SchedulerError

from .experiment import ExperimentService, Limits, experiment_pool
from .input_guard import guard_inputs
from .kinds.registry import check_supported, session_for
from .message_guard import install_message_guard, quiet_handler_errors
from .native_memory import TRIM_DELAY, give_back, keep_large_blocks_returnable
from .origin_guard import OriginPolicy, guarded_viser, is_loopback
from .pace import paced
from .panel.keys import install_keys
from .replay import MAX_REPLAY_BYTES
from .session.session import Session
from .session.upload import MAX_UPLOAD_BYTES
from .tab import TabApp
from .upload_guard import guard_uploads
from .view.camera import home_camera, top_view
from .view.page import install_page
from .view.projector import BRAND
from .view.script import run_script
from .warmup import WARMUP

TICK_HZ = 60.0
PLOT_SHARE = 0.5  # of a tick period: plots due later than this in a round wait for the next round
MAX_TRANSFER_BYTES = max(MAX_UPLOAD_BYTES, MAX_REPLAY_BYTES)  # any upload; bigger ones are dropped as they arrive
MAX_PENDING_BYTES = 2 * MAX_TRANSFER_BYTES  # one tab's unfinished uploads together
STOPPED_TITLE = "This Shoal server has stopped"
STOP_NOTICE_SECONDS = 0.3
FIRST_FRAME_SECONDS = 8.0  # a new tab plays at its page's first camera report, or after this long
DEFAULT_MAX_SESSIONS = 24  # browser tabs with a simulation at once (``shoal serve --max-sessions``)
FULL_TITLE = "This Shoal server is full"
FULL_MESSAGE = ("This server already runs {n} sessions (its maximum), so this tab has no simulation. "
                "Close another Shoal tab or try again later: reload this page then.")


MAX_PORT = 65535


def waiting(client: viser.ClientHandle) -> int:
    """Messages queued for ``client`` that have not left for its page yet (viser's per-connection
    buffer, which a sent message leaves; 0 where it cannot be read)."""
    with contextlib.suppress(Exception):
        return len(client._websock_connection.get_message_buffer().message_from_id)
    return 0


class PortInUseError(OSError):
    """The requested port is taken (viser would silently move to the next free one)."""


def _cannot_listen(host: str, port: int) -> OSError | None:
    """Why a server cannot bind ``host:port`` now (None: it can; SO_REUSEADDR as asyncio servers use it).
    A port in use is a :class:`PortInUseError`."""
    try:
        infos = socket.getaddrinfo(host or None, port, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as err:
        return OSError(f"--host {host}: not an address of this machine ({getattr(err, 'strerror', None) or err})")
    family, socktype, proto, _, addr = infos[0]
    with socket.socket(family, socktype, proto) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(addr)
        except OSError as err:
            if err.errno == errno.EADDRINUSE:
                return PortInUseError(f"port {port} on {host} is already in use; choose another with --port")
            return OSError(f"cannot listen on {host} port {port}: {err.strerror or err}")
    return None


def _collect_and_give_back() -> None:
    """A closed tab's objects held in reference cycles freed now (not at the next full
    collection), then the C heap's free pages returned."""
    gc.collect()
    give_back()


class ShoalServer:
    """A running app: ``port``, ``sessions`` (client id → Session), ``tabs`` (client id → TabApp), ``stop()``.

    At most ``max_sessions`` browser tabs get a session; a tab beyond that is told so in the
    page (``turned_away``) and costs no simulation. A closed tab frees its session at once.
    Requests from pages of other origins are refused (``allow_origins`` lets some in; see
    :mod:`.origin_guard`).
    """

    def __init__(self, scenario: Scenario, host: str = "127.0.0.1", port: int = 8080,
                 max_sessions: int = DEFAULT_MAX_SESSIONS, allow_origins: tuple[str, ...] = (),
                 experiments: ExperimentService | None = None, proxy_key: str | None = None,
                 projector: bool = False) -> None:
        if max_sessions < 1:
            raise ValueError(f"max_sessions must be >= 1 (got {max_sessions})")
        self.scenario = scenario
        # the Experiment tab's sweeps: by default on one worker process beside the server
        self.experiments = experiments or ExperimentService(experiment_pool(1))
        self.host = host
        self.projector = projector  # every tab opens in projector mode (a browser's own choice wins)
        self.max_sessions = max_sessions
        self.turned_away: set[int] = set()  # client ids shown the "server is full" message
        self._opening: set[int] = set()  # client ids whose session is being built
        self._errors: weakref.WeakKeyDictionary[TabApp, str] = weakref.WeakKeyDictionary()  # last error per tab
        keep_large_blocks_returnable()  # tabs that come and go give their memory back
        self.policy = OriginPolicy(host, allow_origins, proxy_key)
        install_message_guard()  # every connection's messages: a budget, and checked before viser's handlers
        self.viser = guarded_viser(host, port, self.policy, self.route())
        quiet_handler_errors(self.viser)
        self.port = self.viser.get_port()
        self.tabs: dict[int, TabApp] = {}
        self._lock = threading.Lock()
        self._trim: threading.Timer | None = None  # the next give_back of the C heap (after a tab closed)
        self._stopping = threading.Event()
        self._configure()
        self.viser.on_client_connect(self._connected)
        self.viser.on_client_disconnect(self._disconnect)
        self._thread = threading.Thread(target=self._run, name="shoal-ticker", daemon=True)
        self._thread.start()

    @property
    def sessions(self) -> dict[int, Session]:
        with self._lock:
            return {cid: tab.session for cid, tab in self.tabs.items()}

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "::", "") else self.host
        return f"http://{host}:{self.port}/"

    def route(self) -> Any:
        """A step between the origin check and viser's page (``origin_guard.guarded_viser``'s
        ``route``; None here: every request goes to viser as it came)."""
        return None

    def _configure(self) -> None:
        gui = self.viser.gui
        gui.configure_theme(control_width="large", show_share_button=False, brand_color=BRAND)
        gui.main_panel.dock_right()
        gui.set_panel_label("Shoal · PSO for robot swarms")
        top_view(self.viser)

    # ------------------------------------------------------------------ tabs
    def open_tab(
        self, key: int, gui: Any, scene: Any, client: viser.ClientHandle | None = None, *, auto_tick: bool = True,
        session: Session | None = None, **keep: Any
    ) -> TabApp:
        """Build a session (or take ``session``) with its panels and arena on ``gui``/``scene`` and
        start ticking it (``keep``: the tab's state kept elsewhere, see :class:`TabApp`).

        Browser tabs come here from ``on_client_connect``; tests may pass ``server.gui``
        and ``server.scene`` with ``client=None`` to drive the panels without a browser, and
        ``auto_tick=False`` to advance it only by calling ``tab.tick(now)`` themselves.
        """
        session = session_for(self.scenario) if session is None else session
        kwargs: dict[str, Any] = {}
        if client is not None:
            kwargs = dict(
                notify=lambda title, body, color: client.add_notification(
                    title, body, color=color, auto_close_seconds=10.0 if color == "red" else 4.0),
                send_file=lambda name, data: client.send_file_download(name, data, save_immediately=True),
                atomic=client.atomic,
                camera=client.camera,
                script=lambda source: run_script(client.gui, source),
                backlog=lambda: waiting(client),
            )
        tab = TabApp(session, gui, scene, experiments=self.experiments, owner=key, projector=self.projector, **kwargs,
                     **keep)
        tab.auto_tick = auto_tick
        with self._lock:
            self.tabs[key] = tab
        return tab

    def close_tab(self, key: int, *, gone: bool = False) -> None:
        """Forget a tab and cancel its experiment; unless its client is ``gone``, also stop
        listening to its scene."""
        self.experiments.close_owner(key)
        with self._lock:
            tab = self.tabs.pop(key, None)
        if tab is not None and not gone:
            tab.close()
        elif tab is not None:
            tab.gone()
        if tab is not None:
            self._give_back_later()

    def _give_back_later(self) -> None:
        """The C heap's free pages back to the system, once the closed tab's memory is freed
        (one trim for a burst of closes)."""
        with self._lock:
            if self._trim is not None:
                self._trim.cancel()
            self._trim = threading.Timer(TRIM_DELAY, _collect_and_give_back)
            self._trim.daemon = True
            self._trim.start()

    def _connected(self, client: viser.ClientHandle) -> None:
        """Every connection starts here: its late writes are expected (:func:`expect_late_writes`),
        then the kind of server decides what the tab is (:meth:`_connect`)."""
        expect_late_writes(client.gui)
        self._connect(client)

    def _connect(self, client: viser.ClientHandle) -> None:
        if self._stopping.is_set():
            return
        cid = client.client_id
        with self._lock:  # count and reserve together: tabs connect on several pool threads at once
            full = len(self.tabs) + len(self._opening) >= self.max_sessions
            (self.turned_away if full else self._opening).add(cid)
        if full:
            self._turn_away(client)
            if cid not in self.viser.get_clients():  # already gone again
                self._disconnect(client)
            return
        try:
            self._open_client(client)
        finally:
            with self._lock:
                self._opening.discard(cid)
        if cid not in self.viser.get_clients():  # it closed while its session was being built
            self.close_tab(cid, gone=True)

    def _turn_away(self, client: viser.ClientHandle) -> None:
        text = FULL_MESSAGE.format(n=f"{self.max_sessions:d}")
        client.gui.add_markdown(f"**{FULL_TITLE}.** {text}")
        with client.gui.add_modal(FULL_TITLE):
            client.gui.add_markdown(text)

    def _open_client(self, client: viser.ClientHandle, session: Session | None = None, *, play: bool = True,
                     **keep: Any) -> TabApp:
        """A browser tab's session (a new one, or ``session``), panels and arena, with the page's
        guards, keys and script; playing unless ``play`` is False."""
        home_camera(client.camera)
        fitted = threading.Event()

        @client.camera.on_update
        def _(camera: viser.CameraHandle) -> None:
            if fitted.is_set():
                return
            fitted.set()  # once: the first report tells the canvas' aspect; later moves are the user's
            tab = self.tabs.get(client.client_id)
            home_camera(camera, tab.display.text_scale if tab is not None else 1.0)

        def refuse(title: str, body: str) -> None:
            client.add_notification(title, body, color="red", auto_close_seconds=10.0)

        guard_inputs(client.gui, refuse)
        guard_uploads(client.gui, MAX_TRANSFER_BYTES, MAX_PENDING_BYTES,
                      lambda name, why: refuse(f"Refused: uploaded {name}", why))
        install_page(client.gui)  # the top view held, light drawing without a GPU, projector mode, names, labels
        tab = self.open_tab(client.client_id, client.gui, client.scene, client, session=session, **keep)
        install_keys(client.gui)  # space, →, r
        if play:
            tab.play_when_drawn(FIRST_FRAME_SECONDS)  # the first view starts at step 0
        return tab

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self.turned_away.discard(client.client_id)
        self.close_tab(client.client_id, gone=True)

    # ------------------------------------------------------------------ ticking
    def _run(self) -> None:
        """Tick every tab, round after round. Scenes come first: once a round has spent
        ``PLOT_SHARE`` of a period, the (costly) plots still due wait for a later round, and
        each round starts one tab further on, so with many tabs every scene keeps moving and
        the plots of all tabs refresh in turn, less often."""
        period = 1.0 / TICK_HZ
        turn = 0
        while not self._stopping.is_set():
            start = time.monotonic()
            turn = self._round(turn, start, period)  # (a closed tab is not referenced from here until a later round)
            self._stopping.wait(max(0.0, period - (time.monotonic() - start)))

    def _round(self, turn: int, start: float, period: float) -> int:
        """One round of ticks, from one tab further on than the last round (``turn``); the next turn."""
        with self._lock:
            tabs = [tab for tab in self.tabs.values() if tab.auto_tick]
        turn = (turn + 1) % max(len(tabs), 1)
        plots_until = start + PLOT_SHARE * period
        for tab in tabs[turn:] + tabs[:turn]:
            try:
                tab.tick(start, plots=time.monotonic() < plots_until)
            except Exception as err:  # one broken tab must not stop the others
                if self._errors.get(tab) != repr(err):  # said once per tab and error, not 60 times a second
                    self._errors[tab] = repr(err)
                    where = traceback.extract_tb(err.__traceback__)[-3:]
                    at = " < ".join(f"{f.filename.rsplit('/', 1)[-1]}:{f.lineno} {f.name}" for f in reversed(where))
                    print(f"shoal: tab update failed: {err!r} at {at}", file=sys.stderr)
        return turn

    def stop(self) -> None:
        """Stop the experiments and the ticking, tell the open tabs, then stop the viser server
        (in that order: no updates on closed connections)."""
        self._stopping.set()
        with self._lock:
            if self._trim is not None:
                self._trim.cancel()
        self.experiments.stop()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=5.0)
        clients = list(self.viser.get_clients().values())
        for client in clients:
            client.add_notification(STOPPED_TITLE, "Its simulations have ended; reload this page once it runs again.",
                                    color="yellow")
            client.flush()
        if clients:
            time.sleep(STOP_NOTICE_SECONDS)  # the notices leave before the connections close
        self.viser.stop()


def expect_late_writes(gui: Any) -> None:
    """A tab's writes race its close: the ticker, the tab's build, its callbacks and a lecture's
    broadcast run on other threads than the one that sees the connection end, so some updates
    go to a client that has just gone. Viser drops them, and would warn ("Queued a … on a closed
    connection") for each tab that closes at the wrong moment. This enters viser's own scope for
    such writes (``sanctioned_dead_writes`` of the connection's buffer, through
    ``GuiApi._websock_interface``: tests/test_internals.py) for the connection's whole life; it
    ends with the buffer. That a closed tab leaves nothing referenced is tested on its own
    (tests/test_trust_memory.py)."""
    interface = getattr(gui, "_websock_interface", None)
    buffer = interface.get_message_buffer() if interface is not None else None
    scope = getattr(buffer, "sanctioned_dead_writes", None)
    if scope is not None and gui not in _LATE_WRITES:
        entered = scope()
        entered.__enter__()
        _LATE_WRITES[gui] = entered  # (left when the tab's GUI is collected, with its connection)


_LATE_WRITES: weakref.WeakKeyDictionary[Any, contextlib.AbstractContextManager[Any]] = weakref.WeakKeyDictionary()


def start_server(preset: str = "default", host: str = "127.0.0.1", port: int = 8080,
                 max_sessions: int = DEFAULT_MAX_SESSIONS, allow_origins: tuple[str, ...] = (),
                 scheduler: str | None = None, experiment_workers: int = 1,
                 limits: Limits | None = None, warm_up: bool = False, projector: bool = False,
                 factory: Callable[..., ShoalServer] | None = None) -> ShoalServer:
    """Start the app without blocking (a ``factory`` of another kind of :class:`ShoalServer`, such as
    a lecture's, takes the same arguments). ``port=0`` picks a free port (see ``.port``). With
    ``warm_up`` (``shoal serve``) the kernels compile in the background once it listens
    (:mod:`.warmup`) and scenes run on numpy meanwhile; else they compile on first use.

    The Experiment tab's sweeps run on the Dask cluster at ``scheduler`` (``tcp://HOST:PORT``)
    or on a local pool of ``experiment_workers`` processes, within ``limits``.

    Raises :class:`PresetError` for an unknown or invalid preset, :class:`PortInUseError`
    when ``port`` is taken, ``OSError`` when ``host`` cannot be listened on, ``ValueError`` for a
    port beyond 0–65535 and :class:`SchedulerError` when the cluster cannot be reached.
    """
    scenario = check_supported(presets_io.load(preset))
    if preset in presets_io.list_presets():  # a shipped scene opens at a speed one can watch (a file keeps its own)
        scenario = paced(scenario)
    if not 0 <= port <= MAX_PORT:
        raise ValueError(f"--port {port}: a port is a whole number from 0 to {MAX_PORT}")
    if (why := _cannot_listen(host, port)) is not None:  # before viser starts: it would wait for ever
        raise why
    if experiment_workers < 1:
        raise ValueError(f"experiment_workers must be >= 1 (got {experiment_workers})")
    pool = DaskCluster(scheduler) if scheduler is not None else experiment_pool(experiment_workers)
    server = (factory or ShoalServer)(scenario, host=host, port=port, max_sessions=max_sessions,
                                      allow_origins=allow_origins,
                                      experiments=ExperimentService(pool, limits, owns_scheduler=True),
                                      projector=projector)
    if port and server.port != port:  # viser moved to the next free port: refuse instead
        server.stop()
        raise PortInUseError(f"port {port} on {host} is already in use; choose another with --port")
    if warm_up:
        WARMUP.start(scenario, elsewhere=True)  # the page is up: compile the kernels behind it, this scene's first
    return server


def serve(preset: str = "default", host: str = "127.0.0.1", port: int = 8080,
          max_sessions: int = DEFAULT_MAX_SESSIONS, allow_origins: tuple[str, ...] = (),
          scheduler: str | None = None, experiment_workers: int = 1, projector: bool = False) -> None:
    """Run the browser app until Ctrl-C (``shoal serve``). Exits with a message if the port is
    taken or the Dask scheduler cannot be reached."""
    try:
        server = start_server(preset, host, port, max_sessions, allow_origins, scheduler, experiment_workers,
                              warm_up=True, projector=projector)
    except (OSError, SchedulerError, ValueError) as err:
        raise SystemExit(f"shoal serve: {err}") from None
    except PresetError as err:
        raise SystemExit("shoal serve: bad preset:\n" + "\n".join(err.messages)) from None
    if not is_loopback(host):
        print(f"warning: serving on {host}: anyone who can reach this machine on port {server.port} "
              "can open and drive the app", file=sys.stderr)
    print(f"Shoal is running at {server.url}  (Ctrl-C to stop); experiments run on "
          f"{server.experiments.scheduler.describe()}", flush=True)
    try:
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        print("\nstopping", flush=True)
    finally:
        server.stop()
        WARMUP.stop()  # (a child still compiling the kernels ends with the server)
