"""``station compare A B [--json]``: two sessions of one procedure, before and after."""

from __future__ import annotations

import argparse
import json

from station.commands._args import parse_number
from station.errors import StationError


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station compare``."""
    parser = subparsers.add_parser(
        "compare",
        help="compare two sessions (before/after an adjustment): shifts, spreads, RP, 3-D",
        description=(
            "Compare session A (before) with session B (after), channel by channel: the mean "
            "shift B - A with its t test and confidence interval (Welch's; where each session "
            "took its own zero, each zero's rest-to-rest uncertainty, from the session's own "
            "spread and the zero's readings, is counted in, and the sentence says when the "
            "zeros make up most of the shift), the spread ratio "
            "sigma_B/sigma_A with its F-test interval and the Brown-Forsythe (Levene, median) "
            "test, a plain sentence per channel; the 3-D shift of the mean of x, y, z with "
            "Hotelling's T2; the change of RP. Holm's procedure holds the chance of calling any "
            "unchanged channel changed at 1 - confidence (5%); a sentence says when Holm's "
            "correction made the call. Sessions of different procedures "
            "or units are refused."
        ),
    )
    parser.add_argument("a", metavar="A", help="the session before (.jsonl)")
    parser.add_argument("b", metavar="B", help="the session after (.jsonl)")
    parser.add_argument(
        "--confidence", metavar="C", default="0.95", help="confidence level (default 0.95)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the comparison; StationError (exit 2) for sessions that cannot be compared."""
    from station.record.compare import compare_sessions, comparison_json
    from station.record.text import plain

    confidence = parse_number(args.confidence, "--confidence")
    if confidence is None or not 0.5 <= confidence < 1:
        raise StationError(f"--confidence {args.confidence!r} must be between 0.5 and 1.")
    comparison = compare_sessions(args.a, args.b, confidence=confidence)
    if args.json:
        print(json.dumps(comparison_json(comparison), indent=2, allow_nan=False))
        return 0
    print(f"A (before): {plain(comparison.a)}")
    print(f"B (after):  {plain(comparison.b)}")
    print(f"Procedure {plain(comparison.procedure)}, unit {plain(comparison.unit)}")
    print()
    for sentence in comparison.sentences:
        print(plain(sentence))
    return 0
