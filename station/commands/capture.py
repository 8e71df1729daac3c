"""``station capture``: the headless run of a procedure, for scripts and for a terminal without
the TUI.

It drives the same :class:`~station.run.Runner` as the TUI: check steps are confirmed by the
command itself (the file records ``by: "station capture"``), input steps take ``--input``
values, zero steps zero, and each cycle is captured until the cycles step has its count. A
``cycle N ...`` line is printed only once that cycle's event is on disk (fsynced), so every line
a script saw is in the file, whatever happens next. The summary ends with the session file and
its last hash.

Relative accuracy (a ``repeat`` block per fixture placement, ``--placements N``): the teach
pendant's X, Y, Z differ per placement, so ``--input P:NAME=VALUE`` gives a value for placement
P only (``--input NAME=VALUE`` serves every placement), and ``--inputs FILE`` reads a CSV with a
``placement`` column and one column per field (``placement,x,y,z``): the operator copies the
pendant's display there. Every value is checked before anything is written.

Linearity (a ``stroke`` step, ``--strokes N``): h, v and s stream without a pause (use
``--trigger push`` with a counter that sends continuously); the strokes are split live by the
scale's direction of travel (:meth:`~station.run.Runner.stream_strokes`), and a line
``stroke 7 A→B 412 points h=0.00123 v=0.00061 (LS straightness)`` is printed once that
stroke's points are on disk. The command stops after N whole strokes and ends with the
procedure's report (the same as ``station analyze FILE``).

Units: the session's unit and gauge resolution are the procedure's unless ``--unit`` and
``--resolution`` say otherwise (with another unit than the procedure's, its resolution and
limits do not apply: give ``--resolution`` and ``--limit`` in that unit). Before the session
file is created (and before a resume is written) a few frames are read and judged
(:meth:`~station.instruments.gauge.GaugeSet.check_frames`): a unit the frames state (U-WAVE,
CDI, Digimatic), fewer decimals than the resolution needs, or values off its steps refuse the
session with one line naming both ("the gauges send steps of 0.001, which is mm on this
protocol; the session is in inches at 0.0001"); with ``--trigger push`` press DATA once (or
the check waits ``--timeout`` and leaves it to the zero step, which checks the unit too).

Pacing: ``--trigger poll`` needs ``--every S`` (at least S seconds between two cycles, and
around a zero) or a terminal (Enter per cycle, after a prompt naming the cycle the file will
record); without either it is refused before anything is written. ``--trigger arrival`` (the
repeatability procedure's default on a polled protocol) reads the gauges continuously and takes
a set each time the robot leaves the fixture and comes back to rest; a return that does not
settle is a warning on stderr, and nothing is recorded for it.

``--resume FILE`` continues the session as it was set up: the line (``--port``, ``--protocol``,
``--map``) and how this run waits (``--timeout``, ``--attempts``, inputs) may be given; a
set-up option (``--cycles``, ``--limit``, ``--trigger``, ...) with another value than the
session's is refused, not ignored (the same value again is accepted).

With ``--trigger push`` the command waits for the operator: a wait with no reading from the
gauges is not a refused set (``--attempts`` counts only sets that arrived and were refused).
With any trigger, a set missed while a port reconnects is not one either: the command waits.

Exit codes: 0 finished; 2 a one-line error (bad option, no port, a failed write such as a full
disk, no complete reading set after ``--attempts`` tries); 70 the command itself failed (a bug:
the session is interrupted and resumable, the line says where); 128 + the signal number after
SIGHUP (129), SIGINT (130) or SIGTERM (143): an ``interrupted`` event is written and the session
is resumable with ``--resume FILE``.
"""

from __future__ import annotations

import argparse
import contextlib
import getpass
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

from station.commands._remedies import CLI_REMEDIES
from station.errors import StationError

