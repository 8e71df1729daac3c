"""SIGHUP and SIGTERM at the very start or the very end of ``station capture`` (issue 27,
finding 5): an exit code (128 + the signal) and one line, never the raw signal; a finished
session's summary is printed whole."""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest

from station.session.model import load_session

from .conftest import Capture, capture_args


def _mapped(pid: int, library: str) -> bool:
    try:
        return library in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


@pytest.mark.parametrize("signum", [signal.SIGHUP, signal.SIGTERM], ids=["SIGHUP", "SIGTERM"])
def test_a_signal_while_the_command_still_loads_is_an_exit_code(simulators, tmp_path, signum):
    sessions = tmp_path / "sessions"
    capture = Capture(capture_args(simulators(int(signum)).url, sessions, 25))
    # numpy's extension mapped into the child: the command is loading (the engine needs numpy),
    # long before it opens a gauge. Polled: the child's memory map has no event to wait on.
    deadline = time.monotonic() + 60
    while not _mapped(capture.process.pid, "_multiarray_umath"):
        assert capture.process.poll() is None, capture.errors
        assert time.monotonic() < deadline, "the command never loaded numpy"
        time.sleep(0.001)
    capture.process.send_signal(signum)
    assert capture.finish() == 128 + signum
    name = signal.Signals(signum).name
    assert len(capture.errors) == 1 and capture.errors[0].startswith(f"station: {name}: stopped")
    assert not sessions.exists() or not list(sessions.glob("*.jsonl"))


@pytest.mark.parametrize("signum", [signal.SIGHUP, signal.SIGTERM], ids=["SIGHUP", "SIGTERM"])
def test_a_signal_during_the_summary_lets_it_finish(simulators, tmp_path, signum):
    capture = Capture(capture_args(simulators(int(signum)).url, tmp_path, 25))
    assert capture.wait_line(lambda line: line.startswith("Last line hash"), 120), capture.errors
    capture.process.send_signal(signum)
    code = capture.finish()
    # Either the signal came while the command still ran (it says so) or after its last line
    # (it had nothing left to do): never the raw signal.
    assert code in (0, 128 + signum), (code, capture.errors)
    if code:
        name = signal.Signals(signum).name
        assert capture.errors[-1] == f"station: {name} after the session finished; it is complete"
    path = capture.session_path
    final = load_session(path, recover=False)
    assert final.status == "finished"
    assert capture.lines[-1] == f"last hash: {final.last_hash}"
