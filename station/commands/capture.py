"""``station capture``: the headless run of a procedure, for scripts and for a terminal without
the TUI.

It drives the same :class:`~station.runner.Runner` as the TUI: check steps are confirmed by the
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
scale's direction of travel (:meth:`~station.runner.Runner.stream_strokes`), and a line
``stroke 7 A→B 412 points h=0.00123 v=0.00061 (LS straightness)`` is printed once that
stroke's points are on disk. The command stops after N whole strokes and ends with the
procedure's report (the same as ``station analyze FILE``).

Exit codes: 0 finished; 2 a one-line error (bad option, no port, a failed write such as a full
disk, no complete reading set after ``--attempts`` tries); 128 + the signal number after
SIGHUP (129), SIGINT (130) or SIGTERM (143): an ``interrupted`` event is written and the session
is resumable with ``--resume FILE``.
"""

from __future__ import annotations

import argparse
import getpass
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from station.errors import StationError

BY = "station capture"
_SIGNALS = ("SIGHUP", "SIGINT", "SIGTERM")


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
    parser.add_argument(
        "--limit",
        metavar="CH=LSL:USL",
        action="append",
        default=[],
        help="spec limits of a channel (repeatable; default: the procedure's)",
    )
    parser.add_argument(
        "--trigger",
        choices=("poll", "push", "stable"),
        default="poll",
        help="poll: ask the gauges; push: they send (DATA button, foot switch); stable: take "
        "the set once it settles (default poll)",
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
        help="continue an unfinished session (its recorded set-up; --port/--protocol/--map "
        "replace the recorded line)",
    )
    parser.add_argument(
        "--timeout", default="5", metavar="S", help="seconds to wait for a reading set (5)"
    )
    parser.add_argument(
        "--attempts",
        default="3",
        metavar="N",
        help="refused reading sets in a row before giving up (3)",
    )
    parser.set_defaults(func=run)


def _positive(text: str, option: str, kind: type = float) -> Any:
    try:
        value = kind(text)
    except ValueError:
        raise StationError(f"{option} {text!r} is not a number") from None
    if not value > 0:
        raise StationError(f"{option} must be more than 0, not {text}")
    return value


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

    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
    except OSError as error:
        raise StationError(f"--inputs {path}: {error.strerror or error}") from None
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
    from station.runner import PortSetup, SessionSetup

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
    return SessionSetup(
        procedure=procedure,
        robot=args.robot,
        operator=args.operator if args.operator is not None else getpass.getuser(),
        ports=(PortSetup(args.port, args.protocol, _channel_map(args, procedure.channels)),),
        trigger=args.trigger,
        limits=limits or None,
        cycles=_positive(args.cycles, "--cycles", int) if args.cycles else None,
        placements=_positive(args.placements, "--placements", int) if args.placements else None,
        strokes=_positive(args.strokes, "--strokes", int) if args.strokes else None,
    )


def _channel_map(args: argparse.Namespace, channels: tuple[str, ...]) -> dict[str, str]:
    from station.commands.read import parse_map

    return parse_map(args.map) or {str(i): ch for i, ch in enumerate(channels, start=1)}


def _resume_setup(args: argparse.Namespace) -> Any:
    from station.runner import PortSetup, resume_setup

    setup = resume_setup(args.resume, procedures_dirs=args.procedures)
    if not args.port:
        return setup
    recorded = setup.ports[0] if setup.ports else None
    protocol = args.protocol or (recorded.protocol if recorded else None)
    if not protocol:
        raise StationError("--protocol missing: the session records no port to take it from")
    port = PortSetup(args.port, protocol, _channel_map(args, setup.channels))
    return resume_setup(args.resume, procedures_dirs=args.procedures, ports=(port,))


