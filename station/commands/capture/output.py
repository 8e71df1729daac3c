"""What ``station capture`` prints: a line per cycle, step, zero and alarm once it is on disk,
the questions for the alarms' causes at a terminal, and the summary."""

from __future__ import annotations

import os
import select
import sys
from pathlib import Path
from typing import Any

from station.commands._remedies import CLI_REMEDIES
from station.commands.capture.walker import BY
from station.errors import StationError
from station.text import zero_taken, zero_text


class TypedLines:
    """Lines typed at a terminal, read straight from its file descriptor.

    select() sees only what the kernel still holds: a buffered ``readline`` may already have
    taken in the lines an operator typed ahead, and the next select would then wait for input
    that has long arrived. Reading the descriptor keeps the two in step."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self._pending = b""

    def readline(self, stop: Any = lambda: False) -> str | None:
        """The next line without its newline; None at the end of input or once ``stop()``
        says so (polled every 0.1 s: a signal is only recorded by the command's handler, and
        must still end the questions)."""
        while b"\n" not in self._pending:
            if stop():
                return None
            if not select.select([self.fd], [], [], 0.1)[0]:
                continue
            try:
                chunk = os.read(self.fd, 4096)
            except OSError:  # the terminal hung up
                chunk = b""
            if not chunk:
                last, self._pending = self._pending, b""
                return last.decode(errors="replace") if last else None
            self._pending += chunk
        line, _, self._pending = self._pending.partition(b"\n")
        return line.decode(errors="replace")


class Printer:
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
                event["cycle"],
                values,
                event["step"],
                None,
                resolution=self.resolution,
                part=event.get("part"),
            )
            self._print(record.line())
        elif kind == "note" and event.get("by") == "station":
            # What the station decided for the operator (the order of a step's parts).
            self._print(f"note: {event['text']}")
        elif kind == "step":
            self._print(f"step {event['step']}: done (by {event.get('by', 'operator')})")
        elif kind == "zero":
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
            # What the method did with the finished session (a gauge check filed).
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

    typed = TypedLines(stdin.fileno())

    def ask(prompt: str) -> str | None:
        print(prompt, end="", file=out, flush=True)
        line = typed.readline(stop)
        return None if line is None or stop() else line.strip()

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


def print_summary(runner: Any, analysis: Any) -> None:
    """The session's report as ``station analyze FILE`` prints it (through the analysis-kind
    registry, so a site's own procedure of a kind gets that kind's report)."""
    from station.methods import analyze_session_file

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
        zero = zero_taken([{"channels": runner.recorded_zero}], runner.setup.resolved_resolution)
        if zero:
            notes.append(zero)
        print(report.text(notes, alarms=True), end="")
    print(f"session file: {Path(runner.path)}")
    print(f"last hash: {runner.last_hash}")
