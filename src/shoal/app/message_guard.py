"""Every message a tab sends passes a budget and a check before viser handles it.

Viser reads a connection's messages in a loop (``viser.infra._infra._message_consumer``) and
hands each to its handlers at once: a client that speaks the websocket protocol can send
thousands a second (20,000 refused values in 0.9 s cut another tab's updates by 76 %), and a
message that does not decode, or decodes with fields of the wrong type, ended the connection
with 1011 and a traceback in the log, or raised in a handler task ("Task exception was never
retrieved"). :func:`install_message_guard` puts this module's loop in its place, for every
connection of every viser server of the process:

- a **budget** per connection: at most :data:`RATE` messages and :data:`BYTE_RATE` bytes a
  second, sustained, after bursts of :data:`BURST` messages and :data:`BYTE_BURST` bytes (a page
  sends a few dozen a second while a slider is dragged; an upload sends 512 KiB parts). A
  client beyond it is not cut off: its next message is read later, so its flood waits in its own
  socket and the other tabs' updates go on;
- a **check**: the message must be msgpack of a viser message type whose fields have the
  types that type declares (``msgspec.convert`` against viser's own dataclass), and a camera
  report finite numbers and a canvas of some size. Anything else
  is dropped and said on stderr in one line (then at most once every :data:`QUIET_SECONDS`
  per connection, with a count); after :data:`MAX_MALFORMED` of them the connection is closed
  (1008, policy violation): a page never sends one;
- a **refusal** of the messages that ask viser to share the server (:data:`REFUSED`): viser
  answers one by opening a public tunnel to this server through viser's share service, for any
  client that asks. The app offers no share button (its Share page is a file), so these are
  dropped as malformed.

:func:`quiet_handler_errors` makes an exception that still escapes a handler task one line
on stderr too. Both read viser 1.x internals; if a viser version keeps them elsewhere they
install nothing and say so (the app's own guards still hold).
"""

from __future__ import annotations

import asyncio
import math
import sys
import time
from typing import Any, Callable

import msgspec

RATE = 200.0  # messages a second, sustained, per connection
BURST = 400.0
BYTE_RATE = 8 * 2**20  # bytes a second, sustained, per connection
BYTE_BURST = 48 * 2**20  # (a 20 MiB replay uploads at once)
MAX_MALFORMED = 100  # then the connection is closed
QUIET_SECONDS = 10.0  # between two lines on stderr about one connection's malformed messages
POLICY_VIOLATION = 1008
REFUSED = {"ShareUrlRequest": "this server is not shared through viser's share service",
           "ShareUrlDisconnect": "this server is not shared through viser's share service"}


class Budget:
    """A token bucket of messages and bytes; :meth:`spend` waits until both allow one more."""

    def __init__(self, rate: float = RATE, burst: float = BURST, byte_rate: float = BYTE_RATE,
                 byte_burst: float = BYTE_BURST) -> None:
        self.rate, self.burst, self.byte_rate, self.byte_burst = rate, burst, byte_rate, byte_burst
        self.messages, self.bytes, self.last = burst, byte_burst, time.monotonic()
        self.waited = 0.0  # seconds this connection was made to wait, in all

    def _refill(self) -> None:
        now = time.monotonic()
        dt, self.last = now - self.last, now
        self.messages = min(self.burst, self.messages + dt * self.rate)
        self.bytes = min(self.byte_burst, self.bytes + dt * self.byte_rate)

    def delay(self, size: int) -> float:
        """Seconds to wait before a message of ``size`` bytes is within the budget (0: now)."""
        self._refill()
        need = max(0.0, (1.0 - self.messages) / self.rate,
                   (min(size, self.byte_burst) - self.bytes) / self.byte_rate)
        return need

    async def spend(self, size: int) -> None:
        wait = self.delay(size)
        if wait > 0:
            self.waited += wait
            await asyncio.sleep(wait)
            self._refill()
        self.messages -= 1.0
        self.bytes -= min(size, self.byte_burst)


