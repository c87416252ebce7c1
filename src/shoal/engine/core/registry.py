"""One pattern for every kind of variant: objectives, Chapter 3 velocity laws, robot laws,
acoustic localisation strategies, SLO candidate selections and scene kinds.

A :class:`Registry` maps a variant's name to an entry that carries everything the rest of
Shoal needs to know about it (its label, how many terms it has, which robots it needs, its
rules, …). The engine dispatches on it, the preset models build their choices and checks from
it and the app panels their labels, so a new variant is one entry in one module, or one
:meth:`Registry.register` call from a plug-in (:mod:`.plugins`: installed packages' entries
are loaded the first time a registry is read).
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable, Iterator, Mapping
from typing import Any, Generic, Protocol, TypeVar

from .plugins import load_plugins
from .suggest import did_you_mean


class Variant(Protocol):
    """What every registry entry has (a class with these class attributes will do)."""

    @property
    def name(self) -> str: ...  # the preset value

    @property
    def label(self) -> str: ...  # what a panel shows


V = TypeVar("V", bound=Variant)
Check = Callable[[Any], "str | None"]  # an entry → why it is malformed (None: it is not)


def shape(*callables: str, **fields: type | tuple[type, ...] | frozenset[Any]) -> Check:
    """A registry's check of its entries: each of ``callables`` is a callable attribute, and each
    of ``fields`` is an instance of its type(s), or one of its values (a frozenset)."""

    def check(entry: Any) -> str | None:
        for attr in callables:
            if not callable(getattr(entry, attr, None)):
                return f"{attr} must be callable, got {_short(getattr(entry, attr, None))}"
        for attr, want in fields.items():
            value = getattr(entry, attr, None)
            if isinstance(want, frozenset):
                if value not in want:
                    return f"{attr} must be one of {sorted(map(repr, want))}, got {_short(value)}"
            elif not isinstance(value, want) or (isinstance(value, bool) and bool not in _types(want)):
                names = " or ".join(t.__name__ for t in _types(want))
                return f"{attr} must be {names}, got {_short(value)}"
        return None

    return check


def _types(want: type | tuple[type, ...]) -> tuple[type, ...]:
    return want if isinstance(want, tuple) else (want,)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _origin(entry: Any) -> str:
    """Where an entry was defined, for messages: its module (and class) name."""
    cls = entry if isinstance(entry, type) else type(entry)
    return f"{getattr(cls, '__module__', '?')}.{getattr(cls, '__qualname__', '?')}"


class Registry(Mapping[str, V], Generic[V]):
    """Entries by name, in the order given (then as registered); ``what`` names the variant in
    error messages. Reading it loads the installed plug-ins first."""

    def __init__(self, what: str, *entries: V, check: Check | None = None) -> None:
        self.what = what
        self.check = check  # what every entry must have (see :func:`shape`)
        self._entries: dict[str, V] = {}
        self._version = 0
        for e in entries:
            self._add(e, replace=False)
        self.builtin = frozenset(self._entries)  # Shoal's own entries (a plug-in replacing one is said)

    def __getitem__(self, name: str) -> V:
        load_plugins()
        return self._entries[name]

    def __iter__(self) -> Iterator[str]:
        load_plugins()
        return iter(list(self._entries))

    def __len__(self) -> int:
        load_plugins()
        return len(self._entries)

    @property
    def version(self) -> int:
        """Bumped by every change (a cache of something derived from the entries keys on it)."""
        load_plugins()
        return self._version

    def __repr__(self) -> str:
        return f"Registry({self.what!r}: {', '.join(self._entries)})"

    def names(self) -> tuple[str, ...]:
        """Every name, in order (the choices of a preset field)."""
        return tuple(self)

    def labels(self) -> dict[str, str]:
        """Label → name of every entry, in order: the choices a panel offers."""
        return {e.label: name for name, e in self.items()}

    def pick(self, name: str) -> V:
        """The entry called ``name``, or a ``ValueError`` naming the choices."""
        try:
            return self[name]
        except (KeyError, TypeError):
            raise ValueError(f"{self.what}: unknown {name!r}{did_you_mean(name, self)}, choose from "
                             f"{sorted(self)}") from None

    def register(self, entry: V, *, replace: bool = False) -> V:
        """Add ``entry`` under its name (a ``ValueError`` if the name is taken, unless ``replace``,
        or if the entry lacks what the registry's ``check`` asks); returns it, so it can decorate a
        class. Replacing one of Shoal's own entries is said (a warning naming both)."""
        name = getattr(entry, "name", None)
        old = self._entries.get(name) if isinstance(name, str) else None
        self._add(entry, replace=replace)
        if old is not None and name in self.builtin:
            by = sys._getframe(1).f_globals.get("__name__", "?")
            warnings.warn(f"{self.what} {name!r}: Shoal's built-in {old.label!r} ({_origin(old)}) is replaced by "
                          f"{entry.label!r} ({_origin(entry)}, registered from {by})", stacklevel=2)
        return entry

    def unregister(self, name: str) -> V:
        """Remove and return the entry called ``name`` (a ``KeyError`` if there is none)."""
        entry = self._entries.pop(name)
        self._version += 1
        return entry

    def _add(self, entry: V, *, replace: bool) -> None:
        name, label = getattr(entry, "name", None), getattr(entry, "label", None)
        if not isinstance(name, str) or not name.strip() or not isinstance(label, str):
            raise ValueError(f"{self.what}: an entry needs a name and a label (strings), got {entry!r}")
        if name in self._entries and not replace:
            raise ValueError(f"{self.what}: {name!r} is registered already")
        why = self.check(entry) if self.check is not None else None
        if why is not None:
            raise ValueError(f"{self.what} {name!r} ({_origin(entry)}): {why}")
        self._entries[name] = entry
        self._version += 1
