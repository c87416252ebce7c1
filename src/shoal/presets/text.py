"""Text read from a file made sendable: JSON's ``"\\ud800"`` is valid and decodes to a lone
surrogate, a Python string that UTF-8 (and so msgpack, viser's wire format) cannot encode.
A page that tried to send one lost its connection (close code 1011). :func:`encodable` turns
every lone surrogate into U+FFFD (and a pair written as two escapes into the character it
stands for), in a string or in every key and value of a parsed JSON document."""

from __future__ import annotations

from typing import Any

REPLACEMENT = "\ufffd"


def _text(value: str) -> str:
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        return value.encode("utf-16", "surrogatepass").decode("utf-16", "replace")
    return value


def encodable(value: Any) -> Any:
    """``value`` (a string, or JSON data: dicts, lists, numbers, strings) with every string
    UTF-8 encodable; anything else as it is."""
    if isinstance(value, str):
        return _text(value)
    if isinstance(value, dict):
        return {encodable(k): encodable(v) for k, v in value.items()}
    if isinstance(value, list):
        return [encodable(v) for v in value]
    return value


def has_surrogate_escape(text: str) -> bool:
    """Might JSON ``text`` decode to a surrogate (a ``\\uD800``–``\\uDFFF`` escape)?"""
    lowered = text.lower()
    return any(f"\\ud{c}" in lowered for c in "89abcdef")
