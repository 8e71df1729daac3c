"""SIGHUP and SIGTERM mid-capture: an ``interrupted`` event, a clean exit (128 + signal),
nothing acknowledged lost, and ``--resume`` continues the numbering."""

from __future__ import annotations

import signal
import threading

import pytest

from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import Capture, assert_acknowledged_kept, capture_args

CYCLES = 60
HELD_AFTER = 30
"""The simulator stops answering after this many readings of z (the frames check's few, the
zero's and a few cycles'): the capture cannot run out of cycles before the signal, however
slow the machine."""


@pytest.mark.parametrize("signum", [signal.SIGHUP, signal.SIGTERM], ids=["SIGHUP", "SIGTERM"])
def test_signal_mid_capture_is_clean_and_resumable(simulators, tmp_path, signum):
    simulator = simulators(int(signum))
    url = simulator.url
    answering = threading.Event()

    def hold(channel: str, k: int) -> None:
        # Runs on the simulator's thread: blocking it is the gauges falling silent.
        if channel == "z" and k + 1 >= HELD_AFTER:
            answering.wait(120)

    simulator.on_sent = hold
    # A long timeout: held gauges must not end the run (3 refused sets) before the signal.
    capture = Capture(capture_args(url, tmp_path, CYCLES, timeout=30))
    try:
        assert capture.wait_line(lambda line: line.startswith("cycle 5 "), 60.0), capture.errors
        capture.process.send_signal(signum)
        assert capture.finish() == 128 + signum
    finally:
        simulator.on_sent = None
        answering.set()
    assert max(capture.acknowledged) < CYCLES  # the signal came mid-capture
    name = signal.Signals(signum).name
    assert f"station: {name}: session interrupted" in capture.errors[-1]
    assert "--resume" in capture.errors[-1]
    assert not any("Traceback" in line for line in capture.errors)

    path = capture.session_path
    session = load_session(path, recover=False)
    assert session.torn is None  # a clean stop, not a crash
    assert session.status == "interrupted"
    assert session.events[-1]["type"] == "interrupted"
    assert session.events[-1]["reason"] == name
    assert_acknowledged_kept(capture, session)
    # Nothing was recorded that was not acknowledged, either: the last line printed is the last
    # cycle on disk.
    assert max(session.cycles) == max(capture.acknowledged)
    assert verify_session(path).ok

    # After a hang-up the adapter may come back as another device: resume on a new port.
    moved = signum == signal.SIGHUP
    port = ["--port", simulators(99).url, "--protocol", "mitutoyo"] if moved else []
    resumed = Capture(["--resume", str(path), "--timeout", "3", "--every", "0.01", *port])
    assert resumed.finish(60) == 0, resumed.errors
    assert min(resumed.acknowledged) == max(session.cycles) + 1
    final = load_session(path, recover=False)
    assert final.status == "finished" and len(final.accepted_cycles) == CYCLES
    resume_event = next(e for e in final.events if e["type"] == "resume")
    assert resume_event["previous_status"] == "interrupted"
    resumed_on = resume_event["instruments"]["ports"][0]["url"]
    assert (resumed_on != url) == moved and final.header["instruments"]["ports"][0]["url"] == url
    assert resumed.lines[-1] == f"last hash: {final.last_hash}"
    assert verify_session(path).ok
