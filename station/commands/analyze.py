"""``station analyze FILE``: the report's statistics of a CSV table or a session file."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.commands._args import (
    RESOLUTION_RANGE,
    bounded_int,
    bounded_number,
    limit_value,
    parse_limit,
    parse_number,
)
from station.errors import StationError
from station.plain import plain
from station.text import CAPABLE, INCONCLUSIVE, NOT_CAPABLE, judged_word

if TYPE_CHECKING:
    from station.analysis.summary import AnalysisConfig

RULE_CHOICES = ("report", "western-electric", "nelson")
OPTION_FLAGS = {
    "reference": "--reference",
    "tolerance": "--tolerance",
    "process_variation": "--process-variation",
    "pool_above": "--pool-above",
    "distance": "--distance",
    "band": "--band",
}
"""The command line's values a method's analysis may take (its ``options``), by flag."""
SUBGROUP_LIMIT = 1000
"""The largest subgroup (X̄-S charts beyond 10; a subgroup of thousands is a typo)."""

DESCRIPTION = """\
Analyse readings the way the 1990 NASA/KSC report does: maximum, average,
minimum, sigma, skewness, range, mode, histogram, control chart with run rules,
Cp/Cpu/Cpl/Cpk and the verdict. FILE is a CSV table (a header row, '#' comment
lines, one numeric column per channel; columns named cycle, subgroup, t,
sample, id, index or obs are not channels, nor is a column that counts the rows
1, 2, 3 ...) or a session file (.jsonl).