def _check_answerable(runner_plan: Any, procedure: Any, inputs: Inputs, done: set) -> None:
    """Refuse, before anything is written, a procedure this command cannot walk alone
    (``runner_plan``: the unrolled steps as (step, placement); ``done``: the (step id,
    placement) pairs a resumed session already confirmed)."""
    for step, placement in runner_plan:
        if (step.id, placement) in done or step.kind != "input":
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
    signals, so an interrupt never lands in the middle of a journal write."""

    def __init__(
        self,
        runner: Any,
        inputs: Inputs,
        timeout: float,
        attempts: int,
        *,
        deadband: float | None = None,
        still: float = 2.0,
    ) -> None:
        self.runner = runner
        self.inputs = inputs
        self.timeout = timeout
        self.attempts = attempts
        self.deadband = deadband
        self.still = still
        self.error: StationError | None = None
        self.done = threading.Event()

    def run(self) -> None:
        try:
            self._walk()
        except StationError as error:
            self.error = error
        finally:
            self.done.set()

    def _walk(self) -> None:
        runner = self.runner
        refused = 0
        while True:
            state = runner.state()
            if state.status != "running" or state.current is None:
                return
            step = state.current.step
            if step.kind == "check":
                runner.confirm(by=BY)
            elif step.kind == "zero":
                runner.zero(by=BY)
            elif step.kind == "input":
                given = _values_for(self.inputs, state.current.placement)
                # _check_answerable made sure every required field has a value; the runner
                # checks them.
                values = {f.name: given[f.name] for f in step.fields if f.name in given}
                runner.submit_input(values, by=BY)
            elif step.kind == "stroke" and state.strokes >= state.strokes_target:
                runner.confirm(by=BY)
            elif step.kind == "stroke":
                runner.stream_strokes(
                    self.timeout,
                    deadband=self.deadband,
                    still_seconds=self.still,
                    on_stroke=_print_stroke,
                    by=BY,
                )
            elif step.kind == "cycles" and state.cycle >= state.cycles_target:
                runner.confirm(by=BY)
            elif step.kind in ("cycles", "capture"):
                outcome = runner.capture(self.timeout, by=BY)
                if runner.state().status != "running":
                    return
                refused = 0 if outcome.recorded else refused + 1
                if refused >= self.attempts:
                    raise StationError(
                        f"{refused} reading sets in a row were refused (last: "
                        f"{outcome.message}); check the gauges and the cable, "
                        f"then resume with `station capture --resume {runner.path}`"
                    )
            else:
                raise StationError(
                    f"station capture cannot run {step.kind} steps yet (step {step.title!r})"
                )


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


def _printer(notice: Any) -> None:
    """Print acknowledged cycles and the runner's warnings as they happen (listener)."""
    event = notice.event
    if event is not None and event.get("type") == "reading":
        values = {ch: spec["value"] for ch, spec in event["channels"].items()}
        line = f"cycle {event['cycle']} " + " ".join(f"{ch}={v:+.5f}" for ch, v in values.items())
        print(line, flush=True)
    elif event is not None and event.get("type") == "step":
        print(f"step {event['step']}: done (by {event.get('by', 'operator')})", flush=True)
    elif event is not None and event.get("type") == "zero":
        zeroed = ", ".join(f"{ch} ({spec['method']})" for ch, spec in event["channels"].items())
        print(f"zeroed {zeroed}", flush=True)
    elif notice.message is not None and notice.message.level == "warning":
        # Errors are not printed here: each one also ends the command with its own line.
        print(f"station: warning: {notice.message.text}", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    """Run (or resume) a session headless; the exit code says how it ended."""
    from station.runner import Runner, open_gauges
    from station.session.store import sessions_folder

    timeout = _positive(args.timeout, "--timeout")
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
    from station.runner import plan_steps

    _check_answerable(plan_steps(setup), setup.procedure, inputs, done)

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
        if caught:
            return 128 + caught[0]  # before any session exists: nothing to record
        if args.resume:
            runner = Runner.resume(args.resume, gauges, setup=setup, listener=_printer, by=BY)
        else:
            folder, why = sessions_folder(args.sessions)
            print(f"sessions folder: {folder} ({why})", flush=True)
            runner = Runner.start(setup, gauges, folder, listener=_printer)
        print(f"session file: {runner.path}", flush=True)
        headless = _Headless(runner, inputs, timeout, attempts, deadband=deadband, still=still)
        worker = threading.Thread(target=headless.run, name="station capture", daemon=True)
        worker.start()
        while not headless.done.wait(0.05):
            if caught:
                break
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
        if headless.error is not None:
            # Say in the file why the session stopped (unless the disk itself failed).
            message = headless.error.message
            runner.interrupt(f"station capture stopped: {message}")
            if "--resume" not in message:
                message += f" (resume with `station capture --resume {runner.path}`)"
            raise StationError(message)
        analysis = runner.finish(by=BY)
    finally:
        if gauges is not None:
            gauges.stop()
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    _print_summary(runner, analysis)
    return 0


_PROCEDURE_REPORTS = ("linearity", "relative_accuracy")
"""Procedures whose report is their own (straightness, accuracy per placement), as
``station analyze FILE`` prints it."""


def _print_procedure_report(path: Path) -> None:
    from station.commands import analyze

    parser = argparse.ArgumentParser(prog="station")
    analyze.add_parser(parser.add_subparsers())
    analyze.run(parser.parse_args(["analyze", str(path)]))


def _print_summary(runner: Any, analysis: Any) -> None:
    from station.analysis.report import format_report

    notes = [
        f"Robot {runner.setup.robot}, operator {runner.setup.operator or 'not given'}, "
        f"procedure {runner.setup.procedure.id} {runner.setup.procedure.version}.",
        f"Session file: {runner.path}",
        f"Last line hash (anchors the session file): {runner.last_hash}",
    ]
    if runner.setup.procedure.id in _PROCEDURE_REPORTS:
        _print_procedure_report(runner.path)
    elif analysis is not None:
        print(format_report(analysis, notes=notes), end="")
    else:
        print("no accepted cycles: nothing to analyse")
    print(f"session file: {Path(runner.path)}")
    print(f"last hash: {runner.last_hash}")
