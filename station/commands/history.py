"""``station history ROBOT [--json]``: every session of a robot, its figures and wear trend."""

from __future__ import annotations

import argparse
import json
import sys


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station history``."""
    parser = subparsers.add_parser(
        "history",
        help="a robot's sessions over time: RP, offsets, sigma, Cpk, verdicts, wear trend",
        description=(
            "List every session of ROBOT (its exact name) in the sessions folder, oldest first: "
            "procedure, verdict, RP, per-channel mean offset, sigma and Cpk, and the anchor (the "
            "last line hash). Text charts of RP and Cpk over time follow, then the wear trend: "
            "per channel the slopes of the sessions' Cpk and means against the date with their "
            "95% confidence intervals and, only where Cpk's slope is significant, the date at "
            "which its trend line reaches the threshold, with a 95% range of dates. Sessions of "
            "the latest session's procedure and unit are trended. "
            "The robot's baseline session is marked."
        ),
    )
    parser.add_argument("robot", metavar="ROBOT", help="the robot's name as recorded")
    parser.add_argument(
        "--sessions", metavar="DIR", help="sessions folder (default: STATION_SESSIONS, ...)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the history; StationError (exit 2) when the robot has no session there."""
    from station.record.history import format_history, history_json, robot_history
    from station.session.store import sessions_folder

    folder, why = sessions_folder(args.sessions)
    history = robot_history(folder, args.robot)
    if args.json:
        print(json.dumps(history_json(history), indent=2, allow_nan=False))
        return 0
    print(f"sessions folder: {folder} ({why})", file=sys.stderr)
    print("\n".join(format_history(history)))
    return 0