def problem(raw: Any, message_class: Any) -> str | None:
    """Why ``raw`` is not a well-formed viser message (None: it is)."""
    if not isinstance(raw, bytes):
        return "a text frame"
    try:
        mapping = msgspec.msgpack.decode(raw)
    except Exception as err:
        return f"not msgpack ({type(err).__name__})"
    if not isinstance(mapping, dict):
        return "not a message (a map with a type)"
    kind = mapping.pop("type", None)
    if isinstance(kind, str) and kind in REFUSED:
        return f"{kind}: {REFUSED[kind]}"
    cls = message_class._subclass_from_type_string().get(kind) if isinstance(kind, str) else None
    if cls is None:
        return f"no message type {str(kind)[:60]!r}"
    try:
        msgspec.convert(mapping, cls)
    except Exception as err:
        return f"{kind}: {str(err)[:160]}"
    return _camera_problem(mapping) if kind == "ViewerCameraMessage" else None


def _camera_problem(mapping: dict[str, Any]) -> str | None:
    """A camera report must be finite, with a canvas of some size: viser keeps NaN, inf or a
    zero height, and the home camera (or anything reading its aspect) then raises."""
    numbers = [v for value in mapping.values() for v in (value if isinstance(value, (list, tuple)) else [value])]
    if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in numbers):
        return "a camera report with a number that is not finite"
    if not (mapping.get("image_width", 0) > 0 and mapping.get("image_height", 0) > 0):
        return "a camera report of an empty canvas"
    return None


def _say(text: str) -> None:
    print(f"shoal: {text}", file=sys.stderr, flush=True)


async def guarded_consumer(websocket: Any, handle_message: Callable[[Any], None], message_class: Any) -> None:
    """Viser's message loop of one connection, with the budget and the check of the module doc."""
    budget = Budget()
    peer = "a tab"
    try:
        peer = f"{websocket.remote_address[0]}:{websocket.remote_address[1]}"
    except Exception:
        pass
    malformed, unsaid, said_at = 0, 0, -QUIET_SECONDS
    while True:
        raw = await websocket.recv()
        await budget.spend(len(raw))
        why = problem(raw, message_class)
        if why is None:
            try:
                message = message_class.deserialize(raw)
            except Exception as err:  # (checked above: should not happen)
                why = f"{type(err).__name__}: {str(err)[:160]}"
        if why is None:
            handle_message(message)
            continue
        malformed += 1
        unsaid += 1
        now = time.monotonic()
        if now - said_at >= QUIET_SECONDS or malformed >= MAX_MALFORMED:
            more = f" ({unsaid - 1} more since the last line)" if unsaid > 1 else ""
            _say(f"dropped a malformed message from {peer}: {why}{more}")
            said_at, unsaid = now, 0
        if malformed >= MAX_MALFORMED:
            _say(f"closed the connection of {peer}: {MAX_MALFORMED} malformed messages")
            await websocket.close(POLICY_VIOLATION, "malformed messages")
            return


def install_message_guard() -> bool:
    """Read every viser connection's messages through :func:`guarded_consumer` (process-wide,
    once). Returns whether it could be installed."""
    try:
        from viser.infra import _infra
    except ImportError:
        return False
    current = getattr(_infra, "_message_consumer", None)
    if current is guarded_consumer:
        return True
    if current is None or not asyncio.iscoroutinefunction(current):
        _say("this viser reads messages in a way the message guard cannot wrap; running without it")
        return False
    _infra._message_consumer = guarded_consumer
    return True


def quiet_handler_errors(server: Any) -> bool:
    """On ``server``'s event loop (a started ``viser.ViserServer``), an exception that escapes a
    message handler's task is one line on stderr, not a traceback. Returns whether installed."""
    loop = getattr(getattr(server, "_websock_server", None), "_background_event_loop", None)
    if loop is None:
        return False
    last: dict[str, float] = {}

    def handler(loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        err = context.get("exception")
        if err is None:
            loop.default_exception_handler(context)
            return
        key = f"{type(err).__name__}: {str(err)[:160]}"
        now = time.monotonic()
        if len(last) > 256:  # (errors a hostile client words differently each time)
            last.clear()
        if now - last.get(key, -QUIET_SECONDS) >= QUIET_SECONDS:  # once per kind of error every few seconds
            last[key] = now
            _say(f"a message handler failed: {key}")

    loop.call_soon_threadsafe(loop.set_exception_handler, handler)
    return True
