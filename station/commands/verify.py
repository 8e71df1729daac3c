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
            "signature by the station key the header names, which must be in this station's "
            "trust store (its own key and those added with `station keys trust`). Prints the "
            "verdict, the key that signed, then the last line's hash (quote it in a report to "
            "anchor the file). With --anchor HASH the file holds only when HASH is its last "
            "line's hash (nothing cut or added since the report). An unsigned session passes "
            "only when its header dates it before stations signed. Exit 0 when intact and "
            "signed by a trusted key, 1 naming the first bad line or saying why no trusted key "
            "vouches for it, 2 when the file is missing, unreadable or not a session file."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="the session file (.jsonl)")
    parser.add_argument(
        "--anchor",
        metavar="HASH",
        help="the last hash quoted on the filed report: the file holds only when it ends there",
    )
    parser.add_argument(
        "--allow-unsigned",
        action="store_true",
        help="pass an unsigned session dated after stations began signing (says so)",
    )
    parser.add_argument(
        "--trust-any",
        action="store_true",
        help="pass a session signed by a key not in the trust store (says so)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the verdict; 0 intact and vouched for, 1 damaged or not vouched for
    (StationError gives 2 for a missing file)."""
    from station.session.verify import verify_session

    result = verify_session(
        args.file,
        anchor=args.anchor,
        allow_unsigned=args.allow_unsigned,
        trust_any=args.trust_any,
    )
    print(result.report)
    return 0 if result.ok else 1
