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

from collections.abc import Iterator, Mapping
from typing import Generic, Protocol, TypeVar

from .plugins import load_plugins
from .suggest import did_you_mean


class Variant(Protocol):
    """What every registry entry has (a class with these class attributes will do)."""

    @property
    def name(self) -> str: ...  # the preset value

    @property
    def label(self) -> str: ...  # what a panel shows


V = TypeVar("V", bound=Variant)


class Registry(Mapping[str, V], Generic[V]):
    """Entries by name, in the order given (then as registered); ``what`` names the variant in
    error messages. Reading it loads the installed plug-ins first."""

    def __init__(self, what: str, *entries: V) -> None:
        self.what = what
        self._entries: dict[str, V] = {}
        self._version = 0
        for e in entries:
            self._add(e, replace=False)

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
        """Add ``entry`` under its name (a ``ValueError`` if the name is taken, unless ``replace``);
        returns it, so it can decorate a class."""
        self._add(entry, replace=replace)
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
        self._entries[name] = entry
        self._version += 1
