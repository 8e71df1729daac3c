"""Text from outside (robot and operator names, notes, reasons, frames, file names) made safe to
show in a report: control characters and bidirectional overrides become visible escapes.

Markup is each format's business (Jinja2 autoescapes HTML; :func:`markdown_text` escapes
Markdown); this module only makes sure no byte steers a terminal or reorders a line.
"""

from __future__ import annotations

import re
import unicodedata

# Bidi embedding/override/isolate controls and marks: they reorder what a reader sees.
_BIDI = set("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u200e\u200f\u061c")


def _visible(character: str) -> str:
    code = ord(character)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}"


def plain(value: object) -> str:
    """``value`` as one line of plain text: control characters (C0, C1, DEL, line and paragraph
    separators) and bidi controls shown as ``\\xNN`` / ``\\uNNNN``; other text unchanged."""
    text = str(value)
    return "".join(
        _visible(c)
        if c in _BIDI or (unicodedata.category(c) in ("Cc", "Zl", "Zp") and c != "\t")
        else c
        for c in text
    ).replace("\t", " ")


_MARKDOWN_INLINE = re.compile(r"([\\`*_\[\]|~])")
# At the start of a table cell or list item these would open a block (heading, quote, list).
_MARKDOWN_LEADING = re.compile(r"^(\s*(?:\d+)?)([#>=]|[-+.)](?=\s|$))")


def markdown_text(value: object) -> str:
    """:func:`plain` text escaped for Markdown: characters that could open inline markup are
    backslash-escaped, a leading block marker too, and ``<``, ``&`` become entities, so a
    standard parser shows the text as it is (a robot named ``<script>`` stays text)."""
    text = plain(value).replace("&", "&amp;").replace("<", "&lt;")
    text = _MARKDOWN_INLINE.sub(r"\\\1", text)
    return _MARKDOWN_LEADING.sub(r"\1\\\2", text)
