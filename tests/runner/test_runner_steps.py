"""Which step a reading set lands in, what a failed write says, and that the reader never waits
for the disk: the runner against real gauges on real pseudo-terminals (a pty the test answers
itself where the timing must be the test's), real session files and a real full device."""

from __future__ import annotations

import os
import re
import select
import threading
import time
from pathlib import Path

import pytest

from station.errors import StationError
from station.procedures import parse_procedure
from station.run import (
    PortSetup,
    Runner,
    RunnerNotice,
    SessionSetup,
    format_figure,
    open_gauges,
    setup_from_header,
)
from station.session.header import analysis_config
from station.session.model import load_session

from .conftest import DEVICE_MAP, cycles_only_procedure, make_simulator, setup_for

TWO_CYCLES_STEPS = b"""
id = "two-cycles-steps"
title = "Two cycles steps in a row"
version = "1"
report_section = "2.6"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
[limits]
tolerance = 0.002
[[steps]]
id = "first"
kind = "cycles"
title = "First cycles"
min = 1
target = 3
[[steps]]
id = "second"
kind = "cycles"
title = "Second cycles"
min = 1
target = 3
"""


class AnsweringPty:
    """A real pty whose far end the test plays: it sees each poll request and answers when
    the test says so (Mitutoyo 01A frames)."""

    def __init__(self) -> None:
        self.master, self.slave = os.openpty()
        self.url = os.ttyname(self.slave)

    def wait_request(self, timeout: float = 10.0) -> bytes:
        """The next request bytes the gauges sent (fails the test after ``timeout``)."""
        ready, _, _ = select.select([self.master], [], [], timeout)
        assert ready, "the gauges sent no request"
        return os.read(self.master, 1024)

    def answer(self, values: dict[str, float]) -> None:
        """Send one frame per device channel: ``{"1": 0.0012, ...}``."""
        frames = b"".join(
            f"0{channel}A{'-' if value < 0 else '+'}{abs(value):08.4f}\r".encode()
            for channel, value in values.items()
        )
        os.write(self.master, frames)

    def close(self) -> None:
        for fd in (self.master, self.slave):
            os.close(fd)


@pytest.fixture
def answering_pty():
    pty = AnsweringPty()
    yield pty
    pty.close()


def two_steps_setup(folder: Path, url: str) -> SessionSetup:
    path = folder / "two.toml"
    path.write_bytes(TWO_CYCLES_STEPS)
    return SessionSetup(
        procedure=parse_procedure(TWO_CYCLES_STEPS, path),
        robot="KSC-7",
        operator="tester",
        ports=(PortSetup(url, "mitutoyo", DEVICE_MAP),),
        cycles=3,
    )


def captured_in_thread(runner: Runner) -> tuple[threading.Thread, list]:
    outcomes: list = []
    thread = threading.Thread(target=lambda: outcomes.append(runner.capture(30.0)))
    thread.start()
    return thread, outcomes


def test_a_capture_under_way_stays_in_its_step(answering_pty, gauges_for, tmp_path):
    """Finding 6: confirm() during a capture must not move the set into the next step."""
    setup = two_steps_setup(tmp_path, answering_pty.url)
    gauges = gauges_for(setup)
    runner = Runner.start(setup, gauges, tmp_path / "sessions")
    try:
        thread, outcomes = captured_in_thread(runner)
        answering_pty.wait_request()
        answering_pty.answer({"1": 0.0011, "2": 0.0021, "3": 0.0031})
        thread.join(30)
        assert outcomes[0].recorded, outcomes[0].message  # the step has its minimum now

        thread, outcomes = captured_in_thread(runner)
        answering_pty.wait_request()  # the request is out: the capture is under way
        with pytest.raises(StationError, match="capture is under way"):
            runner.confirm()
        answering_pty.answer({"1": 0.0012, "2": 0.0022, "3": 0.0032})
        thread.join(30)
        assert outcomes[0].recorded, outcomes[0].message
        assert outcomes[0].cycle.step_id == "first"
        assert runner.state().current.id == "first"
        # Values in the one number format: one decimal beyond the 0.0001 in gauge step.
        assert outcomes[0].message == "cycle 2 x=+0.00120 y=+0.00220 z=+0.00320"
        runner.confirm()
        assert runner.state().current.id == "second"
    finally:
        runner.close()
    session = load_session(runner.path)
    assert [c.step for c in session.cycles.values()] == ["first", "first"]


def test_values_show_one_decimal_beyond_the_gauge_step():
    """Finding 16, then issue 22: one formatting for every figure, one decimal beyond the
    gauge step (a reading after a zero taken as a mean is no whole step: +0.00123 stays)."""
    assert format_figure(0.00123, 0.0001) == "+0.00123"
    assert format_figure(-0.0012, 0.001) == "-0.0012"
    assert format_figure(-0.000004, 0.0001) == "+0.00000"  # no "-0.00000" beside "+0.00000"
    assert format_figure(0.000012, 0.00001) == "+0.000012"
    assert format_figure(0.25, 0.0005) == "+0.25000"
    assert format_figure(0.00002, 0.0001, signed=False, unit="in") == "0.00002 in"
    assert format_figure(1e-05, None) == "+0.000010"  # an unknown step: six decimals, no 1e-05


