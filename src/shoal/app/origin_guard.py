"""Only pages of this server may open a session: the ``Origin`` and ``Host`` check.

A browser lets any web page open a websocket to any address, ``127.0.0.1`` included, and
says which page asks in the ``Origin`` header. Without a check, a page the user happens to
visit could open a session on a running ``shoal serve`` and drive it; with a DNS name that
the attacker points at 127.0.0.1 (DNS rebinding) it could even load the app as its own.
So every HTTP request and websocket upgrade is refused (403) unless

- its ``Host`` names this server: a loopback name or address, the address it is bound to,
  the address the request arrived on, or the host of an allowed origin; and
- its ``Origin``, if it has one (browsers always send one on a websocket), is an allowed
  origin (``shoal serve --allow-origin URL``), the page's own (``http://`` + that ``Host``,
  as through an SSH tunnel) or ``http://`` + a name above + the port the request arrived on.

Clients that are not browsers send no ``Origin``; they are held to the ``Host`` check only.

Behind the reverse proxy of ``shoal hall`` every request arrives from the proxy on a loopback
port, so the address and port a request arrived on are the proxy's: the proxy says them in
``X-Shoal-Arrived`` and proves it is the hall's own with ``X-Shoal-Proxy`` (a secret the hall
gives it and its processes, :class:`OriginPolicy` ``proxy_key``). With the key, the checks above
use the address the browser reached; a request that names the proxy without the key is
refused. The browser's ``Host`` and ``Origin`` pass through the proxy unchanged.

A connection that closes or speaks no HTTP before its request (a port check, a health
probe) is said in one line on stderr, not as websockets' three-part traceback
(:class:`HandshakeNoise`).
A request that names ``Host`` or ``Origin`` more than once is refused too (403, not an error).
The private server that records a Share page takes no request at all (:class:`Closed`).

Viser 1.1.1 passes its own HTTP handler to ``websockets``' ``serve(process_request=...)`` and
offers no hook of its own, so :func:`guarded_viser` wraps that handler with the check while
(and only while) it builds the server: no copy of viser, no change to any other server.
"""

from __future__ import annotations

import contextlib
import hmac
import http
import ipaddress
import logging
import sys
import threading
from typing import Any, Callable, Iterator, Sequence
from urllib.parse import urlsplit

import viser
import websockets.asyncio.server as ws_server

LOOPBACK_NAMES = ("localhost",)
WILDCARDS = ("", "0.0.0.0", "::")
MAX_REPORTED = 32  # distinct refused origins/hosts said on stderr (then silence)


def is_loopback(host: str) -> bool:
    host = host.strip("[]").lower()
    if host in LOOPBACK_NAMES:
        return True
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return False
    mapped = getattr(address, "ipv4_mapped", None)
    return address.is_loopback or (mapped is not None and mapped.is_loopback)


def _origin(url: str) -> tuple[str, str, int] | None:
    """(scheme, host, port) of an origin or URL, with the default port filled in; None if malformed."""
    try:
        parts = urlsplit(url.strip())
        port = parts.port
    except ValueError:
        return None
    scheme, host = parts.scheme.lower(), (parts.hostname or "").lower()
    if scheme not in ("http", "https") or not host:
        return None
    return scheme, host, port or (443 if scheme == "https" else 80)


def check_origin_url(url: str) -> str:
    """``url`` if it is an origin ``--allow-origin`` takes (``http[s]://host[:port]``), else ValueError."""
    if _origin(url) is None or urlsplit(url.strip()).path not in ("", "/"):
        raise ValueError(f"--allow-origin {url!r}: expected an origin such as http://192.168.1.10:8080")
    return url


def _address(host: str) -> str:
    try:
        return str(ipaddress.ip_address(host.strip("[]")))
    except ValueError:
        return host.strip("[]").lower()


PROXY_HEADER, ARRIVED_HEADER = "X-Shoal-Proxy", "X-Shoal-Arrived"


class OriginPolicy:
    """Which ``Host`` and ``Origin`` headers a server bound to ``host`` accepts (``proxy_key``: the
    secret of the hall's proxy, whose requests are judged by where the browser reached it)."""

    def __init__(self, host: str, allow_origins: Sequence[str] = (), proxy_key: str | None = None) -> None:
        self.bound = "" if host in WILDCARDS else _address(host)
        self.allowed = {o for o in (_origin(url) for url in allow_origins) if o is not None}
        self.proxy_key = proxy_key
        self._reported: set[str] = set()
        self._lock = threading.Lock()

    def arrival(self, headers: Any, local: tuple[str, int]) -> tuple[tuple[str, int] | None, str | None]:
        """(where the request arrived, why it is refused): ``local`` for a direct request; the
        proxy's ``X-Shoal-Arrived`` for a request that carries the proxy's key."""
        (key, twice), (arrived, twice_too) = _one(headers, PROXY_HEADER), _one(headers, ARRIVED_HEADER)
        if twice or twice_too:
            return None, twice or twice_too
        if key is None and arrived is None:
            return local, None
        if self.proxy_key is None or key is None or not hmac.compare_digest(key.encode(), self.proxy_key.encode()):
            return None, "the request names the hall's proxy without its key"
        where = _origin(f"http://{arrived}") if arrived else None
        if where is None:
            return None, f"the proxy said it arrived at {arrived!r}, not an address and port"
        return (where[1], where[2]), None

    def _own_host(self, name: str, local: str) -> bool:
        name = _address(name)
        return (is_loopback(name) or name == self.bound or name == _address(local)
                or any(name == host for _, host, _ in self.allowed))

    def refusal(self, host_header: str | None, origin_header: str | None, local: tuple[str, int]) -> str | None:
        """Why a request with these headers, arriving on the address and port ``local``, is
        refused (None: it is not)."""
        host = _origin(f"http://{host_header}") if host_header else None
        if host is None or not self._own_host(host[1], local[0]):
            return f"Host {host_header!r} is not this server"
        if origin_header is None:
            return None  # not a browser
        origin = _origin(origin_header)
        if origin is not None and (origin in self.allowed or origin == host or (
                origin[0] == "http" and origin[2] == local[1] and self._own_host(origin[1], local[0]))):
            return None
        return f"Origin {origin_header!r} is not this server's page (shoal serve --allow-origin URL allows one)"

    def report(self, why: str) -> None:
        """Say a refusal once on stderr (a server bound beyond loopback is told who knocks)."""
        with self._lock:
            if why in self._reported or len(self._reported) >= MAX_REPORTED:
                return
            self._reported.add(why)
        print(f"shoal: refused a connection: {why}", file=sys.stderr, flush=True)