--procedure linearity reads a CSV with columns stroke, s, h, v (one row per
streamed point) and adds the straightness per stroke (least squares and minimum
zone of h and v against s), per direction, the path repeatability along the bar
and the capability of the straightness against --tolerance. --procedure
relative_accuracy reads columns placement, x, y, z (optionally the teach
pendant's px, py, pz) and adds the accuracy per placement and across
placements. --procedure gauge_check reads one column of repeated readings of a
reference and gives the Type-1 study (Cg, Cgk, bias and its t-test, resolution
against --tolerance) with --reference X_M and --tolerance T; --procedure
gauge_linearity reads reference, value (each reading with the size of the
master it was read on) and gives the AIAG linearity and bias study (bias per
master with its t-test, its regression on the size, linearity = |slope|·PV with
--process-variation PV, the average bias, and a verdict, against --tolerance T
when given); --procedure joint_troubleshooting reads joint, x, y, z (and
optionally lever: the joint's axis to the cube) and names the suspect joint;
--procedure gain_schedule reads q and one column per gain (see also station
gains fit); --procedure gage_rr reads part, appraiser (or operator), trial,
value (part and appraiser may be names) and gives the crossed Gage R&R by ANOVA
and by average and range, %GRR against --tolerance T when given, ndc, and
AIAG's verdict; --procedure positioning reads target, direction (up/down or
+/-), actual or deviation and an optional cycle, and gives the ISO 230-2
figures of one axis (B, R, E, M, A, up, down and both); --procedure
pose_characteristics reads cycle, x, y, z and optionally pose (1 = P1 ...),
direction and the command pose cx, cy, cz, and gives the ISO 9283 barycentre,
AP and RP per pose, vAP, and with --distance P2:P4=D the distance accuracy AD
and repeatability RD. A session file is analysed as its procedure declares
(its `analysis`) unless --procedure says otherwise.

exit codes:
  0  analysed
  1  with --fail-if-incapable: a channel is NOT CAPABLE (its confidence bound
     is below the threshold), has no verdict (no limits) or only a provisional
     one (fewer readings than --min-n); a study with a verdict of its own
     (gauge_linearity, gage_rr) is not ACCEPTABLE. An INCONCLUSIVE channel
     (its bounds straddle the threshold) passes, with a note on stderr; with
     --fail-if-inconclusive it fails too
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
    parser.add_argument(
        "--min-n",
        metavar="N",
        help="readings needed for a final verdict; below it the verdict is PROVISIONAL "
        "(default: the session's procedure minimum, else 25)",
    )
    parser.add_argument(
        "--freeze-after",
        metavar="K",
        help="phase I: the live control limits freeze after the first K readings (default: "
        "the session's, else 20)",
    )
    parser.add_argument("--unit", default="", help="unit of the readings, for the report")
    parser.add_argument(
        "--procedure",
        metavar="METHOD",
        help="the method FILE is judged by, e.g. linearity or gauge_linearity (see above; "
        "default: the one a session's procedure declares, else repeatability)",
    )
    parser.add_argument(
        "--tolerance",
        metavar="T",
        help="linearity: straightness tolerance, the zone width per stroke (default: the "
        "session's, from its h/v limits); gauge_check, gauge_linearity, gage_rr: the tolerance "
        "T the gauge will judge",
    )
    parser.add_argument(
        "--process-variation",
        metavar="PV",
        help="gauge_linearity: the process variation (6 sigma) the linearity is stated "
        "against (default: the session's, else the tolerance)",
    )
    parser.add_argument(
        "--pool-above",
        metavar="P",
        help="gage_rr: pool the part x appraiser interaction into repeatability when its "
        "p-value is above P (default: the session's, else 0.25 as AIAG)",
    )
    parser.add_argument(
        "--reference",
        metavar="X_M",
        help="gauge_check: the reference's known size (default: the session's, typed in)",
    )
    parser.add_argument(
        "--distance",
        metavar="PA:PB=D",
        help="pose_characteristics: the two poses AD and RD are measured between and their "
        "command distance D (without =D: from their command poses)",
    )
    parser.add_argument(
        "--band",
        metavar="R",
        help="stabilisation: the band's radius about the final position, in the session's "
        "unit (e.g. the manufacturer's stated limit; default 5 x the indicators' noise at rest)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument(
        "--fail-if-incapable",
        action="store_true",
        help="exit 1 when any channel is NOT CAPABLE, unjudged or provisional (an "
        "INCONCLUSIVE one passes with a note)",
    )
    parser.add_argument(
        "--fail-if-inconclusive",
        action="store_true",
        help="as --fail-if-incapable, and an INCONCLUSIVE channel fails too (exit 1 unless "
        "every channel is CAPABLE)",
    )
    parser.set_defaults(func=run)


def is_session_file(path: Path) -> bool:
    """True when the file begins like a station session file (or it is named .jsonl)."""
    from station.session.lines import looks_like_session

    if path.suffix.lower() == ".jsonl":
        return True
    try:
        with path.open("rb") as stream:
            first = stream.readline(65536)
    except OSError:
        return False
    return looks_like_session(first)


def load_source(path: Path, labels: tuple[str, ...] = ()) -> Any:
    """A session file (detected by its header: a ``SessionSource``) or a CSV table of readings
    (a ``TableSource``; ``labels``: the columns of names the method reads)."""
    from station.inputfiles import check_regular_file

    # A FIFO, a device, a folder or a name too long is refused before a byte is read.
    check_regular_file(path, "file of readings")
    if is_session_file(path):
        from station.methods import load_session_source

        return load_session_source(path)
    from station.session.tables import read_table

    table = read_table(path, labels)
    cycles = None if table.cycles is None else dict.fromkeys(table.channels, table.cycles)
    if table.channel_cycles is not None:  # a tidy table: its own cycle numbers per channel
        cycles = dict(table.channel_cycles)
    return TableSource(
        channels=table.channels,
        cycles=cycles,
        table=table,
        excluded_cycles=table.excluded_cycles,
    )


def without_row_counters(source: TableSource) -> TableSource:
    """``source`` without the channel columns that only count the rows (1, 2, 3 ...: a row
    number a spreadsheet wrote under a name of its own), each named in a note; as it is when
    every channel counts (then they are the readings) or for a tidy table (its rows are
    readings by name)."""
    from station.session.tables import row_counters

    counters = () if source.table.channel_cycles is not None else row_counters(source.channels)
    if not counters or len(counters) == len(source.channels):
        return source
    notes = tuple(
        f"column {plain(name, limit=40)!r} counts the rows 1, 2, 3 ...: taken as a row number, "
        "not a channel (name it cycle to say so)."
        for name in counters
    )
    return replace(
        source,
        channels={n: v for n, v in source.channels.items() if n not in counters},
        cycles=None
        if source.cycles is None
        else {n: v for n, v in source.cycles.items() if n not in counters},
        notes=source.notes + notes,
    )


@dataclass(frozen=True)
class TableSource:
    """What a CSV table gives the analysis (the attributes a ``SessionSource`` also has)."""

    channels: dict[str, Any]
    cycles: dict[str, Any] | None
    table: Any  # station.session.tables.ReadingTable
    excluded_cycles: tuple[int, ...] = ()
    config: AnalysisConfig | None = None
    notes: tuple[str, ...] = ()


def table_times(table: Any, channels: dict[str, Any]) -> dict[str, Any] | None:
    """The time of each of ``channels``' readings when the table dates its rows (a ``t``
    column, a tidy table's ``time``), for the drift's trend; None otherwise."""
    if table.times is None or any(len(v) != len(table.times) for v in channels.values()):
        return None
    return {name: table.times for name in channels}


def method_options(method: Any, given: dict[str, float | str | None]) -> dict[str, float | str]:
    """The command line's values the method takes; StationError naming a flag it does not
    take (and the ones it does)."""
    from station.methods import methods

    for name, value in given.items():
        if value is not None and name not in method.options:
            takers = [m.name for m in methods().values() if name in m.options]
            takes = [OPTION_FLAGS[o] for o in method.options if o in OPTION_FLAGS]
            raise StationError(
                f"{OPTION_FLAGS[name]} is not an option of --procedure {method.name}"
                + (f" (it takes {', '.join(takes)})" if takes else "")
                + (f"; it belongs to --procedure {' or '.join(takers)}." if takers else ".")
            )
    return {name: value for name, value in given.items() if value is not None}


def run(args: argparse.Namespace) -> int:
    """Analyse FILE and print the text report or the JSON document."""
    from station.analysis.capability import SpecLimits
    from station.analysis.summary import AnalysisConfig

    path = Path(args.file)
    lsl = limit_value(args.lsl, "--lsl", "lower")
    usl = limit_value(args.usl, "--usl", "upper")
    resolution = bounded_number(args.resolution, "--resolution", *RESOLUTION_RANGE)
    threshold = bounded_number(args.capable_at, "--capable-at", 1e-6, 1e6)
    subgroup = bounded_int(args.subgroup, "--subgroup", 1, SUBGROUP_LIMIT) or 1
    per_channel = [parse_limit(text) for text in args.limit]
    min_n = None
    if args.min_n is not None:
        try:
            min_n = int(args.min_n)
        except ValueError:
            raise StationError(f"--min-n {args.min_n!r} is not a whole number.") from None
        if min_n < 0:
            raise StationError(f"--min-n {min_n} must be 0 or more.")

    from station.inputfiles import check_regular_file
    from station.methods import (
        MethodInputs,
        judge,
        method_of,
        names,
        report_session,
        session_method,
    )

    # A FIFO, a device, a folder or a name too long is refused before a byte is read. A table
    # is judged by the method named (its label columns read as text), a session by its own.
    check_regular_file(path, "file of readings")
    table_method = None if is_session_file(path) else method_of(args.procedure or names()[0])
    source = load_source(path, table_method.label_columns if table_method else ())
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
        min_n=recorded.min_n if min_n is None else min_n,
    )
    freeze_after = bounded_int(args.freeze_after, "--freeze-after", 2, SUBGROUP_LIMIT)
    if freeze_after is not None:
        config = replace(config, freeze_after=freeze_after)
    if isinstance(source, TableSource):
        assert table_method is not None
        method = table_method
        if not method.reads_columns_by_name:
            source = without_row_counters(source)
            channels = source.channels
    else:
        method = method_of(args.procedure or session_method(source.session))
    tolerance = parse_number(args.tolerance, "--tolerance")
    if tolerance is not None and not tolerance > 0:
        raise StationError(f"--tolerance {args.tolerance!r} must be greater than 0.")
    variation = parse_number(args.process_variation, "--process-variation")
    if variation is not None and not variation > 0:
        raise StationError(
            f"--process-variation {args.process_variation!r} must be greater than 0."
        )
    pool_above = parse_number(args.pool_above, "--pool-above")
    if pool_above is not None and not 0 < pool_above < 1:
        raise StationError(f"--pool-above {args.pool_above!r} must be between 0 and 1.")
    options = method_options(
        method,
        {
            "pool_above": pool_above,
            "reference": parse_number(args.reference, "--reference"),
            "tolerance": tolerance,
            "process_variation": variation,
            "distance": args.distance,
            "band": parse_number(args.band, "--band"),
        },
    )
    if isinstance(source, TableSource):
        inputs = MethodInputs(
            config=config,
            channels=channels,
            cycles=source.cycles,
            excluded_cycles=source.excluded_cycles,
            times=table_times(source.table, channels),
            options=options,
            table=source.table,
        )
        report = judge(method, inputs, name=path.name, notes=source.notes)
    else:
        report = report_session(source, config=config, method=method.name, options=options)
    if report.empty:
        raise StationError(f"{path}: the session has no accepted readings to analyse yet.")
    analysis = report.analysis

    if args.json:
        if isinstance(source, TableSource):  # the text report shows them; JSON has no place
            for note in source.notes:
                print(f"station: note: {note}", file=sys.stderr)
        # Indented for a person at a terminal; compact (json's C encoder, several times faster
        # on a document of thousands of alarms) when a script reads it.
        indent = 2 if sys.stdout.isatty() else None
        print(json.dumps(report.document(), indent=indent, allow_nan=False))
    else:
        print(report.text())
    if args.fail_if_incapable or args.fail_if_inconclusive:
        # A channel without a verdict (no limits, too few readings) fails too: a script that
        # asks for the verdict must not pass on data that was never judged.
        channels = analysis.channels.items() if analysis is not None else ()
        failed = [
            f"{name} ({_failure(c)})"
            for name, c in channels
            if _fails(c, strict=args.fail_if_inconclusive)
        ]
        undecided = [
            f"{name} ({_failure(c)})"
            for name, c in channels
            if not _fails(c, strict=args.fail_if_inconclusive) and judged_word(c) != CAPABLE
        ]
        if undecided:
            print(
                f"station: passed the capability check without proof: {', '.join(undecided)}; "
                "--fail-if-inconclusive fails it",
                file=sys.stderr,
            )
        own = report.verdict
        if own is not None and own.accepted is not True:
            failed.append(f"{method.name} ({own.word})")
        elif analysis is None and own is None:
            failed.append(f"{method.name} (no verdict: it judges no readings)")
        if failed:
            print(f"station: failed the capability check: {', '.join(failed)}", file=sys.stderr)
            return 1
    return 0


def _fails(channel: Any, *, strict: bool) -> bool:
    """Whether a channel fails ``--fail-if-incapable``: anything but CAPABLE, except that an
    INCONCLUSIVE verdict (judged, neither proven) fails only when ``strict``."""
    word = judged_word(channel)
    return word != CAPABLE and (strict or word != INCONCLUSIVE)


def _failure(channel: Any) -> str:
    """Why a channel fails (or only passes) ``--fail-if-incapable``."""
    verdict = channel.verdict
    word = judged_word(channel)
    if word == NOT_CAPABLE:
        return "not capable"
    if word == INCONCLUSIVE:
        needed = verdict.readings_needed if verdict is not None else None
        return "inconclusive" + (f": {needed} readings would settle it" if needed else "")
    if verdict is not None and verdict.provisional:
        return f"provisional: {verdict.n} of {verdict.min_n} readings"
    return "no verdict"
