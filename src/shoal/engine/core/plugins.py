"""Plug-ins: variants (objectives, laws, robot laws, strategies, selections, scene kinds) that
installed packages add to Shoal's registries, without a fork.

A package declares an entry point in the group ``shoal.plugins`` whose object is a function
of no arguments that registers its entries (``LAWS.register(...)``, …), or a module that does
so when imported. :func:`load_plugins` loads every such entry point once, the first time any
registry is read; it takes no name from anywhere but the installed packages' metadata, so no
preset, upload, replay or browser value can make Shoal import or run anything. Set
``SHOAL_PLUGINS=off`` to run without them.
"""

from __future__ import annotations

import os
import threading
import warnings
from dataclasses import dataclass
from importlib.metadata import entry_points
from types import ModuleType

GROUP = "shoal.plugins"


@dataclass(frozen=True)
class Plugin:
    """One entry point of the group, loaded (``error`` None) or not (why)."""

    name: str
    value: str  # "package.module:function", from the package's metadata
    distribution: str
    error: str | None = None


_lock = threading.RLock()
_loading = False
_plugins: list[Plugin] | None = None


def disabled() -> bool:
    return os.environ.get("SHOAL_PLUGINS", "").lower() in ("off", "0", "no", "false")


def load_plugins() -> list[Plugin]:
    """Load every installed entry point of :data:`GROUP` (once; later calls return the same
    list). A plug-in that fails to load is reported (a warning, and its ``error``), not fatal."""
    global _loading, _plugins
    if _plugins is not None:
        return _plugins
    with _lock:
        if _plugins is not None or _loading:  # (a plug-in reading a registry while it registers)
            return _plugins or []
        _loading = True
        found: list[Plugin] = []
        try:
            for ep in [] if disabled() else sorted(entry_points(group=GROUP), key=lambda e: e.name):
                dist = getattr(ep.dist, "name", "") or ""
                try:
                    obj = ep.load()
                    if callable(obj) and not isinstance(obj, ModuleType):
                        obj()
                except Exception as err:  # noqa: BLE001 - a broken plug-in must not take Shoal down
                    why = f"{type(err).__name__}: {err}"
                    warnings.warn(f"shoal plug-in {ep.name!r} ({ep.value}) did not load: {why}", stacklevel=2)
                    found.append(Plugin(ep.name, ep.value, dist, why))
                else:
                    found.append(Plugin(ep.name, ep.value, dist))
        finally:
            _loading = False
            _plugins = found
        return found
