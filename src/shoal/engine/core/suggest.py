""""Did you mean …?" for a mistyped name: the closest of the names it could have been (difflib)."""

from __future__ import annotations

from typing import Iterable


def close(word: str, choices: Iterable[str], n: int = 2) -> list[str]:
    """The names of ``choices`` closest to ``word`` (at most ``n``, best first; none if none is close)."""
    import difflib  # (only a mistyped name needs it)

    return difflib.get_close_matches(word, [c for c in choices if isinstance(c, str)], n=n, cutoff=0.6)


def did_you_mean(word: object, choices: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` for the closest of ``choices`` to ``word``, else ``""``."""
    if not isinstance(word, str):
        return ""
    found = [c for c in close(word, choices) if c != word]
    if not found:
        return ""
    return f" (did you mean {' or '.join(map(repr, found))}?)"
