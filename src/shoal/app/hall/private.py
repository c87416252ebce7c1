"""Private sessions by id (``/p/<id>``): the part of a lecture a worker of ``shoal hall`` serves.

A :class:`PrivateServer` is a :class:`~shoal.app.server.ShoalServer` whose tabs open at
``/p/<id>``: it claims the id on the lecture's desk (:mod:`.desk`; in another process through
:mod:`.channel`), builds the session the id names (a take-over's state, :mod:`.takeover`, or a
fresh plain session) within ``--max-sessions``, and lets the id go when the tab closes. A tab
that had the id before (its connection dropped, or the process that ran it stopped) is told it
starts again. Every private tab has *Back to the lecture*; none sees the lecture's broadcast.
``/solo`` is answered with the redirect to a fresh plain session's ``/p/<id>``
(:func:`.routes.page_router`).
"""

from __future__ import annotations

from typing import Any, Hashable, Protocol

import viser

from shoal.presets.models import Scenario

from ..experiment import ExperimentService
from ..kinds.registry import session_for
from ..markdown import escape
from ..server import DEFAULT_MAX_SESSIONS, ShoalServer
from ..session.session import Session
from ..tab import TabApp
from ..view.camera import CAMERA_FOV, CAMERA_HEIGHT
from ..view.page import run_script
from . import routes, takeover
from .desk import PLAIN, TAKEOVER, Claim, Refused

BACK = "Back to the lecture"
NOT_HERE = ("**This is a worker of a lecture hall.** The class watches at the hall's own address (`/`); "
            "private sessions open there (*Take over*, or `/solo`).")


class Desk(Protocol):
    """The desk a server claims its private sessions at (:class:`.desk.Desk`, or a worker's
    :class:`.channel.RemoteDesk`)."""

    def issue(self, kind: str, state: bytes = b"", step: int = 0) -> str: ...

    def issue_plain(self) -> str: ...

    def claim(self, pid: str, holder: Hashable) -> Claim: ...

    def release(self, pid: str, holder: Hashable) -> None: ...


def configure_client(client: Any) -> None:
    """A private tab's page set up as the server's own is for the class (theme, panel, lights):
    a private connection gets none of the server's broadcast (:mod:`.fanout`)."""
    gui = client.gui
    gui.configure_theme(control_width="large", show_share_button=False, brand_color=(40, 90, 200))
    gui.main_panel.dock_right()
    gui.set_panel_label("Shoal · PSO for robot swarms")
    client.scene.set_up_direction("+z")
    client.scene.configure_default_lights(enabled=True, cast_shadow=False)
    camera = client.camera  # (the server's initial camera is part of its broadcast: this tab's own)
    camera.fov, camera.near, camera.far = CAMERA_FOV, 1.0, 4.0 * CAMERA_HEIGHT


class PrivateServer(ShoalServer):
    """Private sessions claimed on ``desk`` under the holder name ``owner`` (this process)."""

    def __init__(self, scenario: Scenario, host: str = "127.0.0.1", port: int = 8080, *, desk: Desk,
                 owner: str = "lecture", max_sessions: int = DEFAULT_MAX_SESSIONS, allow_origins: tuple[str, ...] = (),
                 experiments: ExperimentService | None = None, proxy_key: str | None = None,
                 projector: bool = False) -> None:
        self.desk, self.owner = desk, owner
        self.held: dict[int, str] = {}  # client id → the private id its tab holds
        self._claims: dict[int, Claim] = {}  # client id → its claim, while its session is built
        super().__init__(scenario, host, port, max_sessions, allow_origins, experiments, proxy_key, projector)

    def route(self) -> Any:
        return routes.page_router(self.desk.issue_plain)

    def _connect(self, client: viser.ClientHandle) -> None:
        if self._stopping.is_set():
            return
        path, _ = routes.request_of(self.viser, client.client_id)
        if routes.role(path) == routes.PRIVATE:
            self._open_private(client, path)
        else:
            self._elsewhere(client, path)

    def _elsewhere(self, client: viser.ClientHandle, path: str) -> None:
        """A page this server does not serve."""
        configure_client(client)
        client.gui.add_markdown(NOT_HERE)

    def _gone(self, cid: int) -> bool:
        return cid not in self.viser.get_clients()

    def _open_private(self, client: viser.ClientHandle, path: str) -> None:
        """A ``/p/<id>`` page: its id claimed on the desk, then a session within ``--max-sessions``."""
        cid, pid = client.client_id, routes.private_id(path)
        try:
            if pid is None:
                raise Refused("this is no private session's address")
            claim = self.desk.claim(pid, (self.owner, cid))
        except Refused as err:
            configure_client(client)
            client.gui.add_markdown(f"**No private session here.** {escape(str(err))}")
            self._back_button(client)
            return
        with self._lock:
            self.held[cid] = pid
            self._claims[cid] = claim
        configure_client(client)
        self._back_button(client)
        try:
            super()._connect(client)  # (→ _open_client, unless the server is full)
        except takeover.CannotTakeOver as err:
            client.gui.add_markdown(f"**This take-over cannot start.** {escape(str(err))}")
        finally:
            with self._lock:
                self._claims.pop(cid, None)
                opened = cid in self.tabs
            if not opened:
                self._release(cid)

    def _open_client(self, client: viser.ClientHandle, session: Session | None = None, *, play: bool = True,
                     **keep: Any) -> TabApp:
        with self._lock:
            claim = self._claims.get(client.client_id)
        if session is not None or claim is None:  # the lecturer's tab (or a plain one)
            return super()._open_client(client, session, play=play, **keep)
        session, playing, keep = self._session_of(claim)
        tab = super()._open_client(client, session, play=playing, **keep)
        if claim.again:
            tab.notify("Started again", "This tab's connection was lost (or the server that ran it stopped): "
                       + ("it starts again from where you took over." if claim.kind == TAKEOVER
                          else "this is a new session."), "yellow")
        return tab

    def _release(self, cid: int) -> None:
        with self._lock:
            pid = self.held.pop(cid, None)
        if pid is not None:
            self.desk.release(pid, (self.owner, cid))

    def _session_of(self, claim: Claim) -> tuple[Session, bool, dict[str, Any]]:
        """The session a claimed id opens, whether it plays, and the tab's state it starts with."""
        if claim.kind == PLAIN:
            return session_for(self.scenario), True, {}
        session, playing = takeover.restore(claim.state)
        lessons = takeover.lesson_of(claim.state)
        return session, playing, ({"lesson_progress": lessons} if lessons is not None else {})

    def _back_button(self, client: viser.ClientHandle) -> None:
        button = client.gui.add_button(BACK, hint="watch the lecture again (this private session ends)")

        @button.on_click
        def _(event: Any) -> None:
            run_script(client.gui, routes.go_script(routes.CLASS_PATH))

    def _disconnect(self, client: viser.ClientHandle) -> None:
        self._release(client.client_id)
        super()._disconnect(client)
