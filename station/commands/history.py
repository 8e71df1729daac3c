"""``station history ROBOT [--json]``: every session of a robot, its figures and wear trend;
``station history --all``: one line per robot."""

from __future__ import annotations

import argparse
import json
import sys

from station.errors import StationError


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
            "The robot's baseline session is marked. With --all instead of ROBOT: one line per "
            "robot, its latest session's date, verdict, RP and lowest Cpk, and its trend in a "
            "word. The figures of files unchanged since the last run come from the session "
            "index in the station's data folder (a cache; the files stay the truth)."
        ),
    )
    parser.add_argument("robot", metavar="ROBOT", nargs="?", help="the robot's name as recorded")
    parser.add_argument(
        "--all", action="store_true", help="one line per robot of the sessions folder"
    )
    parser.add_argument(
        "--sessions", metavar="DIR", help="sessions folder (default: STATION_SESSIONS, ...)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the history; StationError (exit 2) when the robot has no session there."""
    from station.record.history import (
        fleet_history,
        fleet_json,
        format_fleet,
        format_history,
        history_json,
        robot_history,
    )
    from station.record.index import SessionIndex
    from station.session.store import sessions_folder

    if args.all == (args.robot is not None):
        raise StationError(
            "give a robot's name (station history ROBOT) or --all (every robot), not both"
            if args.all
            else "name the robot (station history ROBOT), or give --all for every robot"
        )
    folder, why = sessions_folder(args.sessions)
    with SessionIndex.open() as index:
        try:
            if args.all:
                fleet = fleet_history(folder, index=index)
                document, lines = fleet_json(fleet), format_fleet(fleet)
            else:
                history = robot_history(folder, args.robot, index=index)
                document, lines = history_json(history), format_history(history)
        finally:
            for warning in index.warnings:
                print(f"station: warning: {warning}", file=sys.stderr)
    if args.json:
        print(json.dumps(document, indent=2, allow_nan=False))
        return 0
    print(f"sessions folder: {folder} ({why})", file=sys.stderr)
    print("\n".join(lines))
    return 0
