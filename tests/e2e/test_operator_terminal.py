"""The operator's terminal, for real: ``station`` in tmux, signals sent to its process, the exit
status read back from the dead pane (issue 13: the TUI exited 0 after SIGHUP/SIGTERM)."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.e2e.terminal import Pane

# End to end in a real terminal: slow by nature (the quick lane leaves them out).
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed"),
]


class PtyProcess:
    """``station`` on a real pseudo-terminal of 80×24 (not tmux: its pane can lose the exit
    status), its output drained on a thread so it never blocks on a full terminal; ``{tty}``
    in an argument is the terminal's own name."""

    def __init__(self, args: list[str], cwd: Path, stderr=None) -> None:
        import fcntl
        import struct
        import termios
        import threading

        master, slave = os.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
        self.tty = os.ttyname(slave)
        env = dict(os.environ, TERM="xterm-256color")
        self.process = subprocess.Popen(
            [arg.replace("{tty}", self.tty) for arg in args],
            stdin=slave,
            stdout=slave,
            stderr=slave if stderr is None else stderr,
            cwd=cwd,
            env=env,
            start_new_session=True,
        )
        os.close(slave)
        self._master = master
        self.output = bytearray()
        self._reader = threading.Thread(target=self._drain, daemon=True)
        self._reader.start()

    def _drain(self) -> None:
        while True:
            try:
                chunk = os.read(self._master, 65536)
            except OSError:
                return
            if not chunk:
                return
            self.output.extend(chunk)

    def wait_for(self, text: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text.encode() in self.output:
                return
            time.sleep(0.05)
        pytest.fail(f"{text!r} was not drawn within {timeout} s")

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(10)
        os.close(self._master)


@pytest.mark.parametrize(
    ("signum", "code"), [(signal.SIGHUP, 129), (signal.SIGTERM, 143)], ids=["SIGHUP", "SIGTERM"]
)
def test_the_tui_exits_128_plus_the_signal(tmp_path: Path, signum: int, code: int) -> None:
    station = PtyProcess([sys.executable, "-m", "station", "--sessions", str(tmp_path)], tmp_path)
    try:
        station.wait_for("New session", timeout=30)
        station.process.send_signal(signum)
        assert station.process.wait(20) == code
    finally:
        station.close()


def test_station_tui_opens_the_home_screen_and_ctrl_c_quits(tmp_path: Path) -> None:
    """``station tui`` (what plain ``station`` runs) on a real terminal: the home screen names
    the sessions folder, and Ctrl+C on it quits at once, exit 0."""
    station = PtyProcess(
        [sys.executable, "-m", "station", "tui", "--sessions", str(tmp_path)], tmp_path
    )
    try:
        station.wait_for("New session", timeout=30)
        station.wait_for("Sessions folder", timeout=10)
        os.write(station._master, b"\x03")
        assert station.process.wait(60) == 0
    finally:
        station.close()


def test_the_stations_own_terminal_is_refused_as_a_gauge_line(tmp_path: Path) -> None:
    """Finding 10: a pseudo-terminal number reused by the operator's own window, typed or
    recorded as the gauge port, was opened; the poll request "1\\r" was drawn at the top-left
    and the reader thread ate keys. Now it is refused with a sentence."""
    pane = Pane([sys.executable, "-m", "station", "--sessions", str(tmp_path)], tmp_path)
    try:
        pane.wait_for("New session", timeout=30)
        tty = pane.tty()
        pane.send("n")
        pane.wait_for(re.escape("Tab / Shift+Tab"), timeout=30)
        pane.send("R1")
        for _ in range(10):  # robot → ... → the port field
            pane.send("Tab")
        pane.wait_for("Port", timeout=10)
        pane.send("-l", tty)
        time.sleep(0.5)
        pane.send("F3")
        screen = pane.wait_for("own terminal", timeout=20)
        assert "Connected to" not in screen
    finally:
        pane.close()


def test_station_read_refuses_its_own_terminal(tmp_path: Path) -> None:
    """The same guard at the transport: every command that opens a gauge line refuses the
    terminal it runs in (and so does the reader's reconnect)."""
    errors = tmp_path / "stderr.txt"
    command = [sys.executable, "-m", "station", "read", "--port", "{tty}", "--protocol"]
    with errors.open("wb") as sink:
        read = PtyProcess([*command, "mitutoyo", "--count", "1"], tmp_path, stderr=sink)
        try:
            code = read.process.wait(30)
        finally:
            read.close()
    assert code == 2, errors.read_text()
    assert "is this station's own terminal, not a gauge line" in errors.read_text()