BY = "station capture"
_SIGNALS = ("SIGHUP", "SIGINT", "SIGTERM")
CRASH_EXIT = 70
"""The exit code when the command itself fails (EX_SOFTWARE): a bug, not the user's input."""

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


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station capture``."""
    parser = subparsers.add_parser(
        "capture",
        help="run a procedure without the TUI (headless capture into a session file)",
        description=(
            "Run a procedure headless: confirm its check steps, zero at zero steps, capture "
            "each cycle and print one line per cycle once it is on disk, then the analysis "
            "summary with the session file and its last hash. SIGHUP/SIGTERM/SIGINT write an "
            "'interrupted' event and exit 129/143/130; continue with --resume FILE."
        ),
    )
    parser.add_argument("--procedure", metavar="ID", help="procedure id (see station procedures)")
    parser.add_argument("--port", metavar="URL", help="serial port, rfc2217:// or socket:// URL")
    parser.add_argument("--protocol", metavar="P", help="gauge protocol (see station read -h)")
    parser.add_argument("--robot", metavar="NAME", help="the robot under test")
    parser.add_argument("--operator", metavar="NAME", help="operator (default: the login name)")
    parser.add_argument("--cycles", metavar="N", help="cycles to capture (default: procedure's)")
    from station.procedures import UNITS

    parser.add_argument(
        "--unit",
        choices=UNITS,
        help="the session's unit (default: the procedure's; another one needs --resolution "
        "and --limit in it)",
    )
    parser.add_argument(
        "--resolution", metavar="R", help="the gauges' resolution (default: the procedure's)"
    )
    parser.add_argument(
        "--limit",
        metavar="CH=LSL:USL",
        action="append",
        default=[],
        help="spec limits of a channel (repeatable; default: the procedure's)",
    )
    parser.add_argument(
        "--trigger",
        choices=("poll", "push", "stable", "arrival"),
        help="poll: ask the gauges (paced by --every or Enter); push: they send (DATA button, "
        "foot switch); stable: take the set once it settles; arrival: read continuously and "
        "take a set each time the robot leaves and comes back to rest (default: the "
        "procedure's trigger for a polled protocol, else poll)",
    )
    parser.add_argument(
        "--every",
        metavar="S",
        help="poll: at least S seconds between two cycles and around a zero (without it, and "
        "without a terminal to press Enter in, poll is refused)",
    )
    parser.add_argument(
        "--map", metavar="1=x,2=y,3=z", help="device to station channels (default 1, 2, 3 ...)"
    )
    parser.add_argument(
        "--input",
        metavar="[P:]NAME=VALUE",
        action="append",
        default=[],
        help="a value for an input step's field, for placement P only with P: (repeatable)",
    )
    parser.add_argument(
        "--inputs",
        metavar="FILE",
        help="a CSV of input values per placement: a placement column and one per field",
    )
    parser.add_argument(
        "--placements", metavar="N", help="fixture placements of a repeat block (procedure's)"
    )
    parser.add_argument("--strokes", metavar="N", help="whole strokes to stream (procedure's)")
    parser.add_argument(
        "--gauge",
        metavar="CH=ID",
        action="append",
        default=[],
        help="the id or serial of the gauge on channel CH, looked up in the gauge register "
        "(repeatable; default: the gauge last checked on the same line)",
    )
    parser.add_argument(
        "--deadband",
        metavar="D",
        help="stroke splitting: the scale's reversal that ends a stroke (100 resolutions)",
    )
    parser.add_argument(
        "--still",
        default="2",
        metavar="S",
        help="stroke splitting: seconds at rest that end a stroke (2)",
    )
    parser.add_argument(
        "--sessions", metavar="DIR", help="sessions folder (default: STATION_SESSIONS, ...)"
    )
    parser.add_argument(
        "--procedures",
        metavar="DIR",
        action="append",
        default=[],
        help="a site's procedures folder (repeatable; also STATION_PROCEDURES)",
    )
    parser.add_argument(
        "--resume",
        metavar="FILE",
        help="continue an unfinished session as it was set up (--port/--protocol/--map "
        "replace the recorded line; set-up options are refused)",
    )
    parser.add_argument(
        "--timeout", default="5", metavar="S", help="seconds to wait for a reading set (5)"
    )
    parser.add_argument(
        "--attempts",
        default="3",
        metavar="N",
        help="refused reading sets in a row before giving up (3; with push, waiting for "
        "DATA is not a refusal)",
    )
    parser.set_defaults(func=run)


def _positive(text: str | None, option: str, kind: type = float) -> Any:
    from station.commands.read import positive_number

    return positive_number(text, option, kind)


Inputs = dict[int | None, dict[str, str]]
"""Typed values by placement (``None``: for every placement and for steps outside a block)."""


def _parse_inputs(items: list[str], table: str | None = None) -> Inputs:
    """``--input [P:]NAME=VALUE`` values and the rows of an ``--inputs`` CSV, by placement."""
    values: Inputs = {None: {}}
    for item in items:
        name, equals, value = item.partition("=")
        placement, colon, field_name = name.partition(":")
        number: int | None = None
        if colon:
            try:
                number = int(placement)
            except ValueError:
                number = 0
            if number < 1:
                raise StationError(
                    f"--input {item!r}: the placement before ':' must be 1, 2, 3, ..."
                )
            name = field_name
        if not equals or not name.strip():
            raise StationError(
                f"--input {item!r} is not [P:]NAME=VALUE; write e.g. --input x=12.5 or "
                "--input 2:x=12.5"
            )
        values.setdefault(number, {})[name.strip()] = value.strip()
    if table:
        for number, row in _read_inputs(table).items():
            values.setdefault(number, {}).update(row)
    return values


def _read_inputs(path: str) -> dict[int, dict[str, str]]:
    import csv

    from station.inputfiles import read_input_bytes

    # A regular file of at most 1 MiB (a FIFO or /dev/zero is refused), UTF-8 text.
    data = read_input_bytes(path, "--inputs file", 1 << 20)
    try:
        rows = list(csv.DictReader(data.decode("utf-8-sig").splitlines()))
    except UnicodeDecodeError:
        raise StationError(f"--inputs {path} is not UTF-8 text; give a CSV file") from None
    except csv.Error as error:
        raise StationError(f"--inputs {path}: not a CSV table ({error})") from None
    table: dict[int, dict[str, str]] = {}
    for line, row in enumerate(rows, start=2):
        row = {(k or "").strip().lower(): (v or "").strip() for k, v in row.items()}
        try:
            number = int(row.pop("placement"))
        except (KeyError, ValueError):
            raise StationError(
                f"--inputs {path} line {line}: needs a placement column of whole numbers "
                "(placement,x,y,z)"
            ) from None
        table[number] = row
    return table


def _values_for(inputs: Inputs, placement: int | None) -> dict[str, str]:
    """The values that answer an input step at ``placement``."""
    return {**inputs.get(None, {}), **(inputs.get(placement, {}) if placement else {})}


def _setup(args: argparse.Namespace) -> Any:
    """The session set-up from the flags (a new session)."""
    from station.analysis.capability import SpecLimits
    from station.commands.analyze import parse_limit
    from station.procedures import discover_procedures
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
    procedure = discover_procedures(args.procedures).get(args.procedure)
    limits = {}
    for text in args.limit:
        channel, lsl, usl = parse_limit(text)
        limits[channel] = SpecLimits(lsl=lsl, usl=usl)
    resolution = _positive(args.resolution, "--resolution")
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
        cycles=_positive(args.cycles, "--cycles", int) if args.cycles else None,
        placements=_positive(args.placements, "--placements", int) if args.placements else None,
        strokes=_positive(args.strokes, "--strokes", int) if args.strokes else None,
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
    from station.instruments.protocols import get_protocol

    if procedure.trigger and get_protocol(protocol).polled:
        return str(procedure.trigger)
    return "poll"


def _channel_map(args: argparse.Namespace, channels: tuple[str, ...]) -> dict[str, str]:
    from station.text import parse_channel_map

    return parse_channel_map(args.map) or {str(i): ch for i, ch in enumerate(channels, start=1)}


def _resume_setup(args: argparse.Namespace) -> Any:
    from station.run import PortSetup, resume_setup

    setup = resume_setup(args.resume, procedures_dirs=args.procedures)
    conflicts = _resume_conflicts(args, setup)
    if conflicts:
        raise StationError(
            f"{', '.join(conflicts)} cannot change a resumed session: it continues as its "
            "header records; leave them out, or start a new session"
        )
    if not args.port:
        return setup
    recorded = setup.ports[0] if setup.ports else None
    protocol = args.protocol or (recorded.protocol if recorded else None)
    if not protocol:
        raise StationError("--protocol missing: the session records no port to take it from")
    port = PortSetup(args.port, protocol, _channel_map(args, setup.channels))
    return resume_setup(args.resume, procedures_dirs=args.procedures, ports=(port,))


def _resume_conflicts(args: argparse.Namespace, setup: Any) -> list[str]:
    """The set-up options given with ``--resume`` whose value differs from the session's, each
    as ``--cycles 40 (the session's: 30)``."""
    from station.commands.analyze import parse_limit

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
            same = value == _positive(given, option, int)
        elif name == "resolution":
            same = value == _positive(given, option)
        else:
            same = given == value
        if not same:
            was = "the procedure's" if value is None else value
            conflicts.append(f"{option} {given} (the session's: {was})")
    return conflicts


def _pacing(trigger: str, every_text: str | None) -> tuple[float | None, bool]:
    """How a ``poll`` session paces its cycles: (``--every`` seconds, Enter at the terminal).
    Without either, polling would record a cycle as fast as the gauges answer (a gauge standing
    still, not a robot repeating): refused with the three ways to pace it."""
    every = _positive(every_text, "--every") if every_text is not None else None
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


def _check_answerable(runner_plan: Any, procedure: Any, inputs: Inputs, done: set) -> None:
    """Refuse, before anything is written, a procedure this command cannot walk alone
    (``runner_plan``: the unrolled steps as (step, placement); ``done``: the (step id,
    placement) pairs a resumed session already confirmed)."""
    for step, placement in runner_plan:
        if (step.id, placement) in done or not step.fields:
            continue
        given = _values_for(inputs, placement)
        needed = [f.name for f in step.fields if f.required and f.name not in given]
        if needed:
            prefix = f"{placement}:" if placement else ""
            where = f" at placement {placement}" if placement else ""
            raise StationError(
                f"step {step.title!r}{where} asks for {', '.join(needed)}: pass "
                + " ".join(f"--input {prefix}{name}=VALUE" for name in needed)
                + (" (or --inputs FILE with a row per placement)" if placement else "")
            )
    known = {f.name for step in procedure.all_steps() for f in step.fields}
    unknown = sorted({name for values in inputs.values() for name in values} - known)
    if unknown:
        raise StationError(
            f"--input {', '.join(unknown)}: procedure {procedure.id} asks for no such value"
            + (f" (it asks for {', '.join(sorted(known))})" if known else "")
        )


class _Headless:
    """Walks the runner through the procedure on a worker thread; the main thread keeps the
    signals, so an interrupt never lands in the middle of a journal write.

    How the walk ended is left for the main thread: ``error`` (a StationError: one line) or
    ``crash`` (anything else: a bug, which must not end as a finished session)."""

    def __init__(
        self,
        runner: Any,
        inputs: Inputs,
        timeout: float,
        attempts: int,
        *,
        deadband: float | None = None,
        still: float = 2.0,
        every: float | None = None,
        enter: bool = False,
    ) -> None:
        self.runner = runner
        self.every = every
        self.enter = enter
        self._last_capture = float("-inf")
        self._moving_since: float | None = None
        self.inputs = inputs
        self.timeout = timeout
        self.attempts = attempts
        self.deadband = deadband
        self.still = still
        self.error: StationError | None = None
        self.crash: BaseException | None = None
        self.done = threading.Event()
        self.push = runner.setup.trigger == "push"
        self._waiting = False
        self._refused = 0

    def run(self) -> None:
        try:
            self._walk()
        except StationError as error:
            self.error = error
        except BaseException as error:  # a bug: reported by the main thread, never swallowed
            self.crash = error
        finally:
            self.done.set()

    def _readings_seen(self) -> int:
        """Readings the gauges have sent so far (all ports): unchanged over a wait means nobody
        pressed DATA, which with the push trigger is waiting, not a refused set."""
        return sum(reader.reading_count for reader in getattr(self.runner.gauges, "readers", ()))

    def _idle(self, step: Any) -> None:
        """Nobody pressed DATA (or the robot did not come back) during a wait: say once, until
        the next set, that the command waits (the operator or the robot sets the pace)."""
        if not self._waiting:
            what = "press DATA" if self.push else "run the robot's playback loop"
            print(
                f"station: waiting for the gauges: {what} (step {step.title!r})",
                file=sys.stderr,
                flush=True,
            )
        self._waiting = True

    def _pace(self, state: Any) -> bool:
        """Poll: wait out ``--every`` since the last capture, or for Enter at the terminal
        (after the prompt naming the cycle the file will record). False when the walk should
        look at the state again first (the session changed meanwhile)."""
        if self.every is not None:
            delay = self._last_capture + self.every - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        elif self.enter:
            print(f"{state.action.prompt}  [Enter]", file=sys.stderr, flush=True)
            if not sys.stdin.readline():
                raise StationError(
                    "standard input closed while waiting for Enter: resume the session "
                    "with --every S to pace its cycles without a terminal"
                )
        self._last_capture = time.monotonic()
        return self.runner.state().status == "running"

    def _walk(self) -> None:
        """Do what the engine asks next until every step is done: one small call per action
        (the same actions the TUI maps to keys)."""
        runner = self.runner
        while True:
            state = runner.state()
            if state.status != "running" or state.action.kind in ("finish", "done"):
                return
            self._ACTIONS[state.action.kind](self, state)

    def _confirm(self, state: Any) -> None:
        self.runner.confirm(by=BY)

    def _input(self, state: Any) -> None:
        given = _values_for(self.inputs, state.placement)
        # _check_answerable made sure every required field has a value; the engine checks them.
        fields = state.action.fields
        self.runner.submit_input({f.name: given[f.name] for f in fields if f.name in given}, by=BY)

    def _zero(self, state: Any) -> None:
        from station.instruments.zeroing import GaugesMoving

        if self.every is not None:
            # After a capture the robot is brought to where it is zeroed: --every paces that too.
            delay = self._last_capture + self.every - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        seen = self._readings_seen()
        try:
            self.runner.zero(by=BY, timeout=self.timeout)
        except GaugesMoving as moving:
            # The robot is not at rest at the fixture yet: zero once it is (said once), for as
            # long as --attempts waits of --timeout; then the run stops, resumable.
            now = time.monotonic()
            if self._moving_since is None:
                self._moving_since = now
                print(f"station: waiting: {moving.message}", file=sys.stderr, flush=True)
            if now - self._moving_since > self.timeout * self.attempts:
                raise StationError(
                    f"{moving.message.rstrip('.')} (still moving after "
                    f"{now - self._moving_since:.0f} s)",
                    remedy="resume_session",
                    subject=str(self.runner.path),
                ) from None
            time.sleep(0.1)
            return
        except StationError:
            if self.push and self._readings_seen() == seen:
                self._idle(state.current.step)  # nobody pressed DATA yet: the zero waits
                return
            raise
        self._waiting = False
        self._moving_since = None
        # The robot is started on its loop once it is zeroed: the first cycle is paced too.
        self._last_capture = time.monotonic()

    def _stream(self, state: Any) -> None:
        if state.progress is not None and state.progress.complete:
            self.runner.confirm(by=BY)
            return
        self.runner.stream_strokes(
            self.timeout,
            deadband=self.deadband,
            still_seconds=self.still,
            on_stroke=_print_stroke,
            by=BY,
        )

    def _capture(self, state: Any) -> None:
        runner = self.runner
        if state.progress is not None and state.progress.complete:
            runner.confirm(by=BY)
            return
        if not self._pace(state):
            return
        seen = self._readings_seen()
        outcome = runner.capture(self.timeout, by=BY)
        if runner.state().status != "running":
            return
        if outcome.recorded:
            self._refused = 0
        elif outcome.waited and not self.push:
            self._idle(state.current.step)  # the robot has not come back yet: it sets the pace
            return
        elif self.push and self._readings_seen() == seen:
            self._idle(state.current.step)  # no reading at all: nobody pressed DATA yet
            return
        elif outcome.port_down:
            return  # the line is reconnecting: not the gauges' refusal; wait for it
        else:
            self._refused += 1
        self._waiting = False
        if self._refused >= self.attempts:
            raise StationError(
                f"{self._refused} reading sets in a row were refused (last: "
                f"{outcome.message}); check the gauges and the cable",
                remedy="resume_session",
                subject=str(runner.path),
            )

    _ACTIONS: dict[str, Any] = {
        "confirm": _confirm,
        "input": _input,
        "zero": _zero,
        "stream": _stream,
        "capture": _capture,
    }


def _print_stroke(outcome: Any) -> None:
    """``stroke 7 A→B 412 points h=0.00123 v=0.00061 (LS straightness)``, once the stroke's
    points are on disk (``on_stroke`` of the runner's stream)."""
    from station.analysis.linearity import straightness

    profile = outcome.profile
    position = profile.get("s")
    figures = " ".join(
        f"{channel}={straightness(position, values).ls:.5f}"
        for channel, values in profile.items()
        if channel != "s" and position is not None and len(values) >= 2
    )
    print(f"{outcome.line()} {figures} (LS straightness)", flush=True)


class _Printer:
    """The runner's listener: prints acknowledged cycles, steps and zeroes as they happen, and
    its warnings on stderr (a warning repeated with nothing in between is printed once: a
    push device left idle, or the same refusal, would otherwise fill the terminal)."""

    def __init__(self, resolution: float) -> None:
        self.resolution = resolution
        self._last_warning: str | None = None

    def __call__(self, notice: Any) -> None:
        from station.run import CycleRecord

        event = notice.event
        kind = event.get("type") if event is not None else None
        if kind == "reading":
            # The runner's own cycle line: values at the gauges' decimals, as they show them.
            values = {ch: spec["value"] for ch, spec in event["channels"].items()}
            record = CycleRecord(
                event["cycle"], values, event["step"], None, resolution=self.resolution
            )
            self._print(record.line())
        elif kind == "step":
            self._print(f"step {event['step']}: done (by {event.get('by', 'operator')})")
        elif kind == "zero":
            from station.text import zero_text

            self._print("zeroed " + zero_text(event["channels"], self.resolution))
        elif kind == "alarm":
            from station.session.alarms import recorded_alarm

            self._print(alarm_line(recorded_alarm(event)))
            # The engine's warning about the same alarm says nothing new: not repeated.
            self._last_warning = f"{event['channel']}: {event.get('rule_name')}: {event['text']}"
        elif kind == "ack":
            self._print(f"alarm #{event['alarm']} acknowledged: {event['cause']}")
        elif (
            notice.message is not None
            and notice.message.level == "info"
            and notice.state.status == "finished"
        ):
            # What the analysis kind did with the finished session (a gauge check filed).
            self._print(notice.message.text)
        elif notice.message is not None and notice.message.level == "warning":
            # Errors are not printed here: each one also ends the command with its own line.
            text = notice.message.text
            if text != self._last_warning:
                print(f"station: warning: {text}", file=sys.stderr, flush=True)
            self._last_warning = text

    def _print(self, line: str) -> None:
        print(line, flush=True)
        self._last_warning = None


def alarm_line(alarm: Any) -> str:
    """A recorded alarm (:class:`~station.session.alarms.RecordedAlarm`) as ``station capture``
    prints it: ``alarm #41 y, report rule 1 (a point beyond the control limits) [live]:
    <sentence>``."""
    where = "live" if alarm.live else "retrospective"
    return f"alarm #{alarm.seq} {alarm.channel}, {alarm.rule_name} [{where}]: {alarm.text}"


def acknowledge_at_terminal(
    runner: Any, stdin: Any = None, out: Any = None, stop: Any = lambda: False
) -> int:
    """Ask, on a terminal only, for the cause of each alarm not acknowledged yet (before the
    session is finished, while its file takes events): the cause from the procedure's list
    (Enter leaves the alarm as it is), what it was ("other" needs it) and the corrective
    action. Returns how many were acknowledged. Without a terminal on stdin nothing is asked,
    so a script is never blocked; end of input or ``stop()`` (a signal caught) ends the
    questions."""
    import select

    stdin = sys.stdin if stdin is None else stdin
    out = sys.stdout if out is None else out
    if not stdin.isatty():
        return 0
    pending = [alarm for alarm in runner.state().alarm_list if not alarm.acknowledged]
    if not pending:
        return 0
    causes = tuple(runner.setup.procedure.causes)
    print(
        f"{len(pending)} alarm{'s' if len(pending) > 1 else ''} not acknowledged. For each, "
        f"type its cause ({', '.join(causes)}), or press Enter to leave it unacknowledged.",
        file=out,
        flush=True,
    )

    def ask(prompt: str) -> str | None:
        print(prompt, end="", file=out, flush=True)
        # Wait in short steps: a signal (Ctrl-C) is only recorded by the command's handler,
        # and must still end the questions.
        while not select.select([stdin], [], [], 0.1)[0]:
            if stop():
                return None
        line = stdin.readline()
        return None if not line or stop() else line.strip()

    done = 0
    for alarm in pending:
        print(alarm_line(alarm), file=out, flush=True)
        while True:
            cause = ask("  cause: ")
            if cause is None:
                return done  # end of input: the rest stay unacknowledged
            if not cause:
                break
            text = ask("  what it was (needed for 'other'; Enter: nothing): ")
            action = None if text is None else ask("  corrective action (Enter: none): ")
            if text is None or action is None:
                return done
            try:
                runner.acknowledge(alarm.seq, cause, text=text, action=action, by=BY)
            except StationError as error:
                print(f"  {error.message}", file=out, flush=True)
                continue
            done += 1
            break
    return done


def _check_frames(gauges: Any, setup: Any, timeout: float, resume: str | None) -> None:
    """Read a few frames and refuse, before anything is written, gauges whose frames disagree
    with the session's unit or resolution (a unit the frames state, fewer decimals than the
    resolution needs, values off its steps), with one sentence naming both."""
    if setup.trigger == "push":
        print(
            f"frames check: press DATA once on the gauges (waiting up to {timeout:g} s)",
            flush=True,
        )
    # One reading set: its frames show the decimals and any unit the gauges state.
    problem = gauges.check_frames(
        setup.resolved_unit,
        setup.resolved_resolution,
        readings=1,
        timeout=timeout,
        channels=setup.channels,
    )
    if not problem:
        return
    if resume:
        advice = "set the gauges to the session's unit and resolution, then resume again"
    else:
        inferred = gauges.infer_frames(setup.channels).values()
        units = {i.known_unit for i in inferred}
        steps = {i.step for i in inferred if i.step}
        unit = next(iter(units)) if len(units) == 1 and None not in units else "U"
        step = f"{next(iter(steps)):g}" if len(steps) == 1 else "R"
        advice = (
            f"start it in the gauges' unit and resolution (--unit {unit} --resolution {step}, "
            f"with --limit in {unit}), or set the gauges to the session's"
        )
    raise StationError(f"{problem}: {advice}; nothing was written")


def run(args: argparse.Namespace) -> int:
    """Run (or resume) a session headless; the exit code says how it ended."""
    from station.run import Runner, open_gauges
    from station.session.store import sessions_folder

    timeout = _positive(args.timeout, "--timeout")
    if timeout > 86_400:  # a bound time.monotonic() arithmetic and Event.wait() both take
        raise StationError(f"--timeout must be at most 86400 seconds (a day), not {args.timeout}.")
    attempts = _positive(args.attempts, "--attempts", int)
    inputs = _parse_inputs(args.input, args.inputs)
    deadband = _positive(args.deadband, "--deadband") if args.deadband else None
    still = _positive(args.still, "--still")
    if args.resume:
        from station.session.model import load_session

        setup = _resume_setup(args)
        done = {
            (event["step"], event.get("placement"))
            for event in load_session(args.resume, recover=False).events
            if event["type"] == "step"
        }
    else:
        setup, done = _setup(args), set()
        sessions_folder(args.sessions)  # an empty --sessions is refused before any gauge opens
    from station.run import plan_steps

    _check_answerable(plan_steps(setup), setup.procedure, inputs, done)
    every, enter = _pacing(setup.trigger, args.every)

    caught: list[int] = []
    previous = {}
    for name in _SIGNALS:
        signum = getattr(signal, name)
        previous[signum] = signal.signal(signum, lambda number, frame: caught.append(number))
    gauges = None
    try:
        gauges = open_gauges(setup)
        if not gauges.wait_connected(timeout):
            problems = "; ".join(
                f"{r.url}: {r.last_message or r.state}"
                for r in gauges.readers
                if r.state != "connected"
            )
            raise StationError(f"the gauges did not connect within {timeout:g} s ({problems})")
        _check_frames(gauges, setup, timeout, args.resume)
        if caught:
            return 128 + caught[0]  # before any session exists: nothing to record
        printer = _Printer(setup.resolved_resolution)
        if args.resume:
            runner = Runner.resume(args.resume, gauges, setup=setup, listener=printer, by=BY)
        else:
            folder, why = sessions_folder(args.sessions)
            print(f"sessions folder: {folder} ({why})", flush=True)
            runner = Runner.start(setup, gauges, folder, listener=printer)
        print(f"session file: {runner.path}", flush=True)
        headless = _Headless(
            runner,
            inputs,
            timeout,
            attempts,
            deadband=deadband,
            still=still,
            every=every,
            enter=enter,
        )
        worker = threading.Thread(target=headless.run, name="station capture", daemon=True)
        worker.start()
        while not headless.done.wait(0.05):
            if caught:
                break
        if not caught:
            return_code = _ended(runner, headless)
            if return_code is not None:
                return return_code
            # Only at a terminal (the operator is there): the alarms' causes, before the finish.
            acknowledge_at_terminal(runner, stop=lambda: bool(caught))
        if caught:
            signum = caught[0]
            name = signal.Signals(signum).name
            runner.interrupt(name)
            gauges.stop()  # wakes a capture that waits for the gauges
            worker.join(0.5)  # its writes are refused now; it must not delay the exit
            print(
                f"station: {name}: session interrupted; resume it with "
                f"`station capture --resume {runner.path}`",
                file=sys.stderr,
            )
            return 128 + signum
        analysis = runner.finish(by=BY)
    finally:
        if gauges is not None:
            gauges.stop()
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    _print_summary(runner, analysis)
    return 0


def _ended(runner: Any, headless: _Headless) -> int | None:
    """How the walk ended when it did not complete every step: the exit code after one line
    on stderr (or a StationError), ``None`` when the session is complete and may be finished."""
    resume = f"`station capture --resume {runner.path}`"
    if headless.crash is not None:
        crash = headless.crash
        what = f"{type(crash).__name__}: {crash}".rstrip(": ")
        # The file says why it stopped, and stays resumable: a bug is not the end of a session.
        with contextlib.suppress(StationError):  # a failed write says so in its own status
            runner.interrupt(f"station capture crashed: {what}")
        print(
            f"station: station capture crashed ({what}); the session is interrupted, "
            f"nothing acknowledged is lost: resume it with {resume} (and report the bug)",
            file=sys.stderr,
        )
        return CRASH_EXIT
    state = runner.state()
    if state.status == "failed":
        # The write failure's own sentence (a full disk, a file-size limit), not a bare "failed".
        message = runner.failure or f"a write to the session file failed: {runner.path}"
        if "--resume" not in message:
            message += f" (resume with {resume})"
        raise StationError(message)
    if headless.error is not None:
        # Say in the file why the session stopped (unless the disk itself failed).
        message = headless.error.message
        runner.interrupt(f"station capture stopped: {message}")
        if "--resume" not in message:
            message += f" (resume with {resume})"
        raise StationError(message)
    if not state.complete:
        raise StationError(
            f"the session is {state.status} before every step was done; resume it with {resume}"
        )
    return None


def _print_summary(runner: Any, analysis: Any) -> None:
    """The session's report as ``station analyze FILE`` prints it (through the analysis-kind
    registry, so a site's own procedure of a kind gets that kind's report)."""
    from station.verdicts import analyze_session_file

    report, problem = None, None
    try:
        # A kind that judges no cycles (a gain schedule) has a report all the same.
        report = analyze_session_file(Path(runner.path))
    except StationError as error:
        problem = error
    if report is None or report.empty:
        if problem is not None and analysis is not None:
            # The session is finished and safe; only its report could not be made.
            print(f"no report: {problem.worded(CLI_REMEDIES)}")
        else:
            print("no accepted cycles: nothing to analyse")
    else:
        notes = [
            f"Robot {runner.setup.robot}, operator {runner.setup.operator or 'not given'}, "
            f"procedure {runner.setup.procedure.id} {runner.setup.procedure.version}.",
            f"Session file: {runner.path}",
            f"Last line hash (anchors the session file): {runner.last_hash}",
        ]
        from station.text import zero_taken

        zero = zero_taken([{"channels": runner.recorded_zero}], runner.setup.resolved_resolution)
        if zero:
            notes.append(zero)
        print(report.text(notes, alarms=True), end="")
    print(f"session file: {Path(runner.path)}")
    print(f"last hash: {runner.last_hash}")
