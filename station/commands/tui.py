"""``station tui``: the terminal user interface (also what a bare ``station`` runs).

Mouse reporting is off unless ``--mouse``: every pointer move would cross a slow SSH link, and
Textual 8.2.8 can crash on a terminal rebuilt under it (textual #6668) — the operator uses the
keyboard anyway. Exit codes: 0 after a normal quit; 129 after SIGHUP and 143 after SIGTERM (the
running session is then marked interrupted and offered for resume on the next start).
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_common_arguments(parser: argparse.ArgumentParser) -> None:
    """The options ``station tui`` and ``station demo`` share."""
    mouse = parser.add_mutually_exclusive_group()
    mouse.add_argument(
        "--mouse", action="store_true", help="enable the mouse (off by default: safer over SSH)"
    )
    mouse.add_argument(
        "--no-mouse", action="store_true", help="keep the mouse off (the default; accepted)"
    )
    parser.add_argument(
        "--sessions",
        metavar="DIR",
        help="sessions folder (default: STATION_SESSIONS, ./sessions, or the user's data folder)",
    )
    parser.add_argument(
        "--procedures",
        metavar="DIR",
        action="append",
        default=[],
        help="a folder of the site's own procedures (repeatable; also STATION_PROCEDURES)",
    )


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station tui``."""
    parser = subparsers.add_parser(
        "tui",
        help="the terminal user interface (the default command)",
        description="Guided acquisition from set-up to verdict: new session, resume, review. "
        "Everything works by keyboard; every key is in the footer; F1 or ? shows help.",
    )
    add_common_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Open the TUI on the sessions folder; returns its exit code."""
    from station.session.store import sessions_folder
    from station.tui.app import StationApp, StationConfig

    folder, reason = sessions_folder(args.sessions)
    config = StationConfig(
        sessions_dir=folder,
        sessions_reason=reason,
        procedure_dirs=tuple(Path(p) for p in args.procedures),
    )
    return run_app(StationApp(config), mouse=args.mouse)


def run_app(app: object, *, mouse: bool) -> int:
    """Run the app in the terminal and return its exit code."""
    result = app.run(mouse=mouse)  # type: ignore[attr-defined]
    code = app.return_code  # type: ignore[attr-defined]
    if code is None:
        code = result if isinstance(result, int) else 0
    return int(code)
