"""``station analyze FILE``: the report's statistics of a CSV table or a session file."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.commands._args import parse_number
from station.errors import StationError
from station.procedures import ANALYSIS_KINDS

if TYPE_CHECKING:
    from station.analysis.summary import AnalysisConfig

RULE_CHOICES = ("report", "western-electric", "nelson")
LINEARITY_COLUMNS = ("stroke", "s", "h", "v")
ACCURACY_COLUMNS = ("placement", "x", "y", "z")
PENDANT_COLUMNS = ("px", "py", "pz")

DESCRIPTION = """\
Analyse readings the way the 1990 NASA/KSC report does: maximum, average,
minimum, sigma, skewness, range, mode, histogram, control chart with run rules,
Cp/Cpu/Cpl/Cpk and the verdict. FILE is a CSV table (a header row, '#' comment
lines, one numeric column per channel; columns named cycle, subgroup or t are
not channels) or a session file (.jsonl).

--procedure linearity reads a CSV with columns stroke, s, h, v (one row per
streamed point) and adds the straightness per stroke (least squares and minimum
zone of h and v against s), per direction, the path repeatability along the bar
and the capability of the straightness against --tolerance. --procedure
relative_accuracy reads columns placement, x, y, z (optionally the teach
pendant's px, py, pz) and adds the accuracy per placement and across
placements. A session file is analysed as its procedure declares (its
`analysis`) unless --procedure says otherwise.

exit codes:
  0  analysed
  1  with --fail-if-incapable: a channel is not capable, or has no verdict (no
     limits)
  2  bad input: missing or empty file, a cell that is not a number, impossible
     limits
"""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station analyze``."""
    parser = subparsers.add_parser(
        "analyze",
        help="statistics, control chart and capability verdict of a CSV or session file",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", help="CSV table of readings or session file")
    # Numbers are taken as text and parsed in run() so that a bad value is the same one-line
    # "station: ..." error as every other bad input, not argparse's usage block.
    parser.add_argument("--lsl", metavar="V", help="lower specification limit, all channels")
    parser.add_argument("--usl", metavar="V", help="upper specification limit, all channels")
    parser.add_argument(
        "--limit",
        metavar="CH=LSL:USL",
        action="append",
        default=[],
        help="limits of one channel (repeatable); leave a side empty for a one-sided "
        "limit, e.g. x=:0.001",
    )
    parser.add_argument(
        "--resolution", metavar="R", help="gauge resolution (mode and histogram bins)"
    )
    parser.add_argument(
        "--subgroup",
        metavar="N",
        default="1",
        help="consecutive readings per subgroup (default 1: I-MR chart)",
    )
    parser.add_argument(
        "--rules",
        choices=RULE_CHOICES,
        help="run rules on the control chart (default: the session's, else the report's four)",
    )
    parser.add_argument(
        "--capable-at",
        metavar="C",
        help="Cpk at or above which a channel is capable (default: the session's, else 1.0)",
    )
    parser.add_argument("--unit", default="", help="unit of the readings, for the report")
    parser.add_argument(
        "--procedure",
        choices=ANALYSIS_KINDS,
        metavar="KIND",
        help=f"what FILE holds: {', '.join(ANALYSIS_KINDS)} (default: the analysis a "
        "session's procedure declares, else repeatability)",
    )
    parser.add_argument(
        "--tolerance",
        metavar="T",
        help="linearity: straightness tolerance, the zone width per stroke (default: the "
        "session's, from its h/v limits)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument(
        "--fail-if-incapable",
        action="store_true",
        help="exit 1 when any channel is not capable",
    )
    parser.set_defaults(func=run)


def parse_limit(text: str) -> tuple[str, float | None, float | None]:
    """Split ``CH=LSL:USL`` (either side may be empty) into channel, lsl, usl."""
    channel, equals, bounds = text.partition("=")
    lsl_text, colon, usl_text = bounds.partition(":")
    if not equals or not colon or not channel.strip():
        raise StationError(
            f"--limit {text!r} is not CH=LSL:USL; write e.g. --limit x=-0.001:0.001 "
            "(or x=:0.001 for an upper limit only)."
        )
    lsl = parse_number(lsl_text, f"--limit {channel.strip()} lower limit")
    usl = parse_number(usl_text, f"--limit {channel.strip()} upper limit")
    if lsl is None and usl is None:
        raise StationError(f"--limit {text!r} gives neither a lower nor an upper limit.")
    return channel.strip(), lsl, usl


def is_session_file(path: Path) -> bool:
    """True when the file begins like a station session file (or it is named .jsonl)."""
    from station.session.model import looks_like_session

    if path.suffix.lower() == ".jsonl":
        return True
    try:
        with path.open("rb") as stream:
            first = stream.readline(65536)
    except OSError:
        return False
    return looks_like_session(first)


@dataclass
class Source:
    """What a file gives the analysis: channels, and for a session its recorded settings."""

    channels: dict[str, Any]
    cycles: dict[str, Any] | None = None  # the cycle number of each reading, per channel
    excluded_cycles: tuple[int, ...] = ()
    config: AnalysisConfig | None = None  # a session's recorded limits, resolution, unit, rules
    notes: tuple[str, ...] = ()
    analysis: str | None = None  # a session's analysis kind (see session_analysis)
    session: Any = None  # the replayed session (station.session.model.Session)
    table: Any = None  # the CSV table (station.session.tables.ReadingTable)


def load_session_source(path: Path) -> Source:
    """Channels of a session file (rejected cycles left out) and its recorded settings."""
    from station.runner import analysis_config
    from station.session.model import load_session

    session = load_session(path, recover=False)
    notes = [
        f"Session {session.session_id}: robot {session.robot}, operator "
        f"{session.operator or 'not given'}, procedure {session.procedure_id}, "
        f"created {session.created}, {session.status}.",
        f"Last line hash (anchors the session file): {session.last_hash}",
    ]
    if session.torn is not None:
        notes.append(f"Torn tail: {session.torn.message}")
    channels = {name: values for name, values in session.channel_values().items() if len(values)}
    cycles = session.channel_cycles()
    return Source(
        channels=channels,
        cycles={name: cycles[name] for name in channels},
        excluded_cycles=tuple(session.excluded_cycles),
        # The same settings the live analysis of the running session used.
        config=analysis_config(session.header),
        notes=tuple(notes),
        analysis=session_analysis(session),
        session=session,
    )


def session_analysis(session: Any) -> str:
    """How to analyse a session: the analysis its header records for its procedure; else that
    of the same procedure file (id and sha256) where this machine has it; else what the
    session holds, as a procedure's default follows its steps (streamed strokes: linearity;
    captures at fixture placements: relative accuracy; otherwise repeatability)."""
    from station.procedures import discover_procedures

    recorded = session.header["procedure"]
    if recorded.get("analysis") in ANALYSIS_KINDS:
        return str(recorded["analysis"])
    try:
        catalog = discover_procedures()
        procedure = next(
            (
                p
                for p in catalog.procedures
                if p.id == recorded.get("id") and p.sha256 == recorded.get("sha256")
            ),
            None,
        )
    except StationError:  # a STATION_PROCEDURES folder that is gone: judge by the content
        procedure = None
    if procedure is not None:
        return procedure.analysis
    if session.samples:
        return "linearity"
    if any(cycle.placement is not None for cycle in session.cycles.values()):
        return "relative_accuracy"
    return "repeatability"


def load_source(path: Path) -> Source:
    """A session file (detected by its header) or a CSV table of readings."""
    if path.is_file() and is_session_file(path):
        return load_session_source(path)
    from station.session.tables import read_table

    table = read_table(path)
    cycles = None if table.cycles is None else dict.fromkeys(table.channels, table.cycles)
    return Source(channels=table.channels, cycles=cycles, table=table)


def linearity_profiles(source: Source, path: Path) -> list[Any]:
    """The strokes of a linearity CSV (columns stroke, s, h, v) or session (samples events)."""
    import numpy as np

    from station.analysis.linearity import profiles_from_stream, profiles_from_table

    if source.table is not None:
        from station.session.tables import require_columns

        columns = require_columns(source.table, LINEARITY_COLUMNS, "a linearity table")
        return profiles_from_table(
            columns["stroke"], columns["s"], {"h": columns["h"], "v": columns["v"]}
        )
    batches = [b for b in source.session.samples if {"s", "h", "v"} <= set(b.channels)]
    # A runner marks the last event of each whole stroke (`end`); a lead-in or a stroke cut
    # short by an interruption has no mark and is left out. Files without marks: every stroke.
    ended = {event["seq"] for event in source.session.events if event.get("end")}
    if ended:
        whole = {b.stroke for b in batches if b.seq in ended}
        batches = [b for b in batches if b.stroke in whole]
    if not batches:
        raise StationError(
            f"{path}: the session has no streamed strokes (samples events with h, v and s) "
            "to analyse yet."
        )
    arrays = [b.as_arrays() for b in batches]
    joined = {c: np.concatenate([a[c] for a in arrays]) for c in ("s", "h", "v")}
    if all(b.stroke is not None for b in batches):
        numbers = np.concatenate(
            [np.full(len(a["s"]), b.stroke) for a, b in zip(arrays, batches, strict=True)]
        )
        return profiles_from_table(numbers, joined["s"], {"h": joined["h"], "v": joined["v"]})
    # Batches without stroke numbers are one stream: split it by the scale's travel.
    return profiles_from_stream(joined["s"], {"h": joined["h"], "v": joined["v"]})


def accuracy_inputs(source: Source) -> tuple[Any, dict[str, Any], dict[int, tuple[float, ...]]]:
    """Placements, errors x, y, z and pendant coordinates of an accuracy CSV or session."""
    import numpy as np

    if source.table is not None:
        from station.session.tables import require_columns

        columns = require_columns(source.table, ACCURACY_COLUMNS, "a relative-accuracy table")
        pendant: dict[int, tuple[float, ...]] = {}
        lowered = {name.lower() for name in source.table.channels}
        if set(PENDANT_COLUMNS) <= lowered:
            coordinates = require_columns(source.table, PENDANT_COLUMNS, "the pendant")
            for row, number in enumerate(columns["placement"]):
                pendant.setdefault(int(number), tuple(coordinates[c][row] for c in PENDANT_COLUMNS))
        errors = {axis: columns[axis] for axis in ("x", "y", "z")}
        return columns["placement"], errors, pendant
    session = source.session
    numbers = [n for n in session.accepted_cycles if session.cycles[n].placement is not None]
    if not numbers:
        raise StationError(
            f"{session.path}: the session has no accepted readings at a fixture placement yet."
        )
    errors = {
        axis: np.asarray([session.cycles[n].readings[axis].value for n in numbers])
        for axis in ("x", "y", "z")
        if all(axis in session.cycles[n].readings for n in numbers)
    }
    pendant = {}
    for event in session.input_events:
        values, placement = event.get("values") or {}, event.get("placement")
        if isinstance(placement, int) and all(
            isinstance(values.get(axis), int | float) for axis in ("x", "y", "z")
        ):
            pendant[placement] = tuple(float(values[axis]) for axis in ("x", "y", "z"))
    placements = np.asarray([session.cycles[n].placement for n in numbers])
    return placements, errors, pendant


def run(args: argparse.Namespace) -> int:
    """Analyse FILE and print the text report or the JSON document."""
    from station.analysis.capability import SpecLimits
    from station.analysis.report import format_report
    from station.analysis.summary import AnalysisConfig, analyze, to_json

    path = Path(args.file)
    lsl = parse_number(args.lsl, "--lsl")
    usl = parse_number(args.usl, "--usl")
    resolution = parse_number(args.resolution, "--resolution")
    threshold = parse_number(args.capable_at, "--capable-at")
    try:
        subgroup = int(args.subgroup)
    except ValueError:
        raise StationError(f"--subgroup {args.subgroup!r} is not a whole number.") from None
    per_channel = [parse_limit(text) for text in args.limit]

    source = load_source(path)
    channels = source.channels
    for channel, _, _ in per_channel:
        if channel not in channels:
            raise StationError(
                f"--limit names channel {channel!r}, which is not in {path} "
                f"(channels: {', '.join(channels)})."
            )
    # The command line overrides what a session file recorded.
    recorded = source.config or AnalysisConfig()
    limits = dict(recorded.limits)
    default_limits = recorded.default_limits
    if lsl is not None or usl is not None:
        default_limits = SpecLimits(lsl=lsl, usl=usl)
        limits = {}
    limits.update({channel: SpecLimits(lsl=lo, usl=hi) for channel, lo, hi in per_channel})
    config = replace(
        recorded,
        limits=limits,
        default_limits=default_limits,
        resolution=recorded.resolution if resolution is None else resolution,
        unit=args.unit or recorded.unit,
        subgroup=subgroup,
        rule_set=args.rules or recorded.rule_set,
        threshold=recorded.threshold if threshold is None else threshold,
    )
    procedure = args.procedure or source.analysis or "repeatability"
    tolerance = parse_number(args.tolerance, "--tolerance")
    if tolerance is not None and not tolerance > 0:
        raise StationError(f"--tolerance {args.tolerance!r} must be greater than 0.")
    if tolerance is not None and procedure != "linearity":
        raise StationError("--tolerance is the straightness tolerance of --procedure linearity.")
    title = f"BASIC STATISTICS COMPREHENSIVE REPORT ON {path.name}"
    document: dict[str, Any]
    if procedure == "linearity":
        from station.analysis.linearity import (
            analyze_linearity,
            linearity_json,
            linearity_summary,
            tolerance_from_limits,
        )
        from station.analysis.report import format_linearity

        if tolerance is None:
            tolerance = tolerance_from_limits(config)
        result = analyze_linearity(
            linearity_profiles(source, path), tolerance=tolerance, config=config
        )
        analysis = linearity_summary(result)
        document = {**to_json(analysis), "linearity": linearity_json(result)}
        sections = [format_linearity(result, analysis.config)]
        title = f"LINEARITY REPORT ON {path.name}"
    elif procedure == "relative_accuracy":
        from station.analysis.accuracy import accuracy_json, analyze_accuracy
        from station.analysis.report import format_accuracy

        placements, errors, pendant = accuracy_inputs(source)
        result = analyze_accuracy(
            placements, errors, config, pendant=pendant, excluded_cycles=source.excluded_cycles
        )
        analysis = result.overall
        document = {**to_json(analysis), "accuracy": accuracy_json(result)}
        sections = [format_accuracy(result, config)]
        title = f"RELATIVE ACCURACY REPORT ON {path.name}"
    else:
        if not channels:
            raise StationError(f"{path}: the session has no accepted readings to analyse yet.")
        analysis = analyze(
            channels, config, excluded_cycles=source.excluded_cycles, cycles=source.cycles
        )
        document = to_json(analysis)
        sections = []
    document["procedure"] = procedure

    if args.json:
        print(json.dumps(document, indent=2, allow_nan=False))
    else:
        print(format_report(analysis, title=title, notes=source.notes, sections=sections))
    if args.fail_if_incapable:
        # A channel without a verdict (no limits, too few readings) fails too: a script that
        # asks for the verdict must not pass on data that was never judged.
        failed = [
            f"{name} ({'not capable' if c.capability.capable is False else 'no verdict'})"
            for name, c in analysis.channels.items()
            if c.capability.capable is not True
        ]
        if failed:
            print(f"station: failed the capability check: {', '.join(failed)}", file=sys.stderr)
            return 1
    return 0
