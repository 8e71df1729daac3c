"""``station export FILE --csv [-o OUT]``: a session's cycles as tidy CSV."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from station.commands._parser import output_name


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station export``."""
    parser = subparsers.add_parser(
        "export",
        help="export a session's readings as CSV",
        description=(
            "Write a session's readings as CSV. Tidy (repeatability's default): cycle, channel, "
            "value, unit, status (ok or 'rejected: <reason>'), time, then raw value, zero offset "
            "and placement; rejected cycles stay in the export, marked. Wide (the default for "
            "linearity, relative accuracy and the gauge linearity study): the table `station "
            "analyze --procedure NAME` reads, accepted readings only, rejected cycles named in "
            "'#' lines. `station analyze` reads both layouts. The session file is opened "
            "read-only."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="the session file (.jsonl)")
    parser.add_argument(
        "--csv", action="store_true", required=True, help="CSV output (the only format for now)"
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="OUT",
        type=output_name,
        help="write to OUT instead of standard output",
    )
    parser.add_argument(
        "--layout",
        choices=("auto", "tidy", "wide"),
        default="auto",
        help="tidy: one row per cycle and channel; wide: the table `station analyze` reads for "
        "the session's method (linearity: stroke,s,h,v; relative accuracy: "
        "cycle,placement,x,y,z,px,py,pz; gauge linearity: cycle,reference,value; else "
        "cycle,t,x,y,z of the accepted cycles); auto (default): the method's own choice (wide "
        "for linearity, relative accuracy and gauge linearity, tidy otherwise)",
    )
    parser.add_argument("--force", action="store_true", help="overwrite OUT when it exists")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Export; StationError for a missing session or an existing OUT without --force."""
    from station.commands._output import write_output_file
    from station.record.export import default_layout, export_table
    from station.session.model import load_session

    session = load_session(args.file, recover=False)
    if session.torn is not None:
        print(f"station: note: {session.torn.message}", file=sys.stderr)
    layout = default_layout(session) if args.layout == "auto" else args.layout

    if not args.output:
        export_table(session, sys.stdout, layout)
        return 0
    out = Path(args.output)
    # Synced before the rename and the folder after: OUT is whole or absent after a crash.
    # Never written through a link, and never over the session file itself.
    rows = write_output_file(
        out,
        lambda handle: export_table(session, handle, layout),
        force=args.force,
        source=Path(args.file),
    )
    print(f"wrote {rows} rows to {out}", file=sys.stderr)
    return 0
