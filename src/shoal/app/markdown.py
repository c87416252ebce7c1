"""Text that is not the app's own, shown in viser markdown: escaped, so it shows as written.

Viser renders a markdown element with raw HTML and no sanitiser: ``<img onerror=…>`` or an
``<iframe srcdoc>`` in its content runs script in the page. A preset's ``name``, a replay's
metadata, a file name, a refused value echoed in a message or a field's description are
written by whoever made the file or the request, not by the app. Every such text reaches a
markdown element through :func:`escape` (the one helper; ``tests/test_markdown_escaped.py``
scans the app for f-strings and ``format`` calls into markdown content that bypass it):

- ``&``, ``<``, ``>``, ``"`` and ``'`` become character references, so nothing is a tag or
  leaves an attribute, in a markdown paragraph or inside the app's own raw HTML;
- every other ASCII punctuation character is backslash-escaped (CommonMark's escape), so no
  ``*``, ``_``, ``[``, ``#``, `````, ``|`` or ``:`` starts emphasis, a link, a heading, code or a
  table;
- line breaks and other control characters become spaces (a name stays on its line), and a
  text longer than ``limit`` characters is cut with an ellipsis;
- no URL, ``www.`` address or e-mail address becomes a link: viser's markdown has GFM's
  autolinks (remark-gfm), which find them in the text *after* escapes are read, so a word
  joiner (U+2060, invisible, no line break) follows every ``:`` and ``@`` and each ``www``
  before a dot, and ``https://``, ``a@b.org`` or ``www.x.org`` then match none of its patterns;
- a lone surrogate (JSON's ``"\ud800"``) becomes U+FFFD, so the text is UTF-8 encodable and
  msgpack can send it (:func:`shoal.presets.text.encodable`).

Markdown the project writes itself (the shipped notes and lessons, and literals in the code)
is not escaped: it is meant as markdown.
"""

from __future__ import annotations

import re

from shoal.presets.text import encodable

__all__ = ["MAX_SHOWN", "encodable", "escape"]

MAX_SHOWN = 300  # characters of one escaped text, by default (a replay's name may be 1 MiB long)

_CONTROL = re.compile(r"[\x00-\x1f\x7f\u0085\u2028\u2029]+")
_PUNCTUATION = re.compile(r"([!#$%()*+,\-./:;=?@\[\\\]^_`{|}~])")  # ASCII punctuation but & < > " '
_REFERENCES = {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;"}
_REFERENCE = re.compile("[&<>\"']")
JOINER = "\u2060"  # WORD JOINER: breaks an autolink's pattern, shows nothing
_AUTOLINK = re.compile(r"([:@])|(?i:(www)(?=\.))")  # a scheme's or an address's ':', an e-mail's '@', "www."


def escape(value: object, limit: int | None = MAX_SHOWN) -> str:
    """``value`` as text that viser's markdown shows literally (see the module doc); ``limit``:
    the most characters kept (None: all)."""
    text = _CONTROL.sub(" ", encodable(str(value)))
    if limit is not None and len(text) > limit:
        text = text[: max(limit - 1, 0)] + "…"
    text = _AUTOLINK.sub(lambda m: (m.group(1) or m.group(2)) + JOINER, text)
    text = _PUNCTUATION.sub(r"\\\1", text)
    return _REFERENCE.sub(lambda m: _REFERENCES[m.group()], text)
