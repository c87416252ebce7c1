"""The addresses of a lecture: who a connection is, from the path of its page.

A viser page opens its websocket at its own path (viser's client drops the query), so the
path says which page it is:

- ``/``: the **class** page. A watcher: it sees the broadcast, it drives nothing.
- ``/lecturer/``: the lecturer's page. It drives the lecture once its websocket carries the
  lecturer's key in the ``shoal_lecturer`` cookie (:data:`KEY_COOKIE`). The key reaches the
  browser in the address' fragment (``/lecturer#key=…``), which a browser never sends to a
  server: ``/lecturer`` answers with a small page (:data:`KEY_PAGE`) whose script moves the key
  into the cookie and opens ``/lecturer/``, viser's page, with no fragment (viser's page would
  put one into its websocket's address, which browsers refuse). So the key is in no request
  line a server or proxy could log, and not in the address bar of a projected screen.
- ``/p/<id>``: a **private session** by its id (a take-over, or a plain session): the id names a
  record the lecture issued (:mod:`.desk`), never a file or anything a client made up.
- ``/solo``: a plain private session; the request is answered with a redirect to a fresh
  ``/p/<id>`` (so a tab that reconnects to another process is known by its id).

Every other path is no page of a lecture (404 over HTTP; a websocket there gets a notice).
"""

from __future__ import annotations

import dataclasses
import hmac
import http
import json
import re
import secrets
from http.cookies import CookieError, SimpleCookie
from typing import Any, Callable

WATCH, LECTURER, PRIVATE, SOLO, NOWHERE = "watch", "lecturer", "private", "solo", "nowhere"
CLASS_PATH, LECTURER_PATH, PRIVATE_PREFIX, SOLO_PATH = "/", "/lecturer", "/p/", "/solo"
KEY_COOKIE = "shoal_lecturer"
KEY_BYTES = 24  # 192 bits of ``secrets``: the lecturer's key
ID_BYTES = 16  # 128 bits: a private session's id
_ID = re.compile(r"^[A-Za-z0-9_-]{16,64}$")
MAX_COOKIE_HEADER = 4096  # characters of a Cookie header read at all


def new_key() -> str:
    """A lecturer's key (URL-safe text of :data:`KEY_BYTES` random bytes)."""
    return secrets.token_urlsafe(KEY_BYTES)


def new_id() -> str:
    """A private session's id (URL-safe text of :data:`ID_BYTES` random bytes)."""
    return secrets.token_urlsafe(ID_BYTES)


def role(path: str) -> str:
    """Which page ``path`` (a request path, query dropped) is: :data:`WATCH`, :data:`LECTURER`,
    :data:`PRIVATE`, :data:`SOLO` or :data:`NOWHERE`."""
    path = path.split("?", 1)[0]
    if path in ("", CLASS_PATH):
        return WATCH
    if path.rstrip("/") == LECTURER_PATH:
        return LECTURER
    if path.rstrip("/") == SOLO_PATH:
        return SOLO
    if path.startswith(PRIVATE_PREFIX) and private_id(path) is not None:
        return PRIVATE
    return NOWHERE


def is_private(path: str) -> bool:
    """Does a connection at ``path`` stay out of the broadcast (every page but the class page)?"""
    return role(path) != WATCH


def private_id(path: str) -> str | None:
    """The id of a ``/p/<id>`` path (None: not one, or not an id's characters and length)."""
    path = path.split("?", 1)[0]
    if not path.startswith(PRIVATE_PREFIX):
        return None
    rest = path[len(PRIVATE_PREFIX):].rstrip("/")
    return rest if _ID.match(rest) else None


def private_path(pid: str) -> str:
    return f"{PRIVATE_PREFIX}{pid}"


def cookie_key(headers: Any) -> str | None:
    """The lecturer's key a request carries in its ``Cookie`` header (None: none, or unreadable)."""
    values = headers.get_all("Cookie") if headers is not None else []
    text = "; ".join(str(v) for v in values)
    if not text or len(text) > MAX_COOKIE_HEADER:
        return None
    jar: SimpleCookie = SimpleCookie()
    try:
        jar.load(text)
    except CookieError:
        return None
    morsel = jar.get(KEY_COOKIE)
    return morsel.value if morsel is not None else None


def holds_key(headers: Any, key: str) -> bool:
    """Does a request carry the lecturer's ``key`` (compared in constant time)?"""
    given = cookie_key(headers)
    return given is not None and hmac.compare_digest(given.encode(), key.encode())


KEY_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Shoal: the lecturer's page</title></head>
<body style="font-family: sans-serif; font-size: 18px; color: #1b1b1b">
<noscript>The lecturer's page needs JavaScript.</noscript>
<script>
(() => {
  const m = location.hash.match(/^#key=([A-Za-z0-9_-]{16,128})$/);
  if (m) document.cookie = %(cookie)s + "=" + m[1] + "; path=%(path)s; SameSite=Strict";
  location.replace(%(page)s);
})();
</script>
</body></html>
""" % {"cookie": json.dumps(KEY_COOKIE), "path": LECTURER_PATH, "page": json.dumps(LECTURER_PATH + "/")}


def go_script(path: str) -> str:
    """A page's script that opens ``path`` of the same origin (a path this module made)."""
    return f"location.assign({json.dumps(path)});"


Route = Callable[[Any, Any], Any]


def page_router(issue: Callable[[], str] | None) -> Route:
    """A ``process_request`` step (after the origin check, before viser's handler): the pages of a
    lecture are viser's one page, whatever their path; ``/solo`` is answered with a redirect to a
    fresh private session from ``issue()`` (None: no plain sessions here, 404)."""

    def route(connection: Any, request: Any) -> Any:
        if request.headers.get("Upgrade", "").lower() == "websocket":
            return None  # (the websocket keeps its path: it says who the connection is)
        which = role(request.path)
        if request.path.split("?", 1)[0] == LECTURER_PATH:  # the key into its cookie, then the page
            response = connection.respond(http.HTTPStatus.OK, KEY_PAGE)
            del response.headers["Content-Type"]  # (websockets' Headers add a value on assignment)
            response.headers["Content-Type"] = "text/html; charset=utf-8"
            response.headers["Cache-Control"] = "no-store"
            return response
        if which == SOLO:
            if issue is None:
                return connection.respond(http.HTTPStatus.NOT_FOUND, "No plain sessions on this server\n")
            response = connection.respond(http.HTTPStatus.FOUND, "")
            response.headers["Location"] = private_path(issue())
            response.headers["Cache-Control"] = "no-store"
            return response
        if which in (LECTURER, PRIVATE):
            return dataclasses.replace(request, path=CLASS_PATH)  # viser's page, served as at /
        return request

    return route


def request_of(viser_server: Any, client_id: int) -> tuple[str, Any]:
    """(path, headers) of the websocket request of a connected client of ``viser_server``
    (viser 1.x keeps its connections in ``_websock_server._live_connections``); ("", None) when gone."""
    connection = getattr(getattr(viser_server, "_websock_server", None), "_live_connections", {}).get(client_id)
    request = getattr(connection, "request", None)
    if request is None:
        return "", None
    return str(request.path).split("?", 1)[0], request.headers
