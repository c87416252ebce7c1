"""The reverse proxy in front of a lecture hall: nginx (Debian's package), run by ``shoal hall``.

:func:`config` writes the whole configuration for one hall: nginx runs unprivileged in the
foreground (``daemon off``) with its pid file, error log (stderr) and temporary folders in the
hall's own folder, and keeps no access log (a page's path names a private session). It listens
on the hall's address and sends

- ``/`` (the class page) and ``/lecturer`` to the lecture's process;
- ``/p/<id>`` (private sessions) and ``/solo`` to the workers, each new connection to the worker
  with the fewest open ones (``least_conn``: a tab is one websocket, so the least-loaded); a
  worker that refuses the connection is marked down for a while and the next one is tried, so
  a tab whose worker died reconnects to another.

Websockets pass with ``proxy_http_version 1.1`` and the ``Upgrade``/``Connection`` headers, and
stay open for hours (``proxy_read_timeout``). The browser's ``Host`` and ``Origin`` pass
unchanged; nginx adds where the browser reached it (``X-Shoal-Arrived``) and the hall's proxy
key (``X-Shoal-Proxy``, replacing any a client sent), which the processes' origin check reads
(:mod:`shoal.app.origin_guard`).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Sequence

from ..origin_guard import ARRIVED_HEADER, PROXY_HEADER
from . import routes

DEBIAN_NGINX = "/usr/sbin/nginx"
WEBSOCKET_HOURS = 12  # a tab may stay open this long without a message either way


def find() -> str | None:
    """The nginx program (Debian's, or one on PATH); None when it is not installed."""
    return shutil.which("nginx") or (DEBIAN_NGINX if Path(DEBIAN_NGINX).is_file() else None)


def listen_address(host: str, port: int) -> str:
    if host in ("", "0.0.0.0"):
        return f"{port}"
    if host == "::":
        return f"[::]:{port}"
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def config(folder: Path, host: str, port: int, lecture: int, workers: Sequence[int], proxy_key: str,
           connections: int = 4096) -> str:
    """nginx.conf for a hall in ``folder`` on ``host:port``: the lecture on loopback port ``lecture``,
    the workers on ``workers``."""
    f = folder.resolve()
    temp = "\n".join(f"    {name}_temp_path {f / ('tmp-' + name)};"
                     for name in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"))
    pool = "\n".join(f"        server 127.0.0.1:{p} max_fails=1 fail_timeout=10s;" for p in workers)
    hours = f"{WEBSOCKET_HOURS}h"
    return f"""# A Shoal lecture hall (written by shoal hall; removed when it stops)
daemon off;
worker_processes 1;
pid {f / 'nginx.pid'};
error_log stderr error;

events {{
    worker_connections {connections};
}}

http {{
    access_log off;
{temp}
    client_max_body_size 1m;

    map $http_upgrade $connection_upgrade {{
        default upgrade;
        ''      close;
    }}

    upstream shoal_lecture {{
        server 127.0.0.1:{lecture};
    }}

    upstream shoal_workers {{
        least_conn;
{pool}
    }}

    server {{
        listen {listen_address(host, port)};
        proxy_http_version 1.1;
        proxy_set_header Upgrade $http_upgrade;
        proxy_set_header Connection $connection_upgrade;
        proxy_set_header Host $http_host;
        proxy_set_header {PROXY_HEADER} "{proxy_key}";
        proxy_set_header {ARRIVED_HEADER} $server_addr:$server_port;
        proxy_read_timeout {hours};
        proxy_send_timeout {hours};
        proxy_buffering off;
        proxy_request_buffering off;
        proxy_next_upstream error timeout;
        proxy_connect_timeout 5s;

        location {routes.PRIVATE_PREFIX} {{
            proxy_pass http://shoal_workers;
        }}
        location = {routes.SOLO_PATH} {{
            proxy_pass http://shoal_workers;
        }}
        location / {{
            proxy_pass http://shoal_lecture;
        }}
    }}
}}
"""
