"""``station report FILE [--format txt|md|html] [-o OUT]``: a session's filed report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from station.commands._parser import output_name
from station.errors import StationError

FORMATS = ("txt", "md", "html")


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station report``."""
    parser = subparsers.add_parser(
        "report",
        help="a session's filed report: text, Markdown or HTML with charts",
        description=(
            "Write the filed report of a session file: robot, operator, procedure (id, version, "
            "sha256), date and duration, gauges, the zero taken, limits, every reading with the "
            "rejects and their reasons, notes, alarms with their acknowledgements, verdicts with "
            "Cpk's one-sided lower and upper confidence bounds (Bissell), each channel's "
            "measurement budget, hints, the anchor (the last line's hash) and "
            "sign-off lines. --format html is one self-contained page with the charts as inline "
            "SVG (histogram against the limits, control chart with the alarms, 3-D offsets, "
            "linearity profiles, readings over time). The session file is opened read-only."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="the session file (.jsonl)")
    parser.add_argument("--format", choices=FORMATS, default=None, help="txt (default), md or html")
    parser.add_argument(
        "-o",
        "--output",
        metavar="OUT",
        type=output_name,
        help="write to OUT instead of standard output (html needs it at a terminal)",
    )
    parser.add_argument("--force", action="store_true", help="overwrite OUT when it exists")
    parser.set_defaults(func=run)


def output_format(requested: str | None, output: str | None) -> str:
    """The format asked for, else the one OUT's suffix names (.md, .html/.htm), else txt."""
    if requested:
        return requested
    suffix = Path(output).suffix.lower() if output else ""
    return {".md": "md", ".markdown": "md", ".html": "html", ".htm": "html"}.get(suffix, "txt")


def run(args: argparse.Namespace) -> int:
    """Render the report; StationError for a bad session, or an OUT that is FILE, exists, is a
    link or cannot be written (see :func:`~station.commands._output.write_output_file`)."""
    from station.commands._output import check_output_file, write_output_file
    from station.record.render import render_report

    fmt = output_format(args.format, args.output)
    source = Path(args.file)
    if not args.output:
        if fmt == "html" and sys.stdout.isatty():
            # A page of inline SVG charts (some 170 KB) is no text to read at a terminal; a
            # pipe or a redirect still gets it.
            raise StationError(
                "an HTML report is a page for a browser, not for the terminal: "
                f"write it to a file with -o {source.with_suffix('.html').name}"
            )
        sys.stdout.write(render_report(source, fmt))
        return 0
    out = Path(args.output)
    # Checked before the report is rendered: a refused OUT costs nothing.
    check_output_file(out, force=args.force, source=source)
    text = render_report(source, fmt)
    write_output_file(out, lambda handle: handle.write(text), force=args.force, source=source)
    print(f"wrote the {fmt} report of {source.name} to {out}", file=sys.stderr)
    return 0
