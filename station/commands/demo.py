"""``station demo``: the whole repeatability procedure against simulated indicators.

It starts the simulator in this process on a pseudo-terminal, pre-fills the set-up with its
port, and writes the demo's session files to a ``demo`` folder under the sessions folder (said on
screen). ``--autopilot`` walks the procedure by itself (confirming the steps, capturing every
cycle at a watchable pace, rejecting one cycle with a reason) and stops on the summary.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station demo``."""
    from station.commands.tui import add_common_arguments

    parser = subparsers.add_parser(
        "demo",
        help="try the whole procedure against simulated dial indicators (no hardware)",
        description="Runs the TUI against a simulated robot in a fixture with three dial "
        "indicators on a pseudo-terminal: set-up, checklist, 30 cycles, verdict.",
    )
    parser.add_argument(
        "--autopilot",
        action="store_true",
        help="walk the procedure by itself and stop on the summary (for showcases and tests)",
    )
    parser.add_argument(
        "--procedure",
        default="repeatability",
        metavar="ID",
        help="procedure id (default: %(default)s)",
    )
    parser.add_argument(
        "--seed", type=int, default=1990, help="simulator seed (default: %(default)s)"
    )
    parser.add_argument(
        "--pace",
        type=float,
        default=0.2,
        metavar="SECONDS",
        help="autopilot: seconds between two actions (default: %(default)s)",
    )
    add_common_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Start the simulated fixture, then the TUI on a demo sessions folder."""
    from station.commands.tui import run_app
    from station.errors import StationError
    from station.session.store import sessions_folder
    from station.tui.app import DemoPort, StationApp, StationConfig
    from station.tui.instruments import start_demo_fixture

    if args.pace < 0:
        raise StationError(f"--pace must be 0 or more seconds, not {args.pace}")
    folder, reason = sessions_folder(args.sessions)
    fixture = start_demo_fixture(args.seed)
    try:
        config = StationConfig(
            sessions_dir=folder / "demo",
            sessions_reason=f"the demo folder under {folder} ({reason})",
            procedure_dirs=tuple(Path(p) for p in args.procedures),
            demo=DemoPort(
                url=fixture.url,
                protocol=fixture.protocol,
                channel_map=fixture.channel_map,
                procedure=args.procedure,
            ),
            autopilot=args.autopilot,
            autopilot_pace=args.pace,
        )
        return run_app(StationApp(config), mouse=args.mouse)
    finally:
        fixture.stop()
