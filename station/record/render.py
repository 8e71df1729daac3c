"""A session's filed report in text, Markdown or HTML, from one content model and Jinja2
templates shipped with the package (``station/record/templates``).

Every value a template prints passes through the format's escape (Jinja2's ``finalize``): plain
text with control characters made visible (txt), Markdown-escaped text (md), or HTML-escaped text
(html, autoescape on). The HTML report is one self-contained file: styles inline, charts as
inline SVG, no script and a Content-Security-Policy that allows nothing from outside.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from functools import cache
from pathlib import Path
from typing import Any

from jinja2 import Environment, PackageLoader, StrictUndefined
from markupsafe import Markup

from station.errors import StationError
from station.record.charts import report_charts
from station.record.content import ReportContent, build_content
from station.record.source import AnalysedSession, analyse_session
from station.record.text import markdown_text, plain

FORMATS = ("txt", "md", "html")
WIDTH = 80
"""The text report's width (its rules and wrapped sentences)."""


class _Trusted(str):
    """Text the report itself made (an SVG chart): printed as it is."""

    __slots__ = ()


@cache
def _environment(fmt: str) -> Any:
    def finalize(value: Any) -> Any:
        if isinstance(value, Markup):
            return value
        if isinstance(value, _Trusted):
            return Markup(str(value))
        if fmt == "md":
            return markdown_text(value)
        return plain(value)

    environment = Environment(
        loader=PackageLoader("station.record", "templates"),
        autoescape=fmt == "html",
        finalize=finalize,
        undefined=StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    environment.filters["ljust"] = lambda value, width: plain(value).ljust(int(width))
    # A long sentence (the verdict's basis) folded at the text report's width, each piece plain.
    environment.filters["wrap"] = lambda value, indent="": Markup(
        "\n".join(
            textwrap.wrap(
                plain(value),
                WIDTH,
                initial_indent=indent,
                subsequent_indent=indent + "  ",
                break_on_hyphens=False,
            )
        )
    )
    if fmt == "md":
        # Inside a Markdown code block or span nothing is markup: plain text without backticks.
        environment.filters["code"] = lambda value: Markup(plain(value).replace("`", "'"))
    return environment


def render_content(
    content: ReportContent, fmt: str, analysed: AnalysedSession | None = None
) -> str:
    """``content`` in ``fmt`` (txt, md or html); html draws its charts from ``analysed``."""
    if fmt not in FORMATS:
        raise StationError(f"unknown report format {fmt!r}; choose one of {', '.join(FORMATS)}.")
    charts = []
    if fmt == "html" and analysed is not None:
        charts = [
            {"key": c.key, "title": c.title, "svg": _Trusted(c.svg)}
            for c in report_charts(analysed)
        ]
    template = _environment(fmt).get_template(f"report.{fmt}.j2")
    return template.render(c=content, charts=charts)


def render_report(path: str | Path, fmt: str = "txt") -> str:
    """The filed report of the session file at ``path`` in ``fmt`` (txt, md or html): what
    ``station report`` writes."""
    return render_reports(path, (fmt,))[fmt]


def render_reports(path: str | Path, formats: Sequence[str]) -> dict[str, str]:
    """The filed report of the session file at ``path`` in each of ``formats``, from one
    reading and analysis of the file (the TUI's export files text and HTML at once)."""
    for fmt in formats:
        if fmt not in FORMATS:
            raise StationError(
                f"unknown report format {fmt!r}; choose one of {', '.join(FORMATS)}."
            )
    analysed = analyse_session(path)
    content = build_content(analysed)
    return {fmt: render_content(content, fmt, analysed) for fmt in formats}
