"""Text from outside (robot and operator names, notes, reasons, frames, file names) in a report:
:func:`station.plain.plain` (the one sanitiser) makes control characters and bidirectional
overrides visible; Markup is each format's business (Jinja2 autoescapes HTML;
:func:`markdown_text` escapes Markdown).
"""

from __future__ import annotations

import re

from station.plain import plain

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
