"""Outside text in a report: control characters made visible, Markdown shown as text."""

from __future__ import annotations

import html

import pytest
from markdown_it import MarkdownIt

from station.record.text import markdown_text, plain

HOSTILE = [
    "# heading",
    "- item",
    "+ item",
    "1. first",
    "12) twelfth",
    "> quote",
    "===",
    "*bold* _em_ `code` [link](http://x) ![img](y)",
    "<script>alert(1)</script> &amp; | pipe ~~strike~~",
    "back\\slash",
    "-0.0003",
]


@pytest.mark.parametrize("text", HOSTILE)
def test_markdown_text_renders_as_the_text_itself(text):
    rendered = (
        MarkdownIt("commonmark")
        .enable(["table", "strikethrough"])
        .render(f"- {markdown_text(text)}\n")
    )
    assert rendered == f"<ul>\n<li>{html.escape(text, quote=False)}</li>\n</ul>\n"


def test_plain_makes_controls_and_bidi_visible():
    assert plain("a\x1b[2Jb\x07") == "a\\x1b[2Jb\\x07"
    assert plain("x\u202ey\u2066") == "x\\u202ey\\u2066"
    assert plain("line\nbreak\ttab") == "line\\nbreak\\ttab"
    assert plain("µm ±0.001 →") == "µm ±0.001 →"
