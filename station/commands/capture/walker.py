"""The headless walk: what the engine asks next (its action), one small call per action, on a
worker thread, with the pacing, the waits and the refusals counted as the command line needs;
and the line it prints per stroke streamed."""

from __future__ import annotations

import functools
import sys
import threading
import time
from typing import Any

from station.commands.capture.inputs import Inputs, values_for
from station.errors import StationError
from station.instruments.zeroing import GaugesMoving, NotAtFixture
from station.text import format_spread

BY = "station capture"
"""Who confirmed what the command did, as the session file records it."""


class Headless:
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
        idle_report: float = 30.0,
    ) -> None:
        self.runner = runner
        self.every = every
        self.idle_report = idle_report
        """Seconds without a zero or a cycle after which a capture paced by the devices
        (arrival, push) says what the gauges see, and again every so long: a robot that
        stopped, or indicators that never see the cube, must not look like a working capture."""
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
        self._since_set = time.monotonic()
        self._reported_at = self._since_set

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

    def _idle(self, step: Any, seen: str | None = None) -> None:
        """Nobody pressed DATA (or the robot did not come back) during a wait: say once, until
        the next set, that the command waits (the operator or the robot sets the pace); and
        every ``idle_report`` seconds without a cycle, what the gauges see (``seen``, else
        the gauges' own sentence)."""
        if not self._waiting:
            what = "press DATA" if self.push else "run the robot's playback loop"
            print(
                f"station: waiting for the gauges: {what} (step {step.title!r})",
                file=sys.stderr,
                flush=True,
            )
        self._waiting = True
        now = time.monotonic()
        if now - self._reported_at < self.idle_report:
            return
        self._reported_at = now
        if seen is None:
            seen = getattr(self.runner.gauges, "waiting_sentence", lambda: "")()
        check = (
            "check that DATA is pressed and the gauges' cables"
            if self.push
            else "check that the robot's playback loop runs and that the cube reaches every "
            "indicator at the taught point"
        )
        print(
            f"station: nothing taken for {now - self._since_set:.0f} s (step {step.title!r})"
            + (f": {seen}" if seen else "")
            + f"; {check}.",
            file=sys.stderr,
            flush=True,
        )

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
        given = values_for(self.inputs, state.placement)
        # check_answerable made sure every required field has a value; the engine checks them.
        fields = state.action.fields
        self.runner.submit_input({f.name: given[f.name] for f in fields if f.name in given}, by=BY)

    def _zero(self, state: Any) -> None:
        if self.every is not None:
            # After a capture the robot is brought to where it is zeroed: --every paces that too.
            delay = self._last_capture + self.every - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        seen = self._readings_seen()
        try:
            self.runner.zero(by=BY, timeout=self.timeout)
        except NotAtFixture as away:
            # The robot on its loop is not at rest at the fixture yet: the zero waits for it
            # as the cycles do (the robot sets the pace), said once and then every
            # idle_report seconds with what the gauges see.
            if self._moving_since is None:
                self._moving_since = time.monotonic()
                print(f"station: waiting: {away.message}", file=sys.stderr, flush=True)
            self._waiting = True  # said just now
            self._idle(state.current.step, away.message.removeprefix("Could not zero yet: "))
            return
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
        self._last_capture = self._since_set = self._reported_at = time.monotonic()

    def _stream(self, state: Any) -> None:
        if state.progress is not None and state.progress.complete:
            self.runner.confirm(by=BY)
            return
        self.runner.stream_strokes(
            self.timeout,
            deadband=self.deadband,
            still_seconds=self.still,
            on_stroke=functools.partial(
                print_stroke, resolution=self.runner.setup.resolved_resolution
            ),
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
            self._since_set = self._reported_at = time.monotonic()
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


def print_stroke(outcome: Any, resolution: float | None = None) -> None:
    """``stroke 7 A→B 412 points h=0.00123 v=0.00061 (LS straightness)``, once the stroke's
    points are on disk (``on_stroke`` of the runner's stream); the straightness in the one
    number format at the gauge ``resolution``."""
    from station.analysis.linearity import straightness

    profile = outcome.profile
    position = profile.get("s")
    figures = " ".join(
        f"{channel}={format_spread(straightness(position, values).ls, resolution)}"
        for channel, values in profile.items()
        if channel != "s" and position is not None and len(values) >= 2
    )
    print(f"{outcome.line()} {figures} (LS straightness)", flush=True)
