"""``station baseline ROBOT [SESSION] [--clear]``: a robot's phase II baseline."""

from __future__ import annotations

import argparse
from pathlib import Path

from station.errors import StationError
from station.text import format_figure


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station baseline``."""
    parser = subparsers.add_parser(
        "baseline",
        help="keep a capable session's control limits as a robot's baseline (phase II)",
        description=(
            "With SESSION: record that finished session of ROBOT, CAPABLE on every channel "
            "(Cpk's lower bound reaching the threshold; an INCONCLUSIVE one is refused with the "
            "readings that would settle it), as its baseline: the "
            "centre line and control limits of every channel (and the moving-range limit), "
            "with the session's id, anchor and date, in the user's data folder "
            "($XDG_DATA_HOME/station/baselines). Later sessions of ROBOT can test their live "
            "alarms against it, and `station history` marks it. Without SESSION: show the "
            "baseline. --clear removes it. SESSION is a session file, or a file name in the "
            "sessions folder."
        ),
    )
    parser.add_argument("robot", metavar="ROBOT", help="the robot's name as recorded")
    parser.add_argument("session", metavar="SESSION", nargs="?", help="the session file")
    parser.add_argument("--clear", action="store_true", help="remove ROBOT's baseline")
    parser.add_argument(
        "--sessions", metavar="DIR", help="sessions folder (default: STATION_SESSIONS, ...)"
    )
    parser.set_defaults(func=run)


def _session_path(text: str, sessions: str | None) -> Path:
    path = Path(text)
    if path.exists():
        return path
    from station.session.store import sessions_folder

    folder, _ = sessions_folder(sessions)
    candidate = folder / path.name
    if path.name == text and candidate.exists():
        return candidate
    raise StationError(f"{text}: no such session file (nor in {folder}); check the path.")


def run(args: argparse.Namespace) -> int:
    """Set, show or clear the baseline."""
    from station.record.baseline import baseline_for, clear_baseline, store_baseline
    from station.record.text import plain

    robot = args.robot
    if args.clear:
        if args.session:
            raise StationError("--clear takes no SESSION: it removes the robot's baseline.")
        removed = clear_baseline(robot)
        print(
            f"cleared the baseline of {plain(robot)}"
            if removed
            else f"{plain(robot)} had no baseline"
        )
        return 0
    if args.session:
        record = store_baseline(robot, _session_path(args.session, args.sessions))
        print(
            f"baseline of {plain(robot)}: session {record['session']} ({plain(record['file'])}), "
            f"anchor {record['anchor']}"
        )
    else:
        record = baseline_for(robot)
        if record is None:
            print(f"{plain(robot)} has no baseline; set one with `station baseline ROBOT SESSION`")
            return 0
        print(
            f"baseline of {plain(robot)}: session {record['session']} ({plain(record['file'])}), "
            f"created {record['date']}, anchor {record['anchor']}"
        )
    recorded = record.get("resolution")
    # A baseline filed before it recorded its gauge step: the figures at six decimals.
    resolution = float(recorded) if isinstance(recorded, int | float) and recorded > 0 else None
    for channel, spec in record["channels"].items():
        # The control lines are positions (signed), the moving range's limit a spread.
        shown = {
            k: "—" if spec[k] is None else format_figure(spec[k], resolution, signed=k != "mr_ucl")
            for k in spec
        }
        print(
            f"  {plain(channel)}: centre {shown['center']}  LCL {shown['lcl']}  "
            f"UCL {shown['ucl']}  MR UCL {shown['mr_ucl']}"
        )
    return 0