def test_header_limits_read_the_same_for_analysis_and_resume():
    """Finding 16: one reading of the header's limits serves the analysis and the resume."""
    setup = setup_for("/dev/ttyUSB0")  # never opened: only the header is read
    header = setup.header_fields()
    header["limits"]["z"] = {"lsl": None, "usl": None, "nominal": 0.0}  # no limits on z
    assert analysis_config(header).limits == dict(setup_from_header(header, setup.procedure).limits)
    assert set(analysis_config(header).limits) == {"x", "y"}


def test_a_failed_write_in_push_mode_keeps_its_cause(tmp_path):
    """Finding 5: the journal's sentence (here: no space left) reaches capture() and finish()
    instead of a bare 'the session is failed'."""
    sim = make_simulator(seed=3)
    sim.start_pty()
    setup = setup_for(sim.url, cycles_only_procedure(tmp_path), cycles=5, trigger="push")
    gauges = open_gauges(setup, backoff=(0.05, 0.2))
    try:
        assert gauges.wait_connected(5.0)
        runner = Runner.start(setup, gauges, tmp_path / "sessions")
        # The disk fills up: the session file's descriptor now writes to /dev/full (ENOSPC).
        full = os.open("/dev/full", os.O_WRONLY)
        os.dup2(full, runner._writer._fd)
        os.close(full)
        sim.push(1)
        deadline = time.monotonic() + 15
        while runner.state().status != "failed":
            assert time.monotonic() < deadline, "the failed write was never noticed"
            time.sleep(0.02)
        with pytest.raises(StationError) as captured:
            runner.capture(1.0)
        failure = captured.value.message
        assert "the session is failed" not in failure
        with pytest.raises(StationError) as finished:
            runner.finish()
        assert finished.value.message == failure
        assert runner.failure == failure
        assert runner.state().failure == failure
    finally:
        gauges.stop()
        sim.stop()


def test_the_reader_never_waits_for_the_recording(tmp_path):
    """Finding 7: while a push set is being recorded (here: a listener that holds it up),
    the reader keeps reading the line; the sets it completes meanwhile are recorded after."""
    sim = make_simulator(seed=4)
    sim.start_pty()
    setup = setup_for(sim.url, cycles_only_procedure(tmp_path), cycles=5, trigger="push")
    readings = []
    gauges = open_gauges(setup, backoff=(0.05, 0.2), on_reading=readings.append)
    release = threading.Event()
    held = threading.Event()
    recorded: list[int] = []

    def listener(notice: RunnerNotice) -> None:
        if notice.event is not None and notice.event["type"] == "reading":
            recorded.append(notice.event["cycle"])
            if notice.event["cycle"] == 1:
                held.set()
                release.wait(30)

    try:
        assert gauges.wait_connected(5.0)
        runner = Runner.start(setup, gauges, tmp_path / "sessions", listener=listener)
        sim.push(1)
        assert held.wait(15), "the first set was not recorded"
        before = len(readings)
        sim.push(3)
        deadline = time.monotonic() + 15
        while len(readings) < before + 9 and time.monotonic() < deadline:
            time.sleep(0.02)
        still_reading = len(readings) - before
        release.set()
        assert still_reading == 9, "the reader stopped while a set was being recorded"
        deadline = time.monotonic() + 15
        while len(recorded) < 4 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert recorded == [1, 2, 3, 4]
        runner.close()
    finally:
        release.set()
        gauges.stop()
        sim.stop()


def test_a_refused_set_on_a_down_port_is_one_short_sentence(gauges_for, tmp_path):
    """Finding 14: no "(...).. Capture again." and no long port sentence per refused set."""
    sim = make_simulator(seed=6)
    # Behind a link: a dropped plain /dev/pts/N goes to the next pty any process opens, which
    # the reconnecting reader would open (and read another test's simulator through).
    sim.start_pty(link=True)
    try:
        setup = setup_for(sim.url, cycles_only_procedure(tmp_path), cycles=5)
        gauges = gauges_for(setup)
        runner = Runner.start(setup, gauges, tmp_path / "sessions")
        gone = threading.Event()
        watch = gauges.subscribe(
            on_status=lambda status: status.state == "disconnected" and gone.set()
        )
        sim.disconnect(60.0)
        assert gone.wait(10.0), "the reader never noticed the dropped line"
        watch.cancel()
        outcome = runner.capture(0.3)
        assert not outcome.recorded
        assert not re.search(r"(?<!\.)\.\.(?!\.)|\)\.\.", outcome.message), outcome.message
        assert "before the trigger" not in outcome.message
        assert outcome.message.endswith("disconnected (reconnecting...). Capture again.")
        # Short, with the port named as a plain /dev/pts/N (the link's folder is as long as the
        # temporary folder's path, which is not the sentence's doing).
        assert len(outcome.message.replace(sim.url, "/dev/pts/N")) <= 120, outcome.message
        assert outcome.port_down  # not a refusal by the gauges: headless keeps waiting
        runner.close()
    finally:
        sim.stop()
