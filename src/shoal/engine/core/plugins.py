"""Plug-ins: variants (objectives, laws, robot laws, strategies, selections, scene kinds) that
installed packages add to Shoal's registries, without a fork.

A package declares an entry point in the group ``shoal.plugins`` whose object is a function
of no arguments that registers its entries (``LAWS.register(...)``, …), or a module that does
so when imported. :func:`load_plugins` loads every such entry point once, the first time any
registry is read; it takes no name from anywhere but the installed packages' metadata, so no
preset, upload, replay or browser value can make Shoal import or run anything. Set
``SHOAL_PLUGINS=off`` to run without them.

A plug-in cannot silence Shoal: whatever its import or ``register()`` raises (an exception,
``sys.exit``, ``KeyboardInterrupt``, any ``BaseException``) skips that plug-in with one line
on stderr naming its package, the error and ``SHOAL_PLUGINS=off``, and every other command
goes on. Only a real Ctrl-C, a SIGINT that arrives while the plug-ins load, is the user's and
ends the command. A plug-in that takes more than :data:`SLOW_SECONDS` to load is named too.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from importlib.metadata import entry_points
from types import FrameType, ModuleType
from typing import Any

GROUP = "shoal.plugins"
SLOW_SECONDS = 1.0  # a plug-in that takes longer to load is named on stderr


@dataclass(frozen=True)
class Plugin:
    """One entry point of the group, loaded (``error`` None) or not (why)."""

    name: str
    value: str  # "package.module:function", from the package's metadata
    distribution: str
    error: str | None = None
    seconds: float = 0.0  # how long its import and register() took


_lock = threading.RLock()
_loading = False
_plugins: list[Plugin] | None = None


def disabled() -> bool:
    return os.environ.get("SHOAL_PLUGINS", "").lower() in ("off", "0", "no", "false")


def _say(text: str) -> None:
    print(f"shoal: {text}", file=sys.stderr, flush=True)


class _UserInterrupt:
    """While the plug-ins load in the main thread, note whether a real SIGINT or SIGTERM came
    (then a ``KeyboardInterrupt`` is the user's, not a plug-in's); each still does what it did."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.came = False
        self._old: dict[int, Any] = {}

    def __enter__(self) -> _UserInterrupt:
        if threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                try:
                    self._old[sig] = signal.signal(sig, self._handle)
                except (ValueError, OSError):  # (no signals here, e.g. an embedded interpreter)
                    pass
        return self

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        old = self._old.get(signum)
        if old == signal.SIG_IGN:
            return
        self.came = True
        if callable(old):
            old(signum, frame)  # Python's KeyboardInterrupt, or the command's Terminated
        elif signum == signal.SIGINT:
            raise KeyboardInterrupt
        else:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)

    def __exit__(self, *exc: object) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)


def _why(err: BaseException) -> str:
    text = str(err)
    if isinstance(err, SystemExit):
        text = f"exit code {err.code!r}" if not isinstance(err.code, str) else err.code
    return f"{type(err).__name__}: {text}"[:300] if text else type(err).__name__


def load_plugins() -> list[Plugin]:
    """Load every installed entry point of :data:`GROUP` (once; later calls return the same
    list). A plug-in that fails to load is skipped and said in one line (its ``error``), not fatal."""
    global _loading, _plugins
    if _plugins is not None:
        return _plugins
    with _lock:
        if _plugins is not None or _loading:  # (a plug-in reading a registry while it registers)
            return _plugins or []
        _loading = True
        found: list[Plugin] = []
        try:
            with _UserInterrupt() as user:
                for ep in [] if disabled() else sorted(entry_points(group=GROUP), key=lambda e: e.name):
                    found.append(_load(ep, user))
        finally:
            _loading = False
            _plugins = found
        return found


def _load(ep: Any, user: _UserInterrupt) -> Plugin:
    dist = getattr(ep.dist, "name", "") or ""
    package = dist or ep.value.split(":")[0].split(".")[0]
    start = time.perf_counter()
    try:
        obj = ep.load()
        if callable(obj) and not isinstance(obj, ModuleType):
            obj()
    except BaseException as err:  # noqa: BLE001 - a broken plug-in must not take Shoal down, nor silence it
        if isinstance(err, KeyboardInterrupt) and user.came:
            raise  # the user's Ctrl-C, not the plug-in's
        why = _why(err)
        _say(f"skipped plug-in {ep.name!r} of package {package!r} ({ep.value}): {why}; "
             "SHOAL_PLUGINS=off runs without plug-ins")
        return Plugin(ep.name, ep.value, dist, why, time.perf_counter() - start)
    seconds = time.perf_counter() - start
    if seconds > SLOW_SECONDS:
        _say(f"plug-in {ep.name!r} of package {package!r} took {seconds:.1f} s to load "
             "(SHOAL_PLUGINS=off runs without plug-ins)")
    return Plugin(ep.name, ep.value, dist, seconds=seconds)
