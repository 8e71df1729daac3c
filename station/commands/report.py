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
            "the lower confidence bound of Cpk, hints, the anchor (the last line's hash) and "
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
        help="write to OUT instead of standard output",
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
    """Render the report; StationError for a bad session, an OUT that is FILE or exists."""
    from station.record.render import render_report

    fmt = output_format(args.format, args.output)
    source = Path(args.file)
    if not args.output:
        sys.stdout.write(render_report(source, fmt))
        return 0
    out = Path(args.output)
    if out.exists() and source.exists() and out.resolve() == source.resolve():
        raise StationError(f"{out} is the session file itself; choose another name for the report")
    if out.is_symlink():
        raise StationError(f"{out} is a symbolic link; give a plain file name for the report")
    if out.exists() and not args.force:
        raise StationError(f"{out} exists; pass --force to overwrite it or choose another name")
    text = render_report(source, fmt)
    from station.session.durable import replace_durably

    try:
        replace_durably(out, lambda handle: handle.write(text))
    except OSError as error:
        raise StationError(f"cannot write {out}: {error.strerror}") from None
    print(f"wrote the {fmt} report of {source.name} to {out}", file=sys.stderr)
    return 0
