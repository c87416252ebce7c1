"""Bounds on TOML text, checked before ``tomllib`` parses it.

``tomllib`` spends time quadratic in the parts of a dotted key (each part checks every prefix
of the key): 20,000 parts, a 41 KB line, take it seconds to minutes and gigabytes, and it only
learns how deep tables nest once it has built them. A preset needs little of either: its
deepest key is ``section.field`` or an inline table two levels down. So the text is scanned
first, in one pass that knows strings and comments but builds nothing, and refused with the
line and what is too long or too deep:

- a key (bare or quoted) of more than :data:`MAX_KEY_CHARS` characters;
- a key or table header of more than :data:`MAX_KEY_PARTS` dotted parts;
- arrays and inline tables nested more than :data:`MAX_NESTING` deep;
- more than :data:`MAX_KEYS` keys and table headers in all.

Text within the bounds is left to ``tomllib``, which reports any syntax error as before.
"""

from __future__ import annotations

import re

MAX_KEY_CHARS = 256  # the preset model's longest field name has 21 characters
MAX_KEY_PARTS = 16  # a preset's deepest key has 3 (``slo.error_values.range_sd``)
MAX_NESTING = 16  # arrays and inline tables; the io module refuses deeper data after parsing too
MAX_KEYS = 2_000  # keys and headers of one text (a whole preset written out has about a hundred)

_TOKEN = re.compile(r'''
    (?P<mlb>"""[^"\\]*(?:(?:\\.|"(?!""))[^"\\]*)*"""{1,3}) | (?P<mll>\'\'\'.*?\'\'\'{1,3})  # multi-line strings
  | (?P<basic>"[^"\\\n]*(?:\\.[^"\\\n]*)*"?) | (?P<literal>'[^'\n]*'?)       # one-line strings (maybe open)
  | (?P<comment>\#[^\n]*) | (?P<newline>\n)
  | (?P<bare>[A-Za-z0-9_\-+:]+(?:\.[0-9][A-Za-z0-9_\-+:]*)*)                 # keys, numbers, dates, words
  | (?P<punct>[\[\]{}=.,])
''', re.S | re.X)


class TomlBoundsError(ValueError):
    """TOML text beyond a bound; the message names the line and the bound."""


def check_toml(text: str) -> None:
    """Raise :class:`TomlBoundsError` if ``text`` is beyond a bound of the module doc (else None)."""
    line = 1
    stack: list[str] = []  # "[" array, "{" inline table, open in a value
    expect_key = True  # at the start of a line (outside values) or after "{" / "," in an inline table
    header = 0  # 1 on a table header's line
    parts = keys = 0
    for m in _TOKEN.finditer(text):
        kind, token = m.lastgroup, m.group()
        if kind in ("mlb", "mll"):
            line += token.count("\n")
            expect_key = False
            continue
        if kind == "comment":
            continue
        if kind == "newline":
            line += 1
            if not stack:
                expect_key, header = True, 0
            continue
        in_key = expect_key or header
        if in_key and kind in ("basic", "literal", "bare"):
            for piece in (token.split(".") if kind == "bare" else [token]):
                parts += 1
                if len(piece) > MAX_KEY_CHARS:
                    raise TomlBoundsError(f"a key of {len(piece):,} characters (line {line}); "
                                          f"a preset's keys have at most {MAX_KEY_CHARS}")
            if parts > MAX_KEY_PARTS:
                raise TomlBoundsError(f"a key of more than {MAX_KEY_PARTS} dotted parts (line {line}); "
                                      "a preset needs a few")
            continue
        if kind != "punct":
            expect_key = False
            continue
        if in_key and token == ".":
            continue
        if token == "[" and expect_key and not stack:  # a table header "[a.b]" or "[[a.b]]", to the line's end
            header, parts, keys, expect_key = 1, 0, keys + 1, False
            continue
        if header:
            continue
        if token == "=":
            keys += 1
            parts, expect_key = 0, False
            if keys > MAX_KEYS:
                raise TomlBoundsError(f"more than {MAX_KEYS:,} keys (line {line}); a preset has about a hundred")
            continue
        if token in "[{":
            stack.append(token)
            if len(stack) > MAX_NESTING:
                raise TomlBoundsError(f"nested deeper than {MAX_NESTING} levels (line {line}); a preset needs a few")
            expect_key = token == "{"
            parts = 0
        elif token in "]}":
            if stack:
                stack.pop()
            expect_key = False
        elif token == ",":
            expect_key = bool(stack) and stack[-1] == "{"
            parts = 0
