"""``station verify FILE``: check a session file's hash chain and events, read-only."""

from __future__ import annotations

import argparse


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station verify``."""
    parser = subparsers.add_parser(
        "verify",
        help="check that a session file is intact (hash chain, events)",
        description=(
            "Check a session file without changing it: every line's hash, the chain of 'prev' "
            "hashes, the order of events, nothing after 'finish', and the finish's Ed25519 "
            "signature by the station key the header names. Prints the verdict, then the last "
            "line's hash (quote it in a report to anchor the file) and the key id. With --anchor "
            "HASH the file holds only when HASH is its last line's hash (nothing cut or added "
            "since the report). Exit 0 when intact, 1 naming the first bad line, 2 when the file "
            "is missing, unreadable or not a session file."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="the session file (.jsonl)")
    parser.add_argument(
        "--anchor",
        metavar="HASH",
        help="the last hash quoted on the filed report: the file holds only when it ends there",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the verdict; 0 intact, 1 damaged (StationError gives 2 for a missing file)."""
    from station.session.verify import verify_session

    result = verify_session(args.file, anchor=args.anchor)
    print(result.report)
    return 0 if result.ok else 1
