"""One process of a lecture hall, as ``shoal hall`` starts it: the lecture, or a worker.

``python -m shoal.app.hall.process`` reads its settings as one line of JSON on stdin (the keys
too: never on a command line, which any user of the machine may read), starts its server on
loopback and says ``{"port": N}`` on stdout once it listens; SIGTERM (or Ctrl-C) stops it as it
stops ``shoal serve``: its tabs are told.

- ``"role": "lecture"``: the :class:`~.lecture.LectureServer` (the class's page, the lecturer's)
  and its desk on the hall's Unix socket (:class:`~.channel.DeskService`);
- ``"role": "worker"``: a :class:`~.private.PrivateServer` claiming its private sessions from
  that desk (:class:`~.channel.RemoteDesk`) as ``worker-<index>``.
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import sys
import time
from typing import Any

from ..server import ShoalServer, start_server
from ..terminate import terminate_as_interrupt

CONNECT_SECONDS = 60.0  # a worker waits this long for the lecture's desk


def start(config: dict[str, Any]) -> tuple[ShoalServer, Any]:
    """The server ``config`` asks for, started, and what else runs beside it (a desk service)."""
    common = dict(preset=config["preset"], host="127.0.0.1", port=int(config.get("port", 0)),
                  max_sessions=int(config["max_sessions"]), allow_origins=tuple(config.get("allow_origins", ())),
                  experiment_workers=1, warm_up=True)
    if config["role"] == "lecture":
        from .channel import DeskService
        from .lecture import LectureServer

        lecture = functools.partial(LectureServer, key=config["key"], max_watchers=int(config["max_watchers"]),
                                    proxy_key=config["proxy_key"])
        server = start_server(**common, factory=lecture)
        assert isinstance(server, LectureServer)
        return server, DeskService(server.desk, config["channel"], config["channel_key"])  # type: ignore[arg-type]
    from .channel import RemoteDesk
    from .private import PrivateServer

    desk = RemoteDesk(config["channel"], config["channel_key"], f"worker-{int(config['index'])}")
    deadline = time.monotonic() + CONNECT_SECONDS
    while True:
        try:
            desk.connect()
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)
    worker = functools.partial(PrivateServer, desk=desk, owner=desk.owner, proxy_key=config["proxy_key"])
    return start_server(**common, factory=worker), desk


def main() -> int:
    config = json.loads(sys.stdin.readline())
    with terminate_as_interrupt():
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # (viser's banner: stdout says the port alone)
                server, beside = start(config)
        except KeyboardInterrupt:
            return 130
        except Exception as err:
            print(f"shoal hall: the {config.get('role')} process could not start: {err}", file=sys.stderr, flush=True)
            return 1
        print(json.dumps({"port": server.port}), flush=True)
        try:
            while True:
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            server.stop()
            with contextlib.suppress(Exception):
                (getattr(beside, "stop", None) or beside.close)()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
