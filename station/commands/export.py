"""``station export FILE --csv|--dfq [-o OUT]``: a session's readings as CSV (tidy or wide) or
as a Q-DAS AQDEF transfer file (DFQ)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TextIO

from station.commands._parser import output_name


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station export``."""
    parser = subparsers.add_parser(
        "export",
        help="export a session's readings as CSV or as a Q-DAS DFQ file",
        description=(
            "Write a session's readings as CSV. Tidy (repeatability's default): cycle, channel, "
            "value, unit, status (ok or 'rejected: <reason>'), time, then raw value, zero offset "
            "and placement; rejected cycles stay in the export, marked. Wide (the default for "
            "linearity, relative accuracy and the gauge linearity study): the table `station "
            "analyze --procedure NAME` reads, accepted readings only, rejected cycles named in "
            "'#' lines. `station analyze` reads both layouts. --dfq writes the Q-DAS AQDEF "
            "transfer format SPC software imports: the robot as the part (K1001, K1002), one "
            "characteristic per channel (K2001, K2002, decimals K2022, nominal K2101, limits "
            "K2110/K2111, unit K2142) and every reading with its date and time (K0001, K0004, "
            "UTC), the gauge id the session names (K0012) and a rejected cycle's values "
            "deactivated (K0002 255). The session file is opened read-only."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="the session file (.jsonl)")
    formats = parser.add_mutually_exclusive_group(required=True)
    formats.add_argument("--csv", action="store_true", help="CSV output (see --layout)")
    formats.add_argument(
        "--dfq", action="store_true", help="Q-DAS AQDEF transfer file (DFQ) for SPC software"
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
        "for linearity, relative accuracy and gauge linearity, tidy otherwise); CSV only",
    )
    parser.add_argument("--force", action="store_true", help="overwrite OUT when it exists")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Export; StationError for a missing session or an existing OUT without --force."""
    from station.commands._output import write_output_file
    from station.errors import StationError
    from station.record.dfq import write_dfq
    from station.record.export import default_layout, export_table
    from station.session.model import load_session

    if args.dfq and args.layout != "auto":
        raise StationError("--layout is a CSV layout; --dfq has one layout of its own.")
    session = load_session(args.file, recover=False)
    if session.torn is not None:
        print(f"station: note: {session.torn.message}", file=sys.stderr)
    layout = default_layout(session) if args.layout == "auto" else args.layout

    def write(handle: TextIO) -> int:
        return write_dfq(session, handle) if args.dfq else export_table(session, handle, layout)

    if not args.output:
        write(sys.stdout)
        return 0
    out = Path(args.output)
    # Synced before the rename and the folder after: OUT is whole or absent after a crash.
    # Never written through a link, and never over the session file itself.
    rows = write_output_file(out, write, force=args.force, source=Path(args.file))
    print(f"wrote {rows} {'values' if args.dfq else 'rows'} to {out}", file=sys.stderr)
    return 0
