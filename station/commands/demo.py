"""``station demo``: a whole procedure against simulated instruments, no hardware.

It starts the procedure's simulator in this process on a pseudo-terminal (its method's
``demo_rig``: three indicators in a fixture for repeatability; two fixtures and a teach pendant
for relative accuracy; a parallel bar with indicators h, v and a linear scale s for linearity;
a three-joint arm for per-joint troubleshooting; ... every built-in procedure has one),
pre-fills the set-up with its port, channel map and trigger,
and writes the demo's session files to a ``demo`` folder under the sessions folder (said on
screen). Picking another procedure in the set-up starts that procedure's simulator. All are
seeded and deterministic. The repeatability robot moves: it leaves the fixture and comes back
every ``--cycle-period`` seconds (2 by default) and the station takes a cycle each time it is
back and still (the ``arrival`` trigger), as at a robot running its playback loop.
``--autopilot`` walks the procedure by itself (confirming the steps,
typing the pendant's coordinates, capturing every cycle or streaming every stroke at a watchable
pace, rejecting one cycle with a reason) and stops on the summary.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

DEMO_CYCLE_PERIOD = 2.0
"""Seconds per round trip of the demo's repeatability robot: the rhythm of a playback loop."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station demo``."""
    from station.commands.tui import add_common_arguments

    parser = subparsers.add_parser(
        "demo",
        help="try a whole procedure against simulated instruments (no hardware)",
        description="Runs the TUI against a simulated set-up on a pseudo-terminal: set-up, "
        "checklist, captures, verdict. Every built-in procedure has its own: repeatability: a "
        "fixture with three dial indicators, 30 cycles; relative_accuracy: two fixtures and a "
        "teach pendant, a few placements; linearity: a parallel bar with indicators h, v and a "
        "linear scale s, 30 strokes; gauge_check: an indicator over a surface plate and a gauge "
        "block; gauge_linearity: the same indicator and five gauge blocks over its travel; "
        "gage_rr: the same indicator, ten parts and three appraisers, one reading high and one "
        "low; joint_troubleshooting: a three-joint arm at the fixture, joint 2 noisy; "
        "gain_schedule: one joint and the gains its tuning gives at each position; "
        "pose_characteristics: one fixture at the five poses of the ISO 9283 test cube; "
        "positioning: a linear scale along an axis with backlash. A gauge study the demo runs "
        "is filed in the demo folder's own gauge register.",
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
        help="procedure id: repeatability, relative_accuracy, linearity, gauge_check, "
        "gauge_linearity, gage_rr, joint_troubleshooting, gain_schedule, pose_characteristics "
        "or positioning, each on its own simulated set-up (a site's procedure runs on its "
        "method's; `station procedures` lists them) (default: %(default)s)",
    )
    parser.add_argument(
        "--count",
        type=int,
        metavar="N",
        help="what the procedure's set-up counts, pre-filled: cycles (repeatability), fixture "
        "placements (relative_accuracy), strokes (linearity), trials (gage_rr), joints, "
        "positions, poses, masters or runs (default: the procedure's)",
    )
    parser.add_argument(
        "--seed", type=int, default=1990, help="simulator seed (default: %(default)s)"
    )
    parser.add_argument(
        "--cycle-period",
        type=float,
        default=DEMO_CYCLE_PERIOD,
        metavar="SECONDS",
        help="repeatability: the simulated robot leaves the fixture and comes back every so "
        "many seconds, and each return is a cycle (default: %(default)s)",
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
    from station.session.gauge_register import REGISTER_ENV
    from station.session.store import sessions_folder
    from station.tui.app import StationApp
    from station.tui.instruments import DemoLab

    if args.pace < 0:
        raise StationError(f"--pace must be 0 or more seconds, not {args.pace}")
    if args.count is not None and args.count < 1:
        raise StationError(f"--count must be 1 or more, not {args.count}")
    procedure = _demo_choice(args)
    folder, reason = sessions_folder(args.sessions)
    if not args.cycle_period > 0:
        raise StationError(f"--cycle-period must be more than 0 seconds, not {args.cycle_period}")
    # A gauge study the demo runs files itself in the demo's own gauge register, never in the
    # station's (a simulated indicator is no gauge of the site's).
    os.environ[REGISTER_ENV] = str(folder / "demo" / "gauges.json")
    lab = DemoLab(args.seed, cycle_period=args.cycle_period)
    try:
        config = demo_config(args, procedure, lab, folder, reason)
        return run_app(StationApp(config), mouse=args.mouse)
    finally:
        lab.stop()


def demo_config(
    args: argparse.Namespace, procedure: Any, lab: Any, folder: Path, reason: str
) -> Any:
    """The TUI's configuration for the demo of ``procedure``: its own simulated set-up from
    ``lab`` (a ``DemoLab``) pre-filling the set-up, the session files in ``folder``/demo."""
    from station.tui.app import DemoPort, StationConfig

    fixture = lab.fixture(procedure.analysis)
    return StationConfig(
        sessions_dir=folder / "demo",
        # The path above already names the folder: say only why it is this one.
        sessions_reason=f"the demo's own folder in the sessions folder, {reason}",
        procedure_dirs=tuple(Path(p) for p in args.procedures),
        demo=DemoPort(
            url=fixture.url,
            protocol=fixture.protocol,
            channel_map=fixture.channel_map,
            procedure=procedure.id,
            description=fixture.description,
            trigger=fixture.trigger,
            count=args.count,
        ),
        demo_lab=lab,
        autopilot=args.autopilot,
        autopilot_pace=args.pace,
    )


def _demo_choice(args: argparse.Namespace) -> Any:
    """The procedure asked for; one that does not exist, or a --count below what its set-up
    accepts, is refused here with a sentence (the TUI would open on it and wait forever)."""
    import station.methods  # noqa: F401 - procedure files name the methods
    from station.errors import StationError
    from station.procedures import discover_procedures
    from station.tui.screens.setup_form import count_field

    catalog = discover_procedures(args.procedures)
    if args.procedure not in catalog.ids():
        raise StationError(
            f"no procedure {args.procedure!r}; choose one of {', '.join(catalog.ids())}"
        )
    procedure = catalog.get(args.procedure)
    from station.tui.instruments import demo_methods

    if procedure.analysis not in demo_methods():
        # Its readings would come from another method's simulator: a demo of nothing.
        raise StationError(
            f"{args.procedure} has no simulated set-up in the demo yet: run it headless "
            f"against `station simulate` with `station capture --procedure {args.procedure}` "
            "(procedures/README.md), or choose one of "
            + ", ".join(i for i in catalog.ids() if catalog.get(i).analysis in demo_methods())
        )
    if args.count is not None:
        count = count_field(procedure)
        # A demo may be a short trial run (the set-up says the report's range), but not one
        # the procedure's method cannot judge.
        if args.count < count.minimum:
            raise StationError(
                f"--count {args.count} is too few for {args.procedure}: "
                f"give at least {count.minimum} {count.noun}"
            )
    return procedure