class Closed:
    """The policy of a server nobody is meant to reach (the private one that records a Share
    page or ``shoal export-replay``'s scene): every request is refused, quietly."""

    def arrival(self, headers: Any, local: tuple[str, int]) -> tuple[tuple[str, int] | None, str | None]:
        return local, None

    def refusal(self, host_header: str | None, origin_header: str | None, local: tuple[str, int]) -> str | None:
        return "this server records a page and takes no connections"

    def report(self, why: str) -> None:
        pass


Policy = OriginPolicy | Closed
ProcessRequest = Callable[[Any, Any], Any]


def _one(headers: Any, name: str) -> tuple[str | None, str | None]:
    """(the value of header ``name`` or None, why it is refused: it came more than once)."""
    values = headers.get_all(name)
    if len(values) > 1:
        return None, f"{len(values)} {name} headers in one request"
    return (values[0] if values else None), None


def _guard(policy: Policy, inner: ProcessRequest | None, route: ProcessRequest | None = None) -> ProcessRequest:
    """The checks, then ``route`` (a Response to send, or the request to hand on), then ``inner``."""
    def process_request(connection: Any, request: Any) -> Any:
        address, port = (connection.local_address or ("", 0))[:2]
        (host, twice), (origin, twice_too) = _one(request.headers, "Host"), _one(request.headers, "Origin")
        local, why = policy.arrival(request.headers, (str(address), int(port)))
        why = twice or twice_too or why
        if why is None and local is not None:
            why = policy.refusal(host, origin, local)
        if why is not None:
            policy.report(why)
            return connection.respond(http.HTTPStatus.FORBIDDEN, f"Forbidden: {why}\n")
        if route is not None:
            routed = route(connection, request)
            if routed is None or not hasattr(routed, "path"):  # a response (None: a websocket, as it is)
                return routed if routed is not None else (inner(connection, request) if inner is not None else None)
            request = routed
        return inner(connection, request) if inner is not None else None

    return process_request


_building = threading.Lock()  # one guarded server built at a time: the wrapper is in place only then


@contextlib.contextmanager
def _guarding(policy: Policy, route: ProcessRequest | None = None) -> Iterator[threading.Event]:
    """While active, a websockets server started (by viser) checks ``policy`` first; the
    event yielded is set once one did."""
    real, installed = ws_server.serve, threading.Event()

    class GuardedServe(real):  # type: ignore[misc, valid-type]  # (websockets' serve class, read at run time)
        def __init__(self, *args: Any, process_request: ProcessRequest | None = None, **kwargs: Any) -> None:
            super().__init__(*args, process_request=_guard(policy, process_request, route), **kwargs)
            installed.set()

    with _building:
        ws_server.serve = GuardedServe  # type: ignore[misc]  # (websockets' class, replaced while viser starts)
        try:
            yield installed
        finally:
            ws_server.serve = real  # type: ignore[misc]  # (and put back)


class HandshakeNoise(logging.Filter):
    """websockets logs a connection that ends before a valid request as "opening handshake
    failed" with a chained traceback; this keeps one line (who, and why) for each of the first
    ``first`` and then for every ``every``-th (a health probe every few seconds does not flood the log)."""

    def __init__(self, first: int = 10, every: int = 100) -> None:
        super().__init__()
        self.first, self.every, self.seen = first, every, 0
        self._lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        if record.msg != "opening handshake failed" or not record.exc_info:
            return True
        with self._lock:
            self.seen += 1
            seen = self.seen
        if seen > self.first and seen % self.every:
            return False
        err = record.exc_info[1]
        if err is None:
            return True
        why = err.__cause__ or err
        ws = getattr(record, "websocket", None)
        peer = getattr(ws, "remote_address", None)
        who = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) and len(peer) >= 2 else "a client"
        record.msg, record.args = "shoal: a connection from %s ended before a valid request (%s)%s", (
            who, why, f"; {seen} such so far" if seen > self.first else "")
        record.exc_info = record.exc_text = None
        return True


_NOISE = HandshakeNoise()
logging.getLogger("websockets.server").addFilter(_NOISE)  # once per process, whatever servers it runs


def guarded_viser(host: str, port: int, policy: Policy, route: ProcessRequest | None = None) -> viser.ViserServer:
    """A started ``viser.ViserServer`` whose every request passes ``policy`` first (then ``route``,
    which may answer it or hand on another request: a lecture's pages). Raises RuntimeError (and
    serves nothing) if this viser starts its server some other way."""
    with _guarding(policy, route) as installed:
        server = viser.ViserServer(host=host, port=port, verbose=False)  # listening when it returns
    if not installed.is_set():
        server.stop()
        raise RuntimeError(f"viser {viser.__version__} starts its server in a way the origin check cannot "
                           "wrap; refusing to serve without it")
    return server
