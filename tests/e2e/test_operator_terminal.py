"""The operator's terminal, for real: ``station`` in tmux, signals sent to its process, the exit
status read back from the dead pane (issue 13: the TUI exited 0 after SIGHUP/SIGTERM)."""

from __future__ import annotations

import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def _tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, check=False).stdout


class Pane:
    """One detached tmux session that stays after its command exits (to read the status)."""

    def __init__(self, command: list[str], cwd: Path, size: tuple[int, int] = (80, 24)) -> None:
        self.name = f"station-op-{uuid.uuid4().hex[:8]}"
        env = f"TERM=xterm-256color XDG_CONFIG_HOME={shlex.quote(os.environ['XDG_CONFIG_HOME'])}"
        shell = f"cd {shlex.quote(str(cwd))} && {env} exec {shlex.join(command)}"
        subprocess.run(
            ["tmux", "new-session", "-d", "-s", self.name, "-x", str(size[0]), "-y", str(size[1])]
            + [shell],
            check=True,
        )
        _tmux("set-option", "-t", self.name, "remain-on-exit", "on")
        self.pid = int(_tmux("display-message", "-p", "-t", self.name, "#{pane_pid}").strip())

    def screen(self) -> str:
        return _tmux("capture-pane", "-p", "-t", self.name)

    def wait_for(self, text: str, timeout: float) -> str:
        deadline = time.monotonic() + timeout
        screen = ""
        while time.monotonic() < deadline:
            screen = self.screen()
            if text in screen:
                return screen
            time.sleep(0.1)
        pytest.fail(f"{text!r} did not appear within {timeout} s; the screen shows:\n{screen}")

    def exit_status(self, timeout: float) -> int:
        """The command's exit status once the pane is dead."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            fields = _tmux(
                "display-message", "-p", "-t", self.name, "#{pane_dead} #{pane_dead_status}"
            )
            dead, _, status = fields.strip().partition(" ")
            if dead == "1" and status:
                return int(status)
            time.sleep(0.1)
        pytest.fail(f"station did not exit within {timeout} s:\n{self.screen()}")

    def close(self) -> None:
        subprocess.run(["tmux", "kill-session", "-t", self.name], capture_output=True, check=False)


@pytest.mark.parametrize(
    ("signum", "code"), [(signal.SIGHUP, 129), (signal.SIGTERM, 143)], ids=["SIGHUP", "SIGTERM"]
)
def test_the_tui_exits_128_plus_the_signal(tmp_path: Path, signum: int, code: int) -> None:
    pane = Pane([sys.executable, "-m", "station", "--sessions", str(tmp_path)], tmp_path)
    try:
        pane.wait_for("New session", timeout=30)
        os.kill(pane.pid, signum)
        assert pane.exit_status(timeout=20) == code
    finally:
        pane.close()


def test_the_stations_own_terminal_is_refused_as_a_gauge_line(tmp_path: Path) -> None:
    """Finding 10: a pseudo-terminal number reused by the operator's own window, typed or
    recorded as the gauge port, was opened; the poll request "1\\r" was drawn at the top-left
    and the reader thread ate keys. Now it is refused with a sentence."""
    pane = Pane([sys.executable, "-m", "station", "--sessions", str(tmp_path)], tmp_path)
    try:
        pane.wait_for("New session", timeout=30)
        tty = _tmux("display-message", "-p", "-t", pane.name, "#{pane_tty}").strip()
        _tmux("send-keys", "-t", pane.name, "n")
        pane.wait_for("Tab / Shift+Tab", timeout=30)
        _tmux("send-keys", "-t", pane.name, "R1")
        for _ in range(10):  # robot → ... → the port field
            _tmux("send-keys", "-t", pane.name, "Tab")
        pane.wait_for("Port", timeout=10)
        _tmux("send-keys", "-t", pane.name, "-l", tty)
        time.sleep(0.5)
        _tmux("send-keys", "-t", pane.name, "F3")
        screen = pane.wait_for("own terminal", timeout=20)
        assert "Connected to" not in screen
    finally:
        pane.close()


def test_station_read_refuses_its_own_terminal(tmp_path: Path) -> None:
    """The same guard at the transport: every command that opens a gauge line refuses the
    terminal it runs in (and so does the reader's reconnect)."""
    command = (
        f'{shlex.quote(sys.executable)} -m station read --port "$(tty)" --protocol mitutoyo '
        "--count 1; echo EXIT=$?"
    )
    pane = Pane(["sh", "-c", command], tmp_path)
    try:
        screen = pane.wait_for("EXIT=", timeout=30)
        joined = screen.replace("\n", "").replace(" ", "")  # tmux wraps at 80 mid-word
        assert "EXIT=2" in screen and "isthisstation'sownterminal" in joined, screen
    finally:
        pane.close()
