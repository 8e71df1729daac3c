"""``station capture``'s ``run``: the set-up checked, the gauges opened and their frames judged,
the walk on a worker thread while the main thread keeps the signals, then the finish or the
exit code that says how it ended."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
import time
from typing import Any

from station.commands._args import positive_number
from station.commands._signals import keep_stop_signals
from station.commands.capture.inputs import check_answerable, parse_inputs
from station.commands.capture.options import new_setup, pacing, resumed_setup
from station.commands.capture.output import Printer, acknowledge_at_terminal, print_summary
from station.commands.capture.walker import BY, Headless
from station.errors import StationError

CRASH_EXIT = 70
"""The exit code when the command itself fails (EX_SOFTWARE): a bug, not the user's input."""


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

    timeout = positive_number(args.timeout, "--timeout")
    if timeout > 86_400:  # a bound time.monotonic() arithmetic and Event.wait() both take
        raise StationError(f"--timeout must be at most 86400 seconds (a day), not {args.timeout}.")
    attempts = positive_number(args.attempts, "--attempts", int)
    idle_report = positive_number(args.idle_report, "--idle-report")
    inputs = parse_inputs(args.input, args.inputs)
    deadband = positive_number(args.deadband, "--deadband") if args.deadband else None
    still = positive_number(args.still, "--still")
    if args.resume:
        from station.session.model import load_session

        setup = resumed_setup(args)
        done = {
            (event["step"], event.get("placement"))
            for event in load_session(args.resume, recover=False).events
            if event["type"] == "step"
        }
    else:
        setup, done = new_setup(args), set()
        sessions_folder(args.sessions)  # an empty --sessions is refused before any gauge opens
    from station.run import plan_steps

    check_answerable(plan_steps(setup), setup.procedure, inputs, done)
    every, enter = pacing(setup.trigger, args.every)

    # Taken since the process started (station.cli); from here on a signal is recorded and
    # acted on where it is safe, to the end of the process: the summary is never cut short.
    stop_signals = keep_stop_signals()
    stop_signals.hold()
    caught = stop_signals.caught
    gauges = None
    try:
        gauges = open_gauges(setup)
        connected = _connected(gauges, timeout, caught)
        if caught:
            return _stopped_before_start(caught[0])
        if not connected:
            problems = "; ".join(
                f"{r.url}: {r.last_message or r.state}"
                for r in gauges.readers
                if r.state != "connected"
            )
            raise StationError(f"the gauges did not connect within {timeout:g} s ({problems})")
        _check_frames(gauges, setup, timeout, args.resume)
        if caught:
            return _stopped_before_start(caught[0])
        printer = Printer(setup.resolved_resolution)
        if args.resume:
            runner = Runner.resume(args.resume, gauges, setup=setup, listener=printer, by=BY)
        else:
            folder, why = sessions_folder(args.sessions)
            print(f"sessions folder: {folder} ({why})", flush=True)
            runner = Runner.start(setup, gauges, folder, listener=printer)
        print(f"session file: {runner.path}", flush=True)
        headless = Headless(
            runner,
            inputs,
            timeout,
            attempts,
            deadband=deadband,
            still=still,
            every=every,
            enter=enter,
            idle_report=idle_report,
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
    print_summary(runner, analysis)
    if caught:
        name = signal.Signals(caught[0]).name
        print(f"station: {name} after the session finished; it is complete", file=sys.stderr)
        return 128 + caught[0]
    return 0


def _stopped_before_start(signum: int) -> int:
    """One line and the exit code for a signal before any session exists: nothing to record."""
    name = signal.Signals(signum).name
    print(f"station: {name}: stopped before the session started", file=sys.stderr)
    return 128 + signum


def _connected(gauges: Any, timeout: float, caught: list[int]) -> bool:
    """Wait up to ``timeout`` for every gauge to connect; False at once when a signal came."""
    deadline = time.monotonic() + timeout
    while not caught:
        remaining = deadline - time.monotonic()
        if gauges.wait_connected(max(0.0, min(remaining, 0.1))):
            return True
        if remaining <= 0:
            return False
    return False


def _ended(runner: Any, headless: Headless) -> int | None:
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
