"""``station capture``'s set-up from its options: a new session's
:class:`~station.run.SessionSetup`, a resumed session's (refusing a set-up option that would
change it), the default trigger, and how a polled session is paced."""

from __future__ import annotations

import argparse
import getpass
import sys
from typing import Any

from station.commands._args import parse_limit, positive_number
from station.errors import StationError
from station.instruments.protocols import get_protocol
from station.text import parse_channel_map

_SETUP_OPTIONS = (
    ("--procedure", "procedure"),
    ("--robot", "robot"),
    ("--operator", "operator"),
    ("--cycles", "cycles"),
    ("--limit", "limit"),
    ("--trigger", "trigger"),
    ("--unit", "unit"),
    ("--resolution", "resolution"),
    ("--placements", "placements"),
    ("--strokes", "strokes"),
    ("--gauge", "gauge"),
)
"""The options that set a new session up; a resumed session keeps what its header records (the
same value again is accepted: a script may repeat its command line with ``--resume``)."""


def new_setup(args: argparse.Namespace) -> Any:
    """The session set-up from the flags (a new session)."""
    from station.analysis.capability import SpecLimits
    from station.record.baseline import header_baseline
    from station.run import PortSetup, SessionSetup

    missing = [
        flag
        for flag, value in (
            ("--procedure", args.procedure),
            ("--port", args.port),
            ("--protocol", args.protocol),
            ("--robot", args.robot),
        )
        if not value
    ]
    if missing:
        raise StationError(f"{', '.join(missing)} missing: a new session needs them (or --resume)")
    # Deferred: the methods load numpy (``station --help`` builds this command's parser).
    import station.methods  # noqa: F401 - procedure files name the methods
    from station.procedures import discover_procedures

    procedure = discover_procedures(args.procedures).get(args.procedure)
    limits = {}
    for text in args.limit:
        channel, lsl, usl = parse_limit(text)
        limits[channel] = SpecLimits(lsl=lsl, usl=usl)
    resolution = positive_number(args.resolution, "--resolution")
    if args.unit and args.unit != procedure.unit:
        # The procedure's resolution and limits are numbers in its own unit.
        unlimited = [channel for channel in procedure.limits if channel not in limits]
        if resolution is None or unlimited:
            needed = ["--resolution R"] if resolution is None else []
            needed += [f"--limit {channel}=LSL:USL" for channel in unlimited]
            raise StationError(
                f"--unit {args.unit}: procedure {procedure.id}'s resolution and limits are in "
                f"{procedure.unit}; give them in {args.unit}: {' '.join(needed)}"
            )
    return SessionSetup(
        procedure=procedure,
        robot=args.robot,
        operator=args.operator if args.operator is not None else getpass.getuser(),
        ports=(PortSetup(args.port, args.protocol, _channel_map(args, procedure.channels)),),
        trigger=args.trigger or default_trigger(procedure, args.protocol),
        unit=args.unit,
        resolution=resolution,
        limits=limits or None,
        cycles=positive_number(args.cycles, "--cycles", int) if args.cycles else None,
        placements=(
            positive_number(args.placements, "--placements", int) if args.placements else None
        ),
        strokes=positive_number(args.strokes, "--strokes", int) if args.strokes else None,
        # Live alarms test against the robot's baseline when it has one for this procedure.
        baseline=header_baseline(args.robot, procedure.id, args.unit or procedure.unit),
        gauges=_gauges(args.gauge, procedure.channels) or None,
    )


def _gauges(items: list[str], channels: tuple[str, ...]) -> dict[str, str]:
    """``--gauge CH=ID`` values: the gauge id on each channel."""
    gauges: dict[str, str] = {}
    for item in items:
        channel, equals, gauge = item.partition("=")
        if not equals or not gauge.strip() or channel.strip() not in channels:
            raise StationError(
                f"--gauge {item!r} is not CH=ID with CH one of {', '.join(channels)}; "
                "write e.g. --gauge x=MIT-0042"
            )
        gauges[channel.strip()] = gauge.strip()
    return gauges


