"""``shoal serve --lecture``: start a lecture in this process and say its two addresses."""

from __future__ import annotations

import contextlib
import functools
import io
import socket
import sys
import time

from shoal.presets.io import PresetError
from shoal.studies.experiments.schedulers import SchedulerError

from ..origin_guard import WILDCARDS, is_loopback
from ..server import DEFAULT_MAX_SESSIONS, start_server
from .lecture import DEFAULT_MAX_WATCHERS, LectureServer


def lan_address() -> str | None:
    """This machine's address on its network (the one a route out would use; nothing is sent)."""
    with contextlib.suppress(OSError), socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.connect(("10.254.254.254", 1))
        address = str(s.getsockname()[0])
        return None if is_loopback(address) else address
    return None


def class_hint(host: str, port: int) -> str:
    """Where the students' machines reach a server bound to ``host``."""
    if is_loopback(host):
        return "(this machine only: --host 0.0.0.0 lets the class's machines in)"
    address = lan_address() if host in WILDCARDS else host
    return f"(from the class's machines: http://{address}:{port}/)" if address else ""


def start_lecture(preset: str = "default", host: str = "127.0.0.1", port: int = 8080,
                  max_sessions: int = DEFAULT_MAX_SESSIONS, max_watchers: int = DEFAULT_MAX_WATCHERS,
                  allow_origins: tuple[str, ...] = (), scheduler: str | None = None, experiment_workers: int = 1,
                  warm_up: bool = False, key: str | None = None, projector: bool = False) -> LectureServer:
    """A lecture server, started (raises as :func:`shoal.app.server.start_server` does)."""
    factory = functools.partial(LectureServer, key=key, max_watchers=max_watchers)
    server = start_server(preset, host, port, max_sessions, allow_origins, scheduler, experiment_workers,
                          warm_up=warm_up, projector=projector, factory=factory)
    assert isinstance(server, LectureServer)
    return server


def serve_lecture(preset: str = "default", host: str = "127.0.0.1", port: int = 8080,
                  max_sessions: int = DEFAULT_MAX_SESSIONS, max_watchers: int = DEFAULT_MAX_WATCHERS,
                  allow_origins: tuple[str, ...] = (), scheduler: str | None = None,
                  experiment_workers: int = 1, projector: bool = False) -> None:
    """Run a lecture until Ctrl-C. The first line printed is the lecturer's address (with the key,
    which nothing prints again); the second is the class's."""
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # (viser's banner: the lecturer's line comes first)
            server = start_lecture(preset, host, port, max_sessions, max_watchers, allow_origins, scheduler,
                                   experiment_workers, warm_up=True, projector=projector)
    except (OSError, SchedulerError, ValueError) as err:
        raise SystemExit(f"shoal serve: {err}") from None
    except PresetError as err:
        raise SystemExit("shoal serve: bad preset:\n" + "\n".join(err.messages)) from None
    print(f"lecturer: {server.lecturer_url}  (keep it to yourself: it drives the class's run)", flush=True)
    print(f"class:    {server.url}  {class_hint(host, server.port)}".rstrip(), flush=True)
    if not is_loopback(host):
        print(f"warning: serving on {host}: anyone who can reach this machine on port {server.port} can watch "
              "the lecture and open private sessions; only the lecturer's address drives the lecture",
              file=sys.stderr, flush=True)
    print(f"Shoal's lecture of {server.scenario.name} is running (Ctrl-C to stop); experiments run on "
          f"{server.experiments.scheduler.describe()}", flush=True)
    try:
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        print("\nstopping", flush=True)
    finally:
        server.stop()
