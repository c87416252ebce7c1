"""One pattern for every kind of variant: Chapter 3 velocity laws, robot laws, acoustic
localisation strategies, SLO candidate selections.

A :class:`Registry` maps a variant's name to an entry that carries everything the rest of
Shoal needs to know about it (its label, how many terms it has, which robots it needs, …). The
engine dispatches on it, the preset models build their choices and checks from it and the app
panels their labels, so a new variant is one entry in one engine module.
"""

from __future__ import annotations

from typing import Generic, Protocol, TypeVar


class Variant(Protocol):
    """What every registry entry has (a class with these class attributes will do)."""

    name: str  # the preset value
    label: str  # what a panel shows


V = TypeVar("V", bound=Variant)


class Registry(dict[str, V], Generic[V]):
    """Entries by name, in the order given; ``what`` names the variant in error messages."""

    def __init__(self, what: str, *entries: V) -> None:
        super().__init__((e.name, e) for e in entries)
        self.what = what

    def names(self) -> tuple[str, ...]:
        """Every name, in order (e.g. for a ``Literal`` of the preset models)."""
        return tuple(self)

    def labels(self) -> dict[str, str]:
        """Label → name of every entry, in order: the choices a panel offers."""
        return {e.label: name for name, e in self.items()}

    def pick(self, name: str) -> V:
        """The entry called ``name``, or a ``ValueError`` naming the choices."""
        try:
            return self[name]
        except KeyError:
            raise ValueError(f"{self.what}: unknown {name!r}, choose from {sorted(self)}") from None