def default_trigger(procedure: Any, protocol: str) -> str:
    """The trigger of a session without ``--trigger``: the procedure's own (the repeatability
    procedure declares ``arrival``) where the gauges can be read continuously (a polled
    protocol), else ``poll``."""
    if procedure.trigger and get_protocol(protocol).polled:
        return str(procedure.trigger)
    return "poll"


def _channel_map(args: argparse.Namespace, channels: tuple[str, ...]) -> dict[str, str]:
    return parse_channel_map(args.map) or {str(i): ch for i, ch in enumerate(channels, start=1)}


def resumed_setup(args: argparse.Namespace) -> Any:
    from station.run import PortSetup, recorded_setup, resume_setup

    # As recorded, for the comparison: the line is checked once it is the one to open.
    setup = recorded_setup(args.resume, procedures_dirs=args.procedures)
    conflicts = _resume_conflicts(args, setup)
    if conflicts:
        raise StationError(
            f"{', '.join(conflicts)} cannot change a resumed session: it continues as its "
            "header records; leave them out, or start a new session"
        )
    if not args.port:
        return resume_setup(args.resume, procedures_dirs=args.procedures)
    recorded = setup.ports[0] if setup.ports else None
    protocol = args.protocol or (recorded.protocol if recorded else None)
    if not protocol:
        raise StationError("--protocol missing: the session records no port to take it from")
    port = PortSetup(args.port, protocol, _channel_map(args, setup.channels))
    return resume_setup(args.resume, procedures_dirs=args.procedures, ports=(port,))


def _resume_conflicts(args: argparse.Namespace, setup: Any) -> list[str]:
    """The set-up options given with ``--resume`` whose value differs from the session's, each
    as ``--cycles 40 (the session's: 30)``."""
    recorded = {
        "procedure": setup.procedure.id,
        "robot": setup.robot,
        "operator": setup.operator,
        "cycles": setup.resolved_cycles,
        "trigger": setup.trigger,
        "unit": setup.resolved_unit,
        "resolution": setup.resolved_resolution,
        "placements": setup.placements,
        "strokes": setup.strokes,
    }
    conflicts = []
    for option, name in _SETUP_OPTIONS:
        given = getattr(args, name)
        if given in (None, []):
            continue
        if name == "limit":
            limits = setup.resolved_limits()
            for text in given:
                channel, lsl, usl = parse_limit(text)
                now = limits.get(channel)
                if now is None or (now.lsl, now.usl) != (lsl, usl):
                    was = f"{now.lsl}:{now.usl}" if now is not None else "none"
                    conflicts.append(f"--limit {text} (the session's: {channel}={was})")
            continue
        if name == "gauge":
            recorded_gauges = dict(setup.gauges or {})
            for text in given:
                channel, _, gauge = text.partition("=")
                if recorded_gauges.get(channel.strip()) != gauge.strip():
                    was = recorded_gauges.get(channel.strip(), "none")
                    conflicts.append(f"--gauge {text} (the session's: {channel.strip()}={was})")
            continue
        value = recorded[name]
        if name in ("cycles", "placements", "strokes"):
            same = value == positive_number(given, option, int)
        elif name == "resolution":
            same = value == positive_number(given, option)
        else:
            same = given == value
        if not same:
            was = "the procedure's" if value is None else value
            conflicts.append(f"{option} {given} (the session's: {was})")
    return conflicts


def pacing(trigger: str, every_text: str | None) -> tuple[float | None, bool]:
    """How a ``poll`` session paces its cycles: (``--every`` seconds, Enter at the terminal).
    Without either, polling would record a cycle as fast as the gauges answer (a gauge standing
    still, not a robot repeating): refused with the three ways to pace it."""
    every = positive_number(every_text, "--every") if every_text is not None else None
    if every is not None and trigger in ("push", "arrival"):
        who = "gauges" if trigger == "push" else "robot"
        raise StationError(
            f"--every paces --trigger poll; with --trigger {trigger} the {who} set the pace: "
            "leave --every out"
        )
    if trigger != "poll" or every is not None:
        return every, False
    if sys.stdin is not None and sys.stdin.isatty():
        return None, True
    raise StationError(
        "--trigger poll needs a pace: --every S (seconds between cycles), a terminal to press "
        "Enter in for each cycle, or --trigger push or arrival (the gauges or the robot set it)"
    )
