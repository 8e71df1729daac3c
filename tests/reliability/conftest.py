"""Helpers for the crash-safety tests: a real ``station capture`` subprocess against an
in-process simulator on a pty, its stdout read line by line as it is printed."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model
from station.run import format_figure
from station.session.model import Session

REPO = Path(__file__).resolve().parents[2]
CYCLE_LINE = re.compile(r"^cycle (\d+) (.*)$")


def make_simulator(seed: int, push_rate: float = 0.0) -> Simulator:
    """A Mitutoyo fixture in inches: answers polls as fast as it is asked, and with
    ``push_rate`` also sends that many sets a second by itself (a streaming push device)."""
    model = fixture_model(
        ("x", "y", "z"),
        axis=AxisModel(noise=0.0003),
        gauge=GaugeSpec(resolution=0.0001, unit="in", low=-1.0, high=1.0),
    )
    return Simulator(get_protocol("mitutoyo"), model, seed=seed, push_rate=push_rate)


@pytest.fixture
def simulators() -> Iterator[Callable[..., Simulator]]:
    """``simulators(seed, push_rate=0.0)``: a started simulator on a pty, stopped after the
    test."""
    started: list[Simulator] = []

    def start(seed: int, push_rate: float = 0.0) -> Simulator:
        sim = make_simulator(seed, push_rate)
        sim.start_pty()
        started.append(sim)
        return sim

    yield start
    for sim in started:
        sim.stop()


class Capture:
    """A running ``station capture`` with its output collected by threads as it comes."""

    def __init__(self, args: list[str], preexec_fn: Callable[[], None] | None = None) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1", "STATION_PROCEDURES": ""}
        if preexec_fn is not None:
            # A child under a resource limit (a file-size cap) could not write its coverage
            # data at exit, and coverage's traceback would land among the lines under test.
            env.pop("COVERAGE_PROCESS_CONFIG", None)
        self.process = subprocess.Popen(
            [sys.executable, "-m", "station", "capture", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
            env=env,
            preexec_fn=preexec_fn,
        )
        self.lines: list[str] = []
        self.errors: list[str] = []
        self._changed = threading.Condition()
        self._threads = [
            threading.Thread(target=self._pump, args=(self.process.stdout, self.lines)),
            threading.Thread(target=self._pump, args=(self.process.stderr, self.errors)),
        ]
        for thread in self._threads:
            thread.start()

    def _pump(self, stream, into: list[str]) -> None:
        for line in stream:
            with self._changed:
                into.append(line.rstrip("\n"))
                self._changed.notify_all()
        stream.close()

    def wait_line(
        self, predicate: Callable[[str], bool], timeout: float, *, stderr: bool = False
    ) -> bool:
        """Wait until a stdout (``stderr``: stderr) line satisfies ``predicate`` (False on
        timeout or exit)."""
        deadline = time.monotonic() + timeout
        lines, pump = (self.errors, self._threads[1]) if stderr else (self.lines, self._threads[0])
        with self._changed:
            while not any(predicate(line) for line in lines):
                remaining = deadline - time.monotonic()
                if remaining <= 0 or (self.process.poll() is not None and not pump.is_alive()):
                    return False
                self._changed.wait(min(remaining, 0.05))
            return True

    def finish(self, timeout: float = 30.0) -> int:
        """Wait for the exit and the end of the output; the exit code."""
        code = self.process.wait(timeout)
        for thread in self._threads:
            thread.join(timeout)
        return code

    @property
    def acknowledged(self) -> dict[int, str]:
        """Cycle number -> the values text of every ``cycle`` line printed."""
        return {
            int(match[1]): match[2]
            for line in list(self.lines)
            if (match := CYCLE_LINE.match(line)) is not None
        }

    @property
    def session_path(self) -> Path | None:
        """The session file the command announced, if it got that far."""
        for line in list(self.lines):
            if line.startswith("session file: "):
                return Path(line.removeprefix("session file: "))
        return None


def capture_args(
    url: str, sessions: Path, cycles: int, *, timeout: float = 3, trigger: str = "poll"
) -> list[str]:
    """A new repeatability session on the simulator at ``url``."""
    return [
        "--procedure",
        "repeatability",
        "--port",
        url,
        "--protocol",
        "mitutoyo",
        "--robot",
        "KSC-7",
        "--operator",
        "tester",
        "--sessions",
        str(sessions),
        "--cycles",
        str(cycles),
        "--timeout",
        f"{timeout:g}",
        "--trigger",
        trigger,
        # Polled cycles are paced: a short --every (the simulator does not move).
        *(["--every", "0.01"] if trigger == "poll" else []),
    ]


def values_text(session: Session, cycle: int) -> str:
    """A recorded cycle's values as ``station capture`` prints them: one decimal beyond the
    session's gauge step."""
    readings = session.cycles[cycle].readings
    resolution = session.header["resolution"]
    return " ".join(
        f"{channel}={format_figure(reading.value, resolution)}"
        for channel, reading in readings.items()
    )


def assert_acknowledged_kept(capture: Capture, session: Session) -> None:
    """Every cycle the command printed is in the file with the values it printed."""
    for cycle, text in capture.acknowledged.items():
        assert cycle in session.cycles, f"acknowledged cycle {cycle} is missing from the file"
        assert values_text(session, cycle) == text
